#pragma once
// Tests that render whole setups many times run 10-30x slower under
// AddressSanitizer + UBSan (the tracer is instrumented). There they run the same
// code on smaller pictures, or fewer of them; the accuracy each test states is
// asserted in the Release build, which CI runs first.
namespace glasspiv {

#if defined(GLASSPIV_SANITIZED) && GLASSPIV_SANITIZED
inline constexpr bool kSanitizedBuild = true;
#else
inline constexpr bool kSanitizedBuild = false;
#endif

}  // namespace glasspiv
