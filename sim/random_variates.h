#pragma once
// Random variates that are the same on every platform: std::mt19937_64's bits
// are fixed by the standard, std:: distributions are not (libstdc++, libc++ and
// MSVC draw differently), so the uniform, normal and Poisson draws are made here
// from the engine's bits. The transcendental functions (log, cos, lgamma) come
// from the C library, which may differ in the last bit on other platforms. No I/O.
#include <cstdint>
#include <random>

namespace glasspiv {

class RandomVariates {
 public:
  explicit RandomVariates(std::uint64_t seed) : engine_(seed) {}

  // Uniform on [0, 1): the top 53 bits of one engine draw.
  double uniform01();
  // Uniform on [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform01(); }
  // Standard normal (Box-Muller; the pair's second value is kept for the next call).
  double normal();
  // Poisson of the given mean >= 0: Knuth's product of uniforms below mean 10,
  // Hoermann's transformed rejection (PTRS, 1993) above; exact in both.
  std::uint64_t poisson(double mean);

 private:
  std::mt19937_64 engine_;
  bool has_spare_normal_ = false;
  double spare_normal_ = 0;
};

}  // namespace glasspiv
