#pragma once
// A speckle plate (TargetKind::speckle): black discs of one diameter on a
// jittered grid, the same on every platform for a given spec. See
// docs/targets.md, "Speckle plates", for the rule in full.
//
// The grid: cells of about the pitch p = dot_diameter_mm / rho, where rho
// solves speckle_expected_fill(rho) = fill, so that the expected inked
// fraction (the dots overlap where they meet) is `fill`. One dot per cell, its
// centre uniform over the cell (narrowed at the plate's edge so that every dot
// lies inside the plate): a uniform jitter over the whole cell leaves the dot
// centres no periodic component (the jitter's characteristic function vanishes
// at every reciprocal lattice vector), while one dot per cell keeps the pattern
// free of large voids and clumps. Overlapping dots, more frequent near the
// cells' edges, leave the ink a faint modulation at the grid frequency (0.02
// of full ink on the example; docs/targets.md).
#include <vector>

#include <Eigen/Core>

#include "targets/target_spec.h"

namespace glasspiv {

struct SpeckleDot {
  Eigen::Vector2d centre_mm = Eigen::Vector2d::Zero();  // board frame
  double radius_mm = 0;
};

struct SpeckleGrid {
  int cols = 0, rows = 0;                    // cells across and down, one dot each
  double cell_width_mm = 0, cell_height_mm = 0;  // plate size / cells
  double pitch_mm = 0;                       // dot_diameter_mm / diameter_over_pitch, before rounding to cells
  double diameter_over_pitch = 0;            // rho
  std::size_t dot_count() const { return static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows); }
};

// The expected inked fraction of an unbounded grid of unit cells, each holding
// one disc of diameter rho whose centre is uniform over its cell, independently:
// 1 - the mean over a cell of prod_cells (1 - the probability that the cell's
// disc covers the point), by the midpoint rule on 32 x 32 points (evaluated on
// the 16 x 16 of one quarter: the integrand has the cell's symmetry).
double speckle_expected_fill(double diameter_over_pitch);

// rho solving speckle_expected_fill(rho) = fill, by 48 bisection steps on
// [0, 2] rounded to a multiple of 2^-32 (so that last-bit differences between
// maths libraries do not change it). fill in (0, kMaxSpeckleFill].
double speckle_diameter_over_pitch(double fill);

// The grid of a speckle spec (plate_size_mm, dot_diameter_mm, fill); no
// validation beyond finite positive sizes and a fill in (0, 1) (validate_target
// calls it to count the dots).
SpeckleGrid speckle_grid(const TargetSpec& spec);

// The dots, row by row of cells from the top-left (dot index = row * cols +
// col): std::mt19937_64 seeded with spec.seed, two draws per dot (x, then y),
// each turned into u = (draw >> 11) * 2^-53 in [0, 1); x = lo + u (hi - lo)
// with [lo, hi] the cell's columns [col w, (col + 1) w] narrowed to
// [r, plate width - r], at most hi; y likewise. Validates the spec.
std::vector<SpeckleDot> speckle_dots(const TargetSpec& spec);

// The area of the disc (centre, radius) inside the axis-aligned rectangle
// [x0, x1] x [y0, y1], exact (the integral of the disc's chords, clipped).
double disc_rectangle_area(const Eigen::Vector2d& centre, double radius, double x0, double y0, double x1, double y1);

}  // namespace glasspiv
