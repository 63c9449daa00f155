#pragma once
// Doubles rounded outwards to float: Embree's float boxes and ray limits
// around the tracer's double geometry (the scene index, mesh solids), which
// must never cut off a candidate the double test would accept. Equal to
// std::nextafter(float(x), +-infinity) to the bit, without the library call
// (the ray limit is set once per accepted candidate). No I/O.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace glasspiv {

// The next float above float(x): above x, whichever way x rounded. NaN and
// +infinity stay.
inline float float_up(double x) {
  float f = static_cast<float>(x);
  if (std::isnan(f) || f == std::numeric_limits<float>::infinity()) return f;
  if (f == 0) return std::numeric_limits<float>::denorm_min();  // +0 and -0
  std::uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  bits = f > 0 ? bits + 1 : bits - 1;  // a float's magnitude grows with its bits
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

// The next float below float(x) (rounding is symmetric about zero).
inline float float_down(double x) { return -float_up(-x); }

}  // namespace glasspiv
