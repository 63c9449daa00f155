#include "render/crossing_sink.h"

#include <stdexcept>

#include <gtest/gtest.h>

namespace glasspiv {
namespace {

// Rows committed in a scrambled order, some empty, some larger than a chunk,
// come out in row order with every value and tag where it belongs, the arrays
// copied on one thread or several.
TEST(CrossingSink, RowsComeOutInRowOrderWhateverOrderTheyFinish) {
  for (int threads : {1, 3}) {
  SCOPED_TRACE(threads);
  const int rows = 7;
  const std::size_t sizes[rows] = {3, 0, 70000, 5, 140000, 1, 2};
  const int order[rows] = {3, 0, 2, 1, 6, 4, 5};
  CrossingSink sink(rows);
  RowCrossings scratch;
  for (int row : order) {
    for (std::size_t i = 0; i < sizes[row]; ++i) {
      GridCrossing c;
      c.s_mm = static_cast<float>(row);
      c.t_mm = static_cast<float>(i);
      c.weight = c.ds_dcol = c.ds_drow = c.dt_dcol = c.dt_drow = static_cast<float>(row * 10 + 1);
      c.tag = static_cast<std::uint8_t>(row);
      scratch.push(c);
    }
    sink.commit(row, &scratch);
    EXPECT_EQ(scratch.size(), 0u);
  }
  EXPECT_THROW(sink.commit(2, &scratch), std::logic_error);
  TransportMap map;
  sink.move_into(&map, threads);
  std::size_t k = 0;
  for (int row = 0; row < rows; ++row)
    for (std::size_t i = 0; i < sizes[row]; ++i, ++k) {
      ASSERT_EQ(map.s_mm[k], static_cast<float>(row)) << k;
      ASSERT_EQ(map.t_mm[k], static_cast<float>(i)) << k;
      ASSERT_EQ(map.dt_drow[k], static_cast<float>(row * 10 + 1)) << k;
      ASSERT_EQ(map.tag[k], row) << k;
    }
  EXPECT_EQ(k, map.weight.size());
  EXPECT_EQ(map.ds_dcol.size(), k);
  EXPECT_EQ(map.tag.size(), k);
  EXPECT_EQ(sink.size(), k);
  }
}

TEST(CrossingSink, MissingRowIsRefused) {
  CrossingSink sink(2);
  RowCrossings scratch;
  sink.commit(1, &scratch);
  TransportMap map;
  EXPECT_THROW(sink.move_into(&map), std::logic_error);
}

}  // namespace
}  // namespace glasspiv
