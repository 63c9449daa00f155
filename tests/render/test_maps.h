#pragma once
// Bit-for-bit comparison of transport maps, shared by the render tests.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "render/transport_map.h"

namespace glasspiv {

template <typename T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// Sizes and every per-pixel and per-crossing array equal bit for bit (the
// statistics are the caller's to compare).
inline void expect_same_map_arrays(const TransportMap& a, const TransportMap& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.samples_per_axis, b.samples_per_axis);
  EXPECT_TRUE(same_bits(a.pixel_offsets, b.pixel_offsets));
  EXPECT_TRUE(same_bits(a.s_mm, b.s_mm));
  EXPECT_TRUE(same_bits(a.t_mm, b.t_mm));
  EXPECT_TRUE(same_bits(a.weight, b.weight));
  EXPECT_TRUE(same_bits(a.tag, b.tag));
  EXPECT_TRUE(same_bits(a.ds_dcol, b.ds_dcol));
  EXPECT_TRUE(same_bits(a.ds_drow, b.ds_drow));
  EXPECT_TRUE(same_bits(a.dt_dcol, b.dt_dcol));
  EXPECT_TRUE(same_bits(a.dt_drow, b.dt_drow));
  EXPECT_TRUE(same_bits(a.background_weight, b.background_weight));
  EXPECT_TRUE(same_bits(a.opaque_weight, b.opaque_weight));
}

}  // namespace glasspiv
