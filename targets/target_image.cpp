#include "targets/target_image.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include <apriltag/apriltag.h>
#include <fmt/format.h>
#include <opencv2/aruco/dictionary.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "targets/speckle_plate.h"
#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

constexpr double kScaleBarMm = 100.0;
constexpr double kMaxMegapixels = 500.0;

cv::Ptr<cv::aruco::Dictionary> marker_dictionary(const TargetSpec& spec) {
  const std::string name = spec.kind == TargetKind::aprilgrid ? "DICT_APRILTAG_36h11" : spec.dictionary;
  return cv::aruco::getPredefinedDictionary(opencv_dictionary_id(name));
}

// Tag `id` of a libapriltag family drawn as libapriltag's apriltag_to_image()
// draws it (that function's image cannot be freed through the library's
// exported symbols): black, a one-bit white ring `width_at_border` (+ 2 for
// normal borders) wide, and the code's set bits white at (bit_x, bit_y) from
// the detected square's corner, most significant bit first. Cropped to the
// printed pattern (apriltag_family_info): 0 = black, 255 = white.
cv::Mat apriltag_cells(const std::string& family_name, int id) {
  const AprilTagFamilyPtr family = create_apriltag_family(family_name);
  if (!family)
    throw InputError("", "dictionary",
                     "'" + family_name + "' is not an AprilTag family (" + apriltag_family_names() + ")");
  const AprilTagFamilyInfo info = apriltag_family_info(family_name);
  const int total = family->total_width, border = family->width_at_border;
  cv::Mat full(total, total, CV_8UC1, cv::Scalar(0));
  const int ring = border + (family->reversed_border ? 0 : 2);
  const int ring_start = (total - ring) / 2;
  cv::rectangle(full, cv::Rect(ring_start, ring_start, ring, ring), cv::Scalar(255), 1);
  const int border_start = (total - border) / 2;
  const std::uint64_t code = family->codes[id];
  for (std::uint32_t i = 0; i < family->nbits; ++i)
    if (code & (std::uint64_t{1} << (family->nbits - i - 1)))
      full.at<unsigned char>(static_cast<std::int32_t>(family->bit_y[i]) + border_start,
                             static_cast<std::int32_t>(family->bit_x[i]) + border_start) = 255;
  const int skip = (total - info.pattern_cells) / 2;  // the white ring of normal borders is the margin's
  return full(cv::Rect(skip, skip, info.pattern_cells, info.pattern_cells)).clone();
}

// Each row's runs of black cells as rectangles, the pattern's top-left at `origin`.
void add_black_cells(const cv::Mat& cells, const Eigen::Vector2d& origin, double cell, std::vector<BoardRect>& rects) {
  for (int y = 0; y < cells.rows; ++y) {
    for (int x = 0; x < cells.cols;) {
      if (cells.at<unsigned char>(y, x) != 0) {
        ++x;
        continue;
      }
      int end = x;
      while (end < cells.cols && cells.at<unsigned char>(y, end) == 0) ++end;
      rects.push_back({origin.x() + x * cell, origin.y() + y * cell, origin.x() + end * cell, origin.y() + (y + 1) * cell});
      x = end;
    }
  }
}

// Text for SVG: shortest exact decimal, rounded to 1 nm so sums like 0.1 + 0.2
// print as 0.3.
std::string mm(double value) {
  double rounded = std::round(value * 1e6) / 1e6;
  if (rounded == 0) rounded = 0;  // no "-0"
  return fmt::format("{}", rounded);
}

std::string xml_escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\n': case '\r': case '\t': out += ' '; break;
      default: out += c;
    }
  }
  return out;
}

double resolve_margin(const TargetSpec& spec, double margin_mm) {
  return margin_mm < 0 ? default_margin_mm(spec) : margin_mm;
}

// Caption lines under the SVG's pattern.
std::vector<std::string> caption_lines(const TargetSpec& spec) {
  std::vector<std::string> lines;
  const std::string what = spec.kind == TargetKind::speckle ? "glasspiv speckle plate" : "glasspiv calibration target";
  lines.push_back(spec.name.empty() ? what : what + " '" + spec.name + "'");
  switch (spec.kind) {
    case TargetKind::chessboard:
      lines.push_back(fmt::format("chessboard, {} x {} squares, square {} mm ({} x {} inner corners)",
                                  spec.squares_x, spec.squares_y, mm(spec.square_size_mm), spec.squares_x - 1,
                                  spec.squares_y - 1));
      break;
    case TargetKind::charuco:
      lines.push_back(fmt::format("charuco, {} x {} squares, square {} mm, marker {} mm", spec.squares_x,
                                  spec.squares_y, mm(spec.square_size_mm), mm(spec.marker_size_mm)));
      lines.push_back(fmt::format("dictionary {}, first id {}, {} layout", spec.dictionary, spec.first_id,
                                  charuco_layout_name(spec.charuco_layout)));
      break;
    case TargetKind::aprilgrid:
      lines.push_back(fmt::format("aprilgrid, {} x {} tags, tag {} mm, spacing {} mm", spec.squares_x, spec.squares_y,
                                  mm(spec.square_size_mm), mm(spec.marker_size_mm)));
      lines.push_back(fmt::format("dictionary {}, first id {}", spec.dictionary, spec.first_id));
      break;
    case TargetKind::aruco_marker:
      lines.push_back(fmt::format("ArUco marker {} id {}, marker {} mm (its black border)", spec.dictionary,
                                  spec.first_id, mm(spec.marker_size_mm)));
      break;
    case TargetKind::apriltag: {
      const AprilTagFamilyInfo f = apriltag_family_info(spec.dictionary);
      lines.push_back(fmt::format("AprilTag {} id {}, tag size {} mm ({}the detected square, {} bits)",
                                  spec.dictionary, spec.first_id, mm(spec.marker_size_mm),
                                  f.reversed_border ? "inside the black ring: " : "black border: ", f.border_cells));
      break;
    }
    case TargetKind::speckle: {
      const SpeckleGrid g = speckle_grid(spec);
      lines.push_back(fmt::format("speckle plate {} x {} mm, dot diameter {} mm, fill {}, seed {}",
                                  mm(spec.plate_size_mm.x()), mm(spec.plate_size_mm.y()), mm(spec.dot_diameter_mm),
                                  spec.fill, spec.seed));
      lines.push_back(fmt::format("{} dots, one in each cell of a {} x {} grid (docs/targets.md)", g.dot_count(),
                                  g.cols, g.rows));
      break;
    }
  }
  lines.push_back("print at 100% scale; check: this bar is 100 mm");
  return lines;
}

// Caption layout, mm: 3 mm text on 4 mm lines, then the bar and its ticks.
constexpr double kCaptionFontMm = 3.0;
constexpr double kCaptionLineMm = 4.0;
constexpr double kBarGapMm = 2.0;
constexpr double kBarHeightMm = 2.0;
constexpr double kTickMm = 3.0;

double caption_height_mm(const TargetSpec& spec) {
  return caption_lines(spec).size() * kCaptionLineMm + kBarGapMm + kBarHeightMm + kTickMm + 1.5;
}

// PNG with a pHYs chunk, so viewers and printers know the resolution.
std::uint32_t crc32(const unsigned char* data, std::size_t size) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t n = 0; n < 256; ++n) {
      std::uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < size; ++i) c = table[(c ^ data[i]) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

void put_u32(std::vector<unsigned char>& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<unsigned char>(v >> shift));
}

std::vector<unsigned char> png_with_dpi(const cv::Mat& image, double dpi) {
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", image, png)) throw InputError("", "", "PNG encoding failed");
  // Signature (8 bytes) then IHDR: length (4) + type (4) + 13 data + CRC (4).
  const std::size_t after_ihdr = 8 + 4 + 4 + 13 + 4;
  std::vector<unsigned char> chunk;
  put_u32(chunk, 9);
  const std::size_t type_at = chunk.size();
  for (const char c : {'p', 'H', 'Y', 's'}) chunk.push_back(static_cast<unsigned char>(c));
  const auto per_metre = static_cast<std::uint32_t>(std::lround(dpi / 0.0254));
  put_u32(chunk, per_metre);
  put_u32(chunk, per_metre);
  chunk.push_back(1);  // unit: metre
  put_u32(chunk, crc32(chunk.data() + type_at, chunk.size() - type_at));
  png.insert(png.begin() + static_cast<std::ptrdiff_t>(after_ihdr), chunk.begin(), chunk.end());
  return png;
}

// The picture's size for a resolution and margin, refused over kMaxMegapixels.
cv::Size picture_size(const TargetSpec& spec, double px_per_mm, double margin_mm) {
  if (!std::isfinite(px_per_mm) || !(px_per_mm > 0))
    throw InputError("", "resolution", fmt::format("must be positive, got {} px/mm", px_per_mm));
  if (!std::isfinite(margin_mm) || margin_mm < 0)
    throw InputError("", "margin", fmt::format("must be 0 mm or more, got {}", margin_mm));
  const Eigen::Vector2d size = board_size_mm(spec);
  const double w = std::ceil((size.x() + 2 * margin_mm) * px_per_mm - 1e-9);
  const double h = std::ceil((size.y() + 2 * margin_mm) * px_per_mm - 1e-9);
  if (w * h > kMaxMegapixels * 1e6)
    throw InputError("", "resolution",
                     fmt::format("{} px/mm makes a {:.0f} x {:.0f} px picture, over {} megapixels", px_per_mm, w, h,
                                 kMaxMegapixels));
  return cv::Size(static_cast<int>(w), static_cast<int>(h));
}

// Ink of black rectangles, exact area per pixel, added into `ink`.
void add_rect_ink(const std::vector<BoardRect>& rects, double px_per_mm, double margin_mm, cv::Mat& ink) {
  // Pixel (i, j) covers [i, i + 1] x [j, j + 1] in edge coordinates E = (x + margin) * px_per_mm.
  for (const BoardRect& r : rects) {
    const double ex0 = (r.x0 + margin_mm) * px_per_mm, ex1 = (r.x1 + margin_mm) * px_per_mm;
    const double ey0 = (r.y0 + margin_mm) * px_per_mm, ey1 = (r.y1 + margin_mm) * px_per_mm;
    const int i0 = std::max(0, static_cast<int>(std::floor(ex0)));
    const int i1 = std::min(ink.cols, static_cast<int>(std::ceil(ex1)));
    const int j0 = std::max(0, static_cast<int>(std::floor(ey0)));
    const int j1 = std::min(ink.rows, static_cast<int>(std::ceil(ey1)));
    for (int j = j0; j < j1; ++j) {
      const double wy = std::min(ey1, j + 1.0) - std::max(ey0, static_cast<double>(j));
      float* row = ink.ptr<float>(j);
      for (int i = i0; i < i1; ++i) {
        const double wx = std::min(ex1, i + 1.0) - std::max(ex0, static_cast<double>(i));
        row[i] += static_cast<float>(wx * wy);
      }
    }
  }
}

// The union of a speckle plate's discs over pixel squares (edge coordinates:
// pixel (i, j) is [i, i + 1] x [j, j + 1]).
class DiscUnionCoverage {
 public:
  DiscUnionCoverage(const TargetSpec& spec, double px_per_mm, double margin_mm)
      : grid_(speckle_grid(spec)), px_per_mm_(px_per_mm), margin_mm_(margin_mm) {
    const std::vector<SpeckleDot> dots = speckle_dots(spec);
    radius_ = spec.dot_diameter_mm / 2 * px_per_mm;
    centres_.reserve(dots.size());
    for (const SpeckleDot& d : dots) centres_.push_back((d.centre_mm.array() + margin_mm) * px_per_mm);
    // Each dot's overlapping neighbours: dots closer than a diameter lie at
    // most ceil(diameter / cell) cells away.
    const int reach_x = static_cast<int>(std::ceil(spec.dot_diameter_mm / grid_.cell_width_mm));
    const int reach_y = static_cast<int>(std::ceil(spec.dot_diameter_mm / grid_.cell_height_mm));
    const double diameter2 = 4 * radius_ * radius_;
    neighbour_start_.push_back(0);
    for (int row = 0; row < grid_.rows; ++row)
      for (int col = 0; col < grid_.cols; ++col) {
        const int k = row * grid_.cols + col;
        for (int r = std::max(0, row - reach_y); r <= std::min(grid_.rows - 1, row + reach_y); ++r)
          for (int c = std::max(0, col - reach_x); c <= std::min(grid_.cols - 1, col + reach_x); ++c) {
            const int n = r * grid_.cols + c;
            if (n != k && (centres_[n] - centres_[k]).squaredNorm() < diameter2) neighbours_.push_back(n);
          }
        neighbour_start_.push_back(neighbours_.size());
      }
    stamp_.assign(centres_.size(), 0);
    max_depth_ = max_depth(radius_);
    lists_.resize(static_cast<std::size_t>(max_depth_) + 2);
  }

  // The ink of pixel (i, j), and the bound on its error added to `error`.
  double pixel(int i, int j, double& error) {
    // Dots lie in their cells: those of the cells within a radius of the pixel.
    const double x0 = i / px_per_mm_ - margin_mm_, x1 = (i + 1) / px_per_mm_ - margin_mm_;
    const double y0 = j / px_per_mm_ - margin_mm_, y1 = (j + 1) / px_per_mm_ - margin_mm_;
    const double r_mm = radius_ / px_per_mm_;
    const int c0 = std::max(0, static_cast<int>(std::floor((x0 - r_mm) / grid_.cell_width_mm)));
    const int c1 = std::min(grid_.cols - 1, static_cast<int>(std::floor((x1 + r_mm) / grid_.cell_width_mm)));
    const int r0 = std::max(0, static_cast<int>(std::floor((y0 - r_mm) / grid_.cell_height_mm)));
    const int r1 = std::min(grid_.rows - 1, static_cast<int>(std::floor((y1 + r_mm) / grid_.cell_height_mm)));
    if (c1 < c0 || r1 < r0) return 0;
    std::vector<int>& candidates = lists_.back();
    candidates.clear();
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c) candidates.push_back(r * grid_.cols + c);
    return square(i, j, 1.0, candidates, 0, error);
  }

 private:
  // Pieces down to 2^-10 of the smaller of a pixel and a dot's radius: where a
  // pixel holds many dots, its unresolved pieces (near the crossings of
  // overlapping dots' edges) stay as small against each dot as they would be
  // at a pixel per radius, so the error bound does not grow with the dots per
  // pixel.
  static int max_depth(double radius_px) {
    return 10 + (radius_px < 1 ? static_cast<int>(std::ceil(std::log2(1 / radius_px))) : 0);
  }

  // Ink of the square [x0, x0 + side] x [y0, y0 + side] from the discs `ids`.
  double square(double x0, double y0, double side, const std::vector<int>& ids, int depth, double& error) {
    const double x1 = x0 + side, y1 = y0 + side, r2 = radius_ * radius_;
    // One list per depth: a square's children (depth + 1) read its list and
    // fill the next one, one child after another.
    std::vector<int>& partial = lists_[depth];
    partial.clear();
    for (const int k : ids) {
      const Eigen::Vector2d& c = centres_[k];
      const double dx = std::max({x0 - c.x(), 0.0, c.x() - x1}), dy = std::max({y0 - c.y(), 0.0, c.y() - y1});
      if (dx * dx + dy * dy >= r2) continue;  // apart
      const double fx = std::max(std::abs(c.x() - x0), std::abs(c.x() - x1));
      const double fy = std::max(std::abs(c.y() - y0), std::abs(c.y() - y1));
      if (fx * fx + fy * fy <= r2) return side * side;  // inside this disc
      partial.push_back(k);
    }
    if (partial.empty()) return 0;
    // Exact when no two of the discs crossing the square overlap.
    ++token_;
    for (const int k : partial) stamp_[k] = token_;
    bool overlapping = false;
    for (std::size_t a = 0; a < partial.size() && !overlapping; ++a)
      for (std::size_t n = neighbour_start_[partial[a]]; n < neighbour_start_[partial[a] + 1]; ++n)
        if (stamp_[neighbours_[n]] == token_) {
          overlapping = true;
          break;
        }
    double sum = 0, largest = 0;
    for (const int k : partial) {
      const double a = disc_rectangle_area(centres_[k], radius_, x0, y0, x1, y1);
      sum += a;
      largest = std::max(largest, a);
    }
    if (!overlapping) return std::min(sum, side * side);
    const double hi = std::min(sum, side * side);
    if (depth == max_depth_ || hi - largest <= 1e-12) {
      error += (hi - largest) / 2;
      return (hi + largest) / 2;
    }
    const double half = side / 2;
    return square(x0, y0, half, partial, depth + 1, error) + square(x0 + half, y0, half, partial, depth + 1, error) +
           square(x0, y0 + half, half, partial, depth + 1, error) +
           square(x0 + half, y0 + half, half, partial, depth + 1, error);
  }

  SpeckleGrid grid_;
  double px_per_mm_ = 0, margin_mm_ = 0, radius_ = 0;
  std::vector<Eigen::Vector2d> centres_;  // edge coordinates
  std::vector<std::size_t> neighbour_start_;
  std::vector<int> neighbours_;
  std::vector<std::uint64_t> stamp_;
  std::uint64_t token_ = 0;
  int max_depth_ = 0;
  std::vector<std::vector<int>> lists_;  // per depth, and last the pixel's candidates
};

}  // namespace

std::vector<BoardRect> target_black_rects(const TargetSpec& spec) {
  std::vector<BoardRect> rects;
  if (spec.kind == TargetKind::speckle) return rects;
  if (spec.kind == TargetKind::aruco_marker) {
    const cv::Ptr<cv::aruco::Dictionary> dictionary = marker_dictionary(spec);
    const int cells = dictionary->markerSize + 2;  // data bits and the one-bit black border
    cv::Mat bits;
    dictionary->drawMarker(spec.first_id, cells, bits, 1);  // one pixel per cell, 0 = black
    add_black_cells(bits, Eigen::Vector2d::Zero(), spec.marker_size_mm / cells, rects);
    return rects;
  }
  if (spec.kind == TargetKind::apriltag) {
    const AprilTagFamilyInfo f = apriltag_family_info(spec.dictionary);
    add_black_cells(apriltag_cells(spec.dictionary, spec.first_id), Eigen::Vector2d::Zero(),
                    spec.marker_size_mm / f.border_cells, rects);
    return rects;
  }
  if (spec.kind != TargetKind::aprilgrid) {
    const double s = spec.square_size_mm;
    for (int r = 0; r < spec.squares_y; ++r)
      for (int c = 0; c < spec.squares_x; ++c)
        if (square_is_black(spec, c, r)) rects.push_back({c * s, r * s, (c + 1) * s, (r + 1) * s});
  }
  if (spec.kind == TargetKind::chessboard) return rects;
  const cv::Ptr<cv::aruco::Dictionary> dictionary = marker_dictionary(spec);
  const int cells = dictionary->markerSize + 2;  // data bits and the one-bit black border
  for (const BoardMarker& m : board_markers(spec)) {
    cv::Mat bits;
    dictionary->drawMarker(m.id, cells, bits, 1);  // one pixel per cell, 0 = black
    add_black_cells(bits, m.top_left_mm, m.size_mm / cells, rects);
  }
  return rects;
}

std::vector<BoardDisc> target_black_discs(const TargetSpec& spec) {
  std::vector<BoardDisc> discs;
  if (spec.kind != TargetKind::speckle) return discs;
  for (const SpeckleDot& d : speckle_dots(spec)) discs.push_back({d.centre_mm.x(), d.centre_mm.y(), d.radius_mm});
  return discs;
}

double default_margin_mm(const TargetSpec& spec) {
  if (spec.kind == TargetKind::speckle) return std::max(5.0, 2 * spec.dot_diameter_mm);
  // Single markers: two cells (bits). Both detectors need a white quiet zone
  // of at least one cell around the black border (libapriltag draws exactly
  // one; ArUco must see the border as a closed dark contour) and the corner
  // refinement reads the edge half a cell to each side; the second cell is
  // slack for cutting and gluing.
  if (spec.kind == TargetKind::aruco_marker)
    return 2 * spec.marker_size_mm / (marker_dictionary(spec)->markerSize + 2);
  if (spec.kind == TargetKind::apriltag)
    return 2 * spec.marker_size_mm / apriltag_family_info(spec.dictionary).border_cells;
  if (spec.kind == TargetKind::aprilgrid) return std::max(spec.marker_size_mm, spec.square_size_mm / 4);
  return spec.square_size_mm / 2;
}

Eigen::Vector2d TargetRender::pixel_from_board(const Eigen::Vector2d& board_mm) const {
  return (board_mm.array() + margin_mm) * px_per_mm - 0.5;
}

Eigen::Vector2d TargetRender::board_from_pixel(const Eigen::Vector2d& pixel) const {
  return (pixel.array() + 0.5) / px_per_mm - margin_mm;
}

cv::Mat target_ink_coverage(const TargetSpec& spec, double px_per_mm, double margin_mm, double* max_error) {
  validate_target(spec);
  const cv::Size size = picture_size(spec, px_per_mm, margin_mm);
  cv::Mat ink(size, CV_32F, cv::Scalar(0));
  double worst = 0;
  if (spec.kind == TargetKind::speckle) {
    DiscUnionCoverage discs(spec, px_per_mm, margin_mm);
    for (int j = 0; j < ink.rows; ++j) {
      float* row = ink.ptr<float>(j);
      for (int i = 0; i < ink.cols; ++i) {
        double error = 0;
        row[i] = static_cast<float>(std::clamp(discs.pixel(i, j, error), 0.0, 1.0));
        worst = std::max(worst, error);
      }
    }
  } else {
    add_rect_ink(target_black_rects(spec), px_per_mm, margin_mm, ink);
    ink = cv::min(ink, 1.0);  // the rectangles do not overlap: only float rounding reaches past 1
  }
  if (max_error != nullptr) *max_error = worst;
  return ink;
}

TargetRender render_target(const TargetSpec& spec, double px_per_mm, double margin_mm) {
  const cv::Mat ink = target_ink_coverage(spec, px_per_mm, margin_mm);
  TargetRender render;
  render.px_per_mm = px_per_mm;
  render.margin_mm = margin_mm;
  render.image.create(ink.rows, ink.cols, CV_8UC1);
  for (int j = 0; j < ink.rows; ++j) {
    const float* in = ink.ptr<float>(j);
    unsigned char* out = render.image.ptr<unsigned char>(j);
    for (int i = 0; i < ink.cols; ++i)
      out[i] = static_cast<unsigned char>(std::lround(255.0 * (1.0 - std::clamp(static_cast<double>(in[i]), 0.0, 1.0))));
  }
  return render;
}

Eigen::Vector2d target_svg_size_mm(const TargetSpec& spec, double margin_mm) {
  const double margin = resolve_margin(spec, margin_mm);
  const Eigen::Vector2d board = board_size_mm(spec);
  const double content_w = std::max(board.x(), kScaleBarMm + 10.0);
  return Eigen::Vector2d(content_w + 2 * margin, board.y() + 2 * margin + caption_height_mm(spec));
}

TargetPage target_page(const TargetSpec& spec, double margin_mm) {
  validate_target(spec);
  const double margin = resolve_margin(spec, margin_mm);
  if (!std::isfinite(margin)) throw InputError("", "margin", "must be finite");
  TargetPage page;
  page.size_mm = target_svg_size_mm(spec, margin);
  page.title = describe_target(spec);
  page.font_size_mm = kCaptionFontMm;
  for (const BoardRect& r : target_black_rects(spec))
    page.pattern.push_back({r.x0 + margin, r.y0 + margin, r.x1 + margin, r.y1 + margin});
  for (const BoardDisc& d : target_black_discs(spec)) page.discs.push_back({d.x + margin, d.y + margin, d.radius});
  // Caption: below the pattern's margin.
  const double x = margin;
  double y = board_size_mm(spec).y() + 2 * margin;
  for (const std::string& line : caption_lines(spec)) {
    y += kCaptionLineMm;
    page.caption.push_back({x, y, line});
  }
  y += kBarGapMm;
  page.scale_bar.push_back({x, y, x + kScaleBarMm, y + kBarHeightMm});
  // Ticks every 10 mm below the bar, the ends longer.
  for (int k = 0; k <= 10; ++k) {
    const double tick = 0.3, length = (k == 0 || k == 10) ? kTickMm : kTickMm / 2;
    const double tx = std::clamp(x + 10.0 * k - tick / 2, x, x + kScaleBarMm - tick);
    page.scale_bar.push_back({tx, y + kBarHeightMm, tx + tick, y + kBarHeightMm + length});
  }
  return page;
}

std::string target_svg(const TargetSpec& spec, double margin_mm) {
  const TargetPage page = target_page(spec, margin_mm);
  const auto rect = [](const BoardRect& r) {
    return fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/>\n", mm(r.x0), mm(r.y0),
                       mm(r.x1 - r.x0), mm(r.y1 - r.y0));
  };
  std::string svg;
  svg += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  svg += fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"{}mm\" height=\"{}mm\" "
      "viewBox=\"0 0 {} {}\">\n",
      mm(page.size_mm.x()), mm(page.size_mm.y()), mm(page.size_mm.x()), mm(page.size_mm.y()));
  svg += "<title>" + xml_escape(page.title) + "</title>\n";
  svg += fmt::format("<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#ffffff\"/>\n", mm(page.size_mm.x()),
                     mm(page.size_mm.y()));
  svg += "<g id=\"pattern\" fill=\"#000000\" stroke=\"none\">\n";
  for (const BoardRect& r : page.pattern) svg += rect(r);
  for (const BoardDisc& d : page.discs)
    svg += fmt::format("<circle cx=\"{}\" cy=\"{}\" r=\"{}\"/>\n", mm(d.x), mm(d.y), mm(d.radius));
  svg += "</g>\n";
  svg += fmt::format("<g id=\"caption\" font-family=\"sans-serif\" font-size=\"{}\" fill=\"#000000\">\n",
                     mm(page.font_size_mm));
  for (const TargetPageText& line : page.caption)
    svg += fmt::format("<text x=\"{}\" y=\"{}\">{}</text>\n", mm(line.x_mm), mm(line.baseline_mm), xml_escape(line.text));
  svg += "</g>\n";
  svg += "<g id=\"scale-bar\" fill=\"#000000\" stroke=\"none\">\n";
  for (const BoardRect& r : page.scale_bar) svg += rect(r);
  svg += "</g>\n</svg>\n";
  return svg;
}

void write_target_svg(const std::string& path, const TargetSpec& spec) {
  write_file_atomically(path, target_svg(spec));
}

void write_target_png(const std::string& path, const TargetSpec& spec, double dpi) {
  if (!std::isfinite(dpi) || !(dpi > 0)) throw InputError("", "--dpi", fmt::format("must be positive, got {}", dpi));
  const TargetRender render = render_target(spec, dpi / 25.4, default_margin_mm(spec));
  const std::vector<unsigned char> png = png_with_dpi(render.image, dpi);
  write_file_atomically(path, std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
}

}  // namespace glasspiv
