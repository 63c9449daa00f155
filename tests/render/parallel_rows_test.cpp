#include "render/parallel_rows.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace glasspiv {
namespace {

// Every row runs exactly once for any number of rows and threads; progress is
// reported from the calling thread, never decreasing, and last with every row
// done; the threads used are at most the rows.
TEST(ParallelRows, EveryRowOnceAndProgressEndsWithAllRowsDone) {
  const std::thread::id caller = std::this_thread::get_id();
  for (int rows : {0, 1, 2, 7, 300})
    for (int threads : {1, 2, 3, 16}) {
      SCOPED_TRACE(testing::Message() << rows << " rows, " << threads << " threads");
      std::vector<std::atomic<int>> calls(static_cast<std::size_t>(rows));
      std::vector<int> reported;
      bool on_caller = true;
      const int used = parallel_rows(
          rows, threads,
          [&](int row) {
            calls[static_cast<std::size_t>(row)].fetch_add(1);
            if (row % 50 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // some rows slower
          },
          [&](int done, int total) {
            on_caller = on_caller && std::this_thread::get_id() == caller;
            EXPECT_EQ(total, rows);
            reported.push_back(done);
          });
      EXPECT_EQ(used, std::max(1, std::min(threads, rows)));
      for (int row = 0; row < rows; ++row) EXPECT_EQ(calls[static_cast<std::size_t>(row)].load(), 1) << "row " << row;
      EXPECT_TRUE(on_caller);
      ASSERT_FALSE(reported.empty());
      EXPECT_EQ(reported.back(), rows);
      for (std::size_t i = 1; i < reported.size(); ++i) EXPECT_LT(reported[i - 1], reported[i]);
    }
}

// Without a progress callback the rows run all the same.
TEST(ParallelRows, RunsWithoutProgress) {
  std::atomic<long> sum{0};
  EXPECT_EQ(parallel_rows(1000, 2, [&](int row) { sum.fetch_add(row); }), 2);
  EXPECT_EQ(sum.load(), 999L * 1000 / 2);
}

// A row that throws: the exception reaches the caller (not std::terminate from
// a worker thread), after every worker has stopped, whatever the thread count
// and whether progress is reported; several rows throwing at once give one.
TEST(ParallelRows, ExceptionFromARowReachesTheCaller) {
  for (int threads : {1, 2, 8})
    for (bool with_progress : {false, true}) {
      SCOPED_TRACE(testing::Message() << threads << " threads, progress " << with_progress);
      std::atomic<int> running{0};
      std::function<void(int, int)> progress;
      if (with_progress) progress = [](int, int) {};
      try {
        parallel_rows(
            200, threads,
            [&](int row) {
              running.fetch_add(1);
              std::this_thread::sleep_for(std::chrono::microseconds(200));
              running.fetch_sub(1);
              if (row >= 20) throw std::runtime_error("row " + std::to_string(row));
            },
            progress);
        ADD_FAILURE() << "no exception";
      } catch (const std::runtime_error& e) {
        EXPECT_EQ(std::string(e.what()).rfind("row ", 0), 0u);
      }
      EXPECT_EQ(running.load(), 0);
    }
}

}  // namespace
}  // namespace glasspiv
