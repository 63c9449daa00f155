#pragma once
// A terminal progress bar for anything that can take over a second. It draws on
// stderr only when stderr is a terminal, so logs and pipes stay clean.
#include <chrono>
#include <cstddef>
#include <string>

namespace glasspiv {

class ProgressBar {
 public:
  // rate_unit (e.g. "frames"): also draw the rate, "12.3 frames/s".
  ProgressBar(std::string label, std::size_t total, std::string rate_unit = "");
  ~ProgressBar();
  void advance(std::size_t steps = 1);
  // Absolute progress, for work that reports how much is done so far.
  void set_done(std::size_t done);
  void finish();

 private:
  void draw(bool force);
  std::string label_, rate_unit_;
  std::size_t total_, done_ = 0;
  bool enabled_, finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace glasspiv
