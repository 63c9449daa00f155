// piv/row_threads.h: every row once, and an exception thrown by a row reaches
// the caller after the workers stop (not std::terminate from a worker thread).
#include "piv/row_threads.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

namespace glasspiv {
namespace {

TEST(RowThreads, EveryRowOnce) {
  std::vector<std::atomic<int>> calls(100);
  EXPECT_EQ(for_each_row(100, 3, [&](int row, int) { calls[static_cast<std::size_t>(row)].fetch_add(1); }), 3);
  for (const auto& c : calls) EXPECT_EQ(c.load(), 1);
}

TEST(RowThreads, ExceptionFromARowReachesTheCaller) {
  for (int threads : {1, 2, 8}) {
    std::atomic<int> polls{0};
    EXPECT_THROW(for_each_row(
                     500, threads,
                     [](int row, int) {
                       if (row >= 10) throw std::runtime_error("row " + std::to_string(row));
                     },
                     [&] { polls.fetch_add(1); }),
                 std::runtime_error);
    EXPECT_GE(polls.load(), 1);
  }
}

}  // namespace
}  // namespace glasspiv
