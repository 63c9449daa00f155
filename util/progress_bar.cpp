#include "util/progress_bar.h"

#include <cstdio>

#include <fmt/format.h>
#include <unistd.h>

namespace glasspiv {

ProgressBar::ProgressBar(std::string label, std::size_t total, std::string rate_unit)
    : label_(std::move(label)),
      rate_unit_(std::move(rate_unit)),
      total_(total),
      enabled_(::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::advance(std::size_t steps) {
  done_ += steps;
  draw(false);
}

void ProgressBar::set_done(std::size_t done) {
  done_ = done;
  draw(false);
}

void ProgressBar::finish() {
  if (finished_) return;
  finished_ = true;
  if (!enabled_) return;
  draw(true);
  std::fputc('\n', stderr);
}

void ProgressBar::draw(bool force) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (!force && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  const double fraction = total_ == 0 ? 1.0 : static_cast<double>(done_) / static_cast<double>(total_);
  const int width = 30;
  const int filled = static_cast<int>(fraction * width + 0.5);
  const double elapsed_s = std::chrono::duration<double>(now - start_).count();
  std::fprintf(stderr, "\r%s [%s%s] %5.1f%% %6.1fs", label_.c_str(), std::string(filled, '#').c_str(),
               std::string(width - filled, '.').c_str(), 100.0 * fraction, elapsed_s);
  if (!rate_unit_.empty() && elapsed_s > 0)
    std::fprintf(stderr, " %.1f %s/s", static_cast<double>(done_) / elapsed_s, rate_unit_.c_str());
  std::fflush(stderr);
}

}  // namespace glasspiv
