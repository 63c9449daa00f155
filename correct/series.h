#pragma once
// A series of frames corrected one after the other, with reading, correcting
// and writing overlapped (the next frame is read and the last one written
// while the current one is corrected), and the split of a series into shards
// for a scheduler (Slurm job arrays, GNU parallel: docs/cluster.md). The
// library does no I/O itself: the caller's functions do.
#include <cstddef>
#include <functional>
#include <vector>

namespace glasspiv {

// The frames of shard k of n (0 <= k < n): every n-th frame from k, so the n
// shards cover every frame exactly once. Throws std::invalid_argument for
// n < 1 or k outside [0, n).
std::vector<std::size_t> shard_frames(std::size_t frame_count, int k, int n);

struct SeriesStats {
  std::size_t corrected = 0, skipped = 0;
  double seconds = 0;
};

// For each frame i in `frames`: skip(i) true -> skipped (its output exists);
// otherwise Frame f = read(i); correct(i, f); write(i, f). read runs one frame
// ahead and write one frame behind on their own threads, correct on the
// calling thread (it may use all cores itself). progress(done, total) after
// each frame. An exception from any function stops the series after the frames
// in flight and is rethrown; a frame is either written completely by write or
// not at all (write must be atomic).
template <typename Frame>
SeriesStats run_series(const std::vector<std::size_t>& frames, const std::function<bool(std::size_t)>& skip,
                       const std::function<Frame(std::size_t)>& read,
                       const std::function<void(std::size_t, Frame&)>& correct,
                       const std::function<void(std::size_t, const Frame&)>& write,
                       const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace glasspiv

#include "correct/series_impl.h"
