#pragma once
// run_series (correct/series.h), a template: included from there only.
#include <future>
#include <optional>

#include "util/stopwatch.h"

namespace glasspiv {

template <typename Frame>
SeriesStats run_series(const std::vector<std::size_t>& frames, const std::function<bool(std::size_t)>& skip,
                       const std::function<Frame(std::size_t)>& read,
                       const std::function<void(std::size_t, Frame&)>& correct,
                       const std::function<void(std::size_t, const Frame&)>& write,
                       const std::function<void(std::size_t, std::size_t)>& progress) {
  const Stopwatch clock;
  SeriesStats stats;
  std::vector<std::size_t> todo;
  for (std::size_t i : frames) {
    if (skip && skip(i)) ++stats.skipped;
    else todo.push_back(i);
  }
  std::future<Frame> next;
  if (!todo.empty()) next = std::async(std::launch::async, read, todo[0]);
  std::future<void> writing;
  std::optional<Frame> in_write;  // kept alive until its write is done
  for (std::size_t k = 0; k < todo.size(); ++k) {
    Frame frame = next.get();
    if (k + 1 < todo.size()) next = std::async(std::launch::async, read, todo[k + 1]);
    correct(todo[k], frame);  // on a throw, the futures' destructors wait for the frames in flight
    if (writing.valid()) writing.get();  // rethrows a failed write
    in_write = std::move(frame);
    writing = std::async(std::launch::async, [&write, &in_write, i = todo[k]]() { write(i, *in_write); });
    ++stats.corrected;
    if (progress) progress(stats.skipped + k + 1, frames.size());
  }
  if (writing.valid()) writing.get();
  if (progress) progress(frames.size(), frames.size());
  stats.seconds = clock.seconds();
  return stats;
}

}  // namespace glasspiv
