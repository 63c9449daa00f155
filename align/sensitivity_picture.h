#pragma once
// A sensitivity map (align/sensitivity.h) as a picture at the camera's size:
// one block per grid sample, viridis from 0 up to `top` (brighter = more),
// grey where the sample has no direct view of the sheet. No I/O.
#include <vector>

#include <opencv2/core.hpp>

#include "align/sensitivity.h"

namespace glasspiv {

// `values`: one per grid sample (m.displacement_mm, m.displacement_px or a
// parameter's); CV_8UC3 (BGR).
cv::Mat sensitivity_heat_map(const SensitivityMap& m, const std::vector<float>& values, double top);

}  // namespace glasspiv
