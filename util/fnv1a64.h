#pragma once
// FNV-1a 64 over a canonical little-endian byte stream: the hasher behind the
// 64-bit fingerprints of cached files (render/transport_map_file.h,
// correct/correction_operator_file.h), which key a cache on every input a
// result depends on. Integers enter as little-endian bytes whatever the host,
// doubles by their bit pattern, so a change in the last bit of any input
// changes the value. Not a checksum for large payloads (one byte at a time,
// about 0.85 GB/s): see Xxh64 in util/binary_file.h.
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace glasspiv {

class Fnv1a64 {
 public:
  void bytes(const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
      h_ ^= p[i];
      h_ *= 1099511628211ull;
    }
  }
  void u64(std::uint64_t v) {
    unsigned char b[8];
    for (int i = 0; i < 8; ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
    bytes(b, 8);
  }
  void u32(std::uint32_t v) {
    unsigned char b[4];
    for (int i = 0; i < 4; ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
    bytes(b, 4);
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void boolean(bool v) { u32(v ? 1u : 0u); }
  // By bit pattern; -0.0 == 0.0 as inputs, so it hashes as 0.0.
  void f64(double v) {
    static_assert(sizeof(double) == 8, "binary64 doubles required");
    if (v == 0) v = 0;
    std::uint64_t bits;
    std::memcpy(&bits, &v, 8);
    u64(bits);
  }
  // Three doubles v[0], v[1], v[2] (an Eigen::Vector3d, a std::array<double, 3>).
  template <typename Vector3>
  void vec3(const Vector3& v) {
    for (int i = 0; i < 3; ++i) f64(v[i]);
  }
  // Nine doubles m(r, c), row by row (an Eigen::Matrix3d).
  template <typename Matrix3>
  void mat3(const Matrix3& m) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) f64(m(r, c));
  }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 14695981039346656037ull;
};

}  // namespace glasspiv
