#include "align/plate_picture.h"

#include "targets/target_image.h"

namespace glasspiv {

PlateTexture plate_texture(const TargetSpec& spec, double mm_per_texel) {
  const cv::Mat ink = target_ink_coverage(spec, 1.0 / mm_per_texel, 0.0);
  const Eigen::Vector2d size = board_size_mm(spec);
  cv::Mat paper = 1.0 - ink;  // exact area coverage, not 8-bit levels
  if (!paper.isContinuous()) paper = paper.clone();
  // The raster spans [0, cols / px] x [0, rows / px] mm of the board; its
  // centre lies (cols / px - w) / 2 right of and (rows / px - h) / 2 below the
  // pattern's centre, i.e. at (+dx, -dy) on the sheet.
  const double dx = 0.5 * (paper.cols * mm_per_texel - size.x());
  const double dy = 0.5 * (paper.rows * mm_per_texel - size.y());
  PlateTexture plate;
  plate.texture = std::make_unique<SheetTexture>(paper.ptr<float>(0), paper.rows, paper.cols, mm_per_texel,
                                                 Eigen::Vector2d(dx, -dy));
  plate.width_mm = size.x();
  plate.height_mm = size.y();
  return plate;
}

}  // namespace glasspiv
