#pragma once
// The Pareto plot of a chain sweep (sim/chain_sweep.h): PIV error against
// correction time per frame, both log scale, each setting a numbered point
// with its label in the legend on the right, the front (red) a line, the
// default ringed, the glass-free PIV's error a dashed line. Drawing only; the
// caller writes the picture.
#include <cstddef>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "sim/chain_sweep.h"

namespace glasspiv {

// 1280 x 720 BGR; no_glass_px <= 0 or NaN: no reference line.
cv::Mat draw_pareto_plot(const std::vector<ChainRow>& rows, const std::vector<std::size_t>& front, double no_glass_px,
                         const std::string& title);

}  // namespace glasspiv
