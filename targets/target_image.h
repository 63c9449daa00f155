#pragma once
// Pictures of a target: an 8-bit raster (for PNG printing and for synthesising
// photos), its ink coverage as floats (a texture for photometric fitting) and
// the printed page at exact scale, as SVG here and as PDF in
// targets/target_pdf.h. All draw the same black rectangles,
// target_black_rects(), and black discs, target_black_discs().
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "targets/target_spec.h"

namespace glasspiv {

// An axis-aligned black rectangle on the board, mm, board frame.
struct BoardRect {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};
// The black squares, and the black cells of every marker or tag (each row of a
// marker's adjacent black cells merged into one rectangle). They do not overlap.
// ArUco markers are OpenCV's drawMarker bits; single AprilTags libapriltag's
// own (apriltag_to_image: the layout libapriltag decodes), while an
// aprilgrid's tags are OpenCV's DICT_APRILTAG_36h11 (the same codes turned by
// 180 degrees; docs/targets.md).
// Empty for a speckle plate, which is all discs.
std::vector<BoardRect> target_black_rects(const TargetSpec& spec);

// A black disc on the board, mm, board frame: centre (x, y) and radius.
struct BoardDisc {
  double x = 0, y = 0, radius = 0;
};
// The dots of a speckle plate (speckle_dots(); they may overlap); empty for
// every other kind.
std::vector<BoardDisc> target_black_discs(const TargetSpec& spec);

// The white margin pictures get by default, the quiet zone the detectors need
// around the pattern: half a square (chessboard, charuco), or the gap between
// tags but at least two of their bits (aprilgrid), two cells (bits) of the
// marker (aruco_marker, apriltag); for a speckle plate, which no detector
// reads, max(5 mm, 2 dot diameters) of white to cut and clamp it by.
double default_margin_mm(const TargetSpec& spec);

struct TargetRender {
  cv::Mat image;  // CV_8UC1, 255 = white paper, 0 = black ink
  double px_per_mm = 0;
  double margin_mm = 0;
  // Board point (mm) -> pixel of `image` in glasspiv's convention ((0, 0) = the
  // centre of the top-left pixel); the board's origin is at the margin's inner
  // edge: u = (x + margin) * px_per_mm - 0.5.
  Eigen::Vector2d pixel_from_board(const Eigen::Vector2d& board_mm) const;
  Eigen::Vector2d board_from_pixel(const Eigen::Vector2d& pixel) const;
};

// Renders the board at `px_per_mm` with a white margin. Each pixel is the exact
// area average of the ink over its square (box filter), so the picture has no
// half-pixel bias at any scale. Throws InputError (field "resolution") for a
// non-positive resolution or a picture over 500 megapixels.
// The discs of a speckle plate are drawn by target_ink_coverage(): each pixel
// within 1e-4 of full ink of its exact area average.
TargetRender render_target(const TargetSpec& spec, double px_per_mm, double margin_mm);

// The ink of render_target()'s picture as floats: CV_32FC1, 1 = black ink,
// 0 = paper, each pixel the fraction of its square inked; the same size and
// geometry (TargetRender::pixel_from_board with these px_per_mm and margin_mm)
// and the same limits (InputError "resolution" over 500 megapixels).
// Rectangles are exact (to float rounding). Discs (which may overlap) are
// exact where a pixel meets one disc, or several that do not overlap each other
// there; where overlapping discs both cross a pixel's boundary, the pixel is
// split into quarters, down to 2^-10 of a pixel (or of a disc's radius where
// that is smaller than a pixel), and an unresolved piece counts
// the middle of its bounds [largest disc part, min(sum of disc parts, area)].
// `max_error`, if given, receives the largest bound on a pixel's error (half
// the bounds' widths, summed over the pixel's unresolved pieces), in fractions
// of full ink; it is under 1e-4 for every plate tested. The cost is linear in
// the pixels and the dots (each pixel looks at the dots of the grid cells it
// meets).
cv::Mat target_ink_coverage(const TargetSpec& spec, double px_per_mm, double margin_mm, double* max_error = nullptr);

// The printed page that target_svg() and write_target_pdf() draw: page mm,
// origin at the page's top-left corner, y down. The pattern with its white
// margin, below it a caption (kind, squares, sizes, dictionary, first id,
// layout) and a 100 mm scale bar with 10 mm ticks to check the print.
struct TargetPageText {
  double x_mm = 0, baseline_mm = 0;
  std::string text;
};
struct TargetPage {
  Eigen::Vector2d size_mm = Eigen::Vector2d::Zero();  // target_svg_size_mm()
  std::string title;                                   // describe_target()
  std::vector<BoardRect> pattern;                      // target_black_rects() moved by the margin
  std::vector<BoardDisc> discs;                        // target_black_discs() moved by the margin
  std::vector<TargetPageText> caption;                 // sans-serif, font_size_mm high
  double font_size_mm = 0;
  std::vector<BoardRect> scale_bar;  // the 100 mm bar first, then its ticks
};
// margin_mm < 0: default_margin_mm(). Throws InputError for an invalid spec.
TargetPage target_page(const TargetSpec& spec, double margin_mm = -1);

// An SVG at exact scale of target_page(): width and height in mm, viewBox in
// mm, the rectangles as <rect>s, the discs as <circle>s (centres and radii to
// 1e-6 mm), the caption as <text>.
std::string target_svg(const TargetSpec& spec, double margin_mm = -1);

// The page size (width, height) in mm of target_page(), the SVG and the PDF.
Eigen::Vector2d target_svg_size_mm(const TargetSpec& spec, double margin_mm = -1);

// Writers (atomic): the SVG, and a PNG rendered at `dpi` with the default margin.
void write_target_svg(const std::string& path, const TargetSpec& spec);
void write_target_png(const std::string& path, const TargetSpec& spec, double dpi);

}  // namespace glasspiv
