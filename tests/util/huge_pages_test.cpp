#include "util/huge_pages.h"

#include <cstdint>
#include <numeric>
#include <vector>

#include <gtest/gtest.h>

namespace glasspiv {
namespace {

// The advice may change how memory is mapped, never what it holds: a range
// whose ends are not page-aligned, in a buffer already written, reads back
// unchanged, as do the bytes just outside it (MADV_DONTNEED, say, would zero them).
TEST(HugePages, AdviceKeepsEveryByte) {
  std::vector<std::uint32_t> buffer(6u << 20);  // 24 MiB
  std::iota(buffer.begin(), buffer.end(), 0u);
  advise_huge_pages(buffer.data() + 1001, (buffer.size() - 3000) * sizeof(std::uint32_t) - 3);
  for (std::size_t i = 0; i < buffer.size(); ++i) ASSERT_EQ(buffer[i], static_cast<std::uint32_t>(i)) << i;
}

TEST(HugePages, SmallEmptyAndNullRangesAreNoOps) {
  std::vector<float> small(100, 1.5f);
  advise_huge_pages(small.data(), small.size() * sizeof(float));
  advise_huge_pages(nullptr, 1u << 30);
  advise_huge_pages(small.data(), 0);
  for (float v : small) EXPECT_EQ(v, 1.5f);
}

// reserve_huge is reserve: contents kept, capacity at least what was asked,
// and the storage fills like any other.
TEST(HugePages, ReserveHugeKeepsContentsAndReserves) {
  std::vector<double> v = {1, 2, 3};
  reserve_huge(&v, 3u << 20);
  ASSERT_EQ(v.size(), 3u);
  EXPECT_GE(v.capacity(), 3u << 20);
  EXPECT_EQ(v[0], 1);
  EXPECT_EQ(v[2], 3);
  const double* storage = v.data();
  for (std::size_t i = 3; i < (3u << 20); ++i) v.push_back(static_cast<double>(i + 1));
  EXPECT_EQ(v.data(), storage);  // no reallocation within the reservation
  for (std::size_t i = 0; i < v.size(); i += 4099) ASSERT_EQ(v[i], static_cast<double>(i + 1));
  std::vector<double> empty;
  reserve_huge(&empty, 0);
  EXPECT_TRUE(empty.empty());
}

}  // namespace
}  // namespace glasspiv
