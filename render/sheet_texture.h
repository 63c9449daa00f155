#pragma once
// A picture laid on the light sheet (particles, a checkerboard, a grid) and its
// footprint-filtered lookup: the mean of the picture over the parallelogram a
// camera pixel covers on the sheet, so minified regions (the squeezed views
// near a sphere's rim) average instead of aliasing and magnified ones
// interpolate. No I/O.
//
// Placement: centred on the sheet origin (or on centre_st_mm), mm_per_texel per texel; the column
// grows with s and the row with -t (t is "up"), so an image file looks upright
// when the sheet's t axis is up. Outside the picture the sheet is dark (0).
//
// Filter: the footprint's two axes J e_col, J e_row (texels) are covered by a
// stratified grid of up to kMaxTapsPerAxis bilinear taps each; where a
// footprint is longer than that, the taps read a box-filtered mip level
// 2^L coarser, so the cost per lookup is bounded (at most 64 taps).
#include <Eigen/Core>
#include <vector>

namespace glasspiv {

class SheetTexture {
 public:
  static constexpr int kMaxTapsPerAxis = 8;

  // values: row-major rows x cols (copied). Throws std::invalid_argument for an
  // empty picture or mm_per_texel <= 0.
  // centre_st_mm: where on the sheet the picture's centre lies (default the
  // sheet origin).
  SheetTexture(const float* values, int rows, int cols, double mm_per_texel,
               const Eigen::Vector2d& centre_st_mm = Eigen::Vector2d::Zero());

  int rows() const { return rows_[0]; }
  int cols() const { return cols_[0]; }
  double mm_per_texel() const { return mm_per_texel_; }
  int levels() const { return static_cast<int>(levels_.size()); }

  // Bilinear value at sheet coordinates (mm), 0 outside: a point sample.
  float at(double s_mm, double t_mm) const;
  // Mean over the footprint {(s, t) + J (u, v) : |u|, |v| <= 1/2} with J =
  // d(s, t)/d(pixel) in mm per pixel (rows s, t; columns col, row).
  float average(double s_mm, double t_mm, const Eigen::Matrix2d& dst_dpixel) const;

 private:
  double bilinear(int level, double x, double y) const;  // level's texel coordinates
  std::vector<std::vector<float>> levels_;
  std::vector<int> rows_, cols_;
  double mm_per_texel_;
  Eigen::Vector2d centre_st_mm_;
};

}  // namespace glasspiv
