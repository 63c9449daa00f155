#include "piv/interrogation_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace glasspiv {

int step_from_overlap(int window_px, double overlap) {
  if (window_px < 1) throw std::invalid_argument("window_px must be at least 1");
  if (!(overlap >= 0 && overlap < 1)) throw std::invalid_argument("overlap must lie in [0, 1)");
  return std::max(1, static_cast<int>(std::lround(window_px * (1 - overlap))));
}

InterrogationGrid interrogation_grid(int width_px, int height_px, int window_px, int step_px) {
  if (window_px < 1 || step_px < 1) throw std::invalid_argument("window_px and step_px must be at least 1");
  if (window_px > width_px || window_px > height_px)
    throw std::invalid_argument("a " + std::to_string(window_px) + " px window does not fit in " +
                                std::to_string(width_px) + " x " + std::to_string(height_px) + " px");
  InterrogationGrid g;
  g.window_px = window_px;
  g.step_px = step_px;
  g.cols = (width_px - window_px) / step_px + 1;
  g.rows = (height_px - window_px) / step_px + 1;
  g.left0_px = (width_px - window_px - (g.cols - 1) * step_px) / 2;
  g.top0_px = (height_px - window_px - (g.rows - 1) * step_px) / 2;
  return g;
}

}  // namespace glasspiv
