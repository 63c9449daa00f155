#pragma once
// A PIV field scored against a simulated experiment's truth
// (sim/piv_experiment.h): the true displacement at each vector's window
// centre, on a camera's glass-removed grid or on the rectified sheet grid, and
// the RMS and largest |measured - true| over the vectors that are scored. The
// demo, the chain bench and the tests score the same way. No I/O.
#include <cmath>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "calib/lens_maps.h"
#include "piv/piv_evaluate.h"
#include "sim/piv_experiment.h"

namespace glasspiv {

// |measured - true| in px over the scored vectors; NaN when none.
struct PivScore {
  double rms_px = NAN, max_px = NAN;
  int vectors = 0;
};

// The camera truth at each vector of f, whose grid the truth was evaluated on
// (PivExperimentSettings::truth_grids = the final PIV grid's window centres);
// NaN where the truth has none or where usable (CV_8U per pixel, optional) is 0
// at the window centre.
std::vector<Eigen::Vector2d> camera_truth_on_vectors(const PivField& f, const CameraTruth& truth,
                                                     const cv::Mat& usable = cv::Mat());

// The sheet truth at each vector of f on the sheet grid in grid px (column
// along +s, row along -t: u = ds / pitch, v = -dt / pitch), bilinear between
// the truth's cells; NaN off its grid, next to a cell without truth (inside a
// solid) or where usable (per grid cell, optional) is 0 at the window centre.
std::vector<Eigen::Vector2d> sheet_truth_on_vectors(const PivField& f, const SheetGrid& grid, const SheetTruth& truth,
                                                    const cv::Mat& usable = cv::Mat());

// Scores the vectors of f that are not invalid and have a truth (truth_px per
// vector, NaN: none; with only, where it is set too); their errors (NaN
// elsewhere) into *errors for a plot (one cell per vector), the vectors scored
// into *scored and their mean measured displacement into *mean_px (each
// optional).
PivScore score_vectors(const PivField& f, const std::vector<Eigen::Vector2d>& truth_px, GridValues* errors = nullptr,
                       const std::vector<bool>* only = nullptr, std::vector<bool>* scored = nullptr,
                       Eigen::Vector2d* mean_px = nullptr);

// errors->grid as one flat cell per vector of the PIV grid g (calib/lens_maps.h
// cells), then summarised; errors->vector_px must hold one entry per vector.
void use_vector_cells(const InterrogationGrid& g, GridValues* errors);

}  // namespace glasspiv
