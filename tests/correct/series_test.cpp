#include "correct/series.h"

#include <gtest/gtest.h>

#include <mutex>
#include <set>
#include <stdexcept>
#include <string>

namespace glasspiv {
namespace {

TEST(Series, ShardsCoverEveryFrameExactlyOnce) {
  for (std::size_t frames : {0u, 1u, 7u, 200u, 1001u})
    for (int n : {1, 2, 3, 16, 250}) {
      std::multiset<std::size_t> seen;
      for (int k = 0; k < n; ++k)
        for (std::size_t i : shard_frames(frames, k, n)) {
          EXPECT_EQ(i % n, static_cast<std::size_t>(k));
          seen.insert(i);
        }
      ASSERT_EQ(seen.size(), frames);
      for (std::size_t i = 0; i < frames; ++i) EXPECT_EQ(seen.count(i), 1u);
    }
  EXPECT_THROW(shard_frames(10, 2, 2), std::invalid_argument);
  EXPECT_THROW(shard_frames(10, -1, 2), std::invalid_argument);
  EXPECT_THROW(shard_frames(10, 0, 0), std::invalid_argument);
}

// Every frame not skipped is read, corrected and written once, in order of
// correction, with its own data; skipped frames are never read.
TEST(Series, EachFrameReadCorrectedWrittenOnceAndSkipsHonoured) {
  std::vector<std::size_t> frames;
  for (std::size_t i = 0; i < 50; ++i) frames.push_back(i);
  std::mutex m;
  std::multiset<std::size_t> read, written;
  std::vector<std::size_t> corrected;
  const SeriesStats st = run_series<std::string>(
      frames, [](std::size_t i) { return i % 5 == 0; },
      [&](std::size_t i) {
        std::lock_guard<std::mutex> l(m);
        read.insert(i);
        return std::to_string(i);
      },
      [&](std::size_t i, std::string& f) {
        corrected.push_back(i);
        f += "!";
      },
      [&](std::size_t i, const std::string& f) {
        std::lock_guard<std::mutex> l(m);
        EXPECT_EQ(f, std::to_string(i) + "!");
        written.insert(i);
      });
  EXPECT_EQ(st.skipped, 10u);
  EXPECT_EQ(st.corrected, 40u);
  EXPECT_EQ(read, written);
  EXPECT_EQ(read.size(), 40u);
  for (std::size_t i : read) EXPECT_NE(i % 5, 0u);
  for (std::size_t k = 1; k < corrected.size(); ++k) EXPECT_LT(corrected[k - 1], corrected[k]);
}

// A failing write stops the series with its error; later frames are not written.
TEST(Series, AFailedWriteStopsTheSeries) {
  std::vector<std::size_t> frames = {0, 1, 2, 3, 4, 5};
  std::mutex m;
  std::set<std::size_t> written;
  EXPECT_THROW(run_series<int>(
                   frames, {}, [](std::size_t i) { return static_cast<int>(i); }, [](std::size_t, int&) {},
                   [&](std::size_t i, const int&) {
                     if (i == 2) throw std::runtime_error("disk full");
                     std::lock_guard<std::mutex> l(m);
                     written.insert(i);
                   }),
               std::runtime_error);
  EXPECT_EQ(written.count(4), 0u);
  EXPECT_EQ(written.count(5), 0u);
}

}  // namespace
}  // namespace glasspiv
