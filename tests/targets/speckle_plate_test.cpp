// Speckle plates (targets/speckle_plate.h): the dots from the seed, their ink
// coverage against an independent point-sampled raster, the SVG parsed back
// (pugixml), the PDF read back (poppler), the YAML round trip and the
// validation errors.
#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <poppler/cpp/poppler-document.h>
#include <poppler/cpp/poppler-image.h>
#include <poppler/cpp/poppler-page-renderer.h>
#include <poppler/cpp/poppler-page.h>
#include <pugixml.hpp>

#include "targets/speckle_plate.h"
#include "targets/target_image.h"
#include "targets/target_pdf.h"
#include "targets/target_yaml.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

TargetSpec example() {
  return read_target_yaml(std::string(GLASSPIV_SOURCE_DIR) + "/data/targets/speckle_150x120_0.5mm.yaml");
}

TargetSpec small_plate(double fill, std::uint64_t seed) {
  TargetSpec s;
  s.kind = TargetKind::speckle;
  s.plate_size_mm = Eigen::Vector2d(12, 9);
  s.dot_diameter_mm = 1.5;
  s.fill = fill;
  s.seed = seed;
  return s;
}

TEST(Speckle, ExampleSpec) {
  const TargetSpec s = example();
  EXPECT_EQ(s.kind, TargetKind::speckle);
  EXPECT_EQ(s.plate_size_mm, Eigen::Vector2d(150, 120));
  EXPECT_EQ(s.dot_diameter_mm, 0.5);
  EXPECT_EQ(s.fill, 0.4);
  EXPECT_EQ(s.seed, 1u);
  EXPECT_EQ(board_size_mm(s), Eigen::Vector2d(150, 120));
  EXPECT_TRUE(board_corners(s).empty());
  EXPECT_EQ(board_corner_count(s), 0u);
  EXPECT_TRUE(board_markers(s).empty());
  EXPECT_TRUE(target_black_rects(s).empty());
  int w = 0, h = 0;
  double spacing = 0;
  EXPECT_FALSE(corner_grid(s, w, h, spacing));
  const SpeckleGrid g = speckle_grid(s);
  EXPECT_EQ(g.cols, 223);
  EXPECT_EQ(g.rows, 179);
  EXPECT_EQ(speckle_dots(s).size(), g.dot_count());
}

// The rule's fixed points: bisection and rounding give the root of the
// quadrature to 2^-32, and the quadrature is the fill of a jittered grid (a
// Monte Carlo estimate from 200 x 200 cells agrees within its noise).
TEST(Speckle, PitchSolvesTheExpectedFill) {
  for (const double fill : {0.05, 0.2, 0.4, 0.7}) {
    const double rho = speckle_diameter_over_pitch(fill);
    EXPECT_NEAR(speckle_expected_fill(rho), fill, 1e-8) << fill;
    EXPECT_EQ(rho, std::ldexp(std::round(std::ldexp(rho, 32)), -32)) << "rounded to 2^-32";
    // Lower than the nominal fill of discs that never overlap, pi rho^2 / 4.
    EXPECT_GT(rho, std::sqrt(4 * fill / M_PI)) << fill;
  }
  // Monte Carlo: points in the middle of a 200 x 200 jittered grid with rho for fill 0.4.
  const double rho = speckle_diameter_over_pitch(0.4), r = rho / 2;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  const int n = 200;
  std::vector<Eigen::Vector2d> centres;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) centres.emplace_back(i + u(rng), j + u(rng));
  int covered = 0;
  const int samples = 200000;
  for (int k = 0; k < samples; ++k) {
    const Eigen::Vector2d p(50 + 100 * u(rng), 50 + 100 * u(rng));
    bool in = false;
    for (int j = static_cast<int>(p.y()) - 2; j <= static_cast<int>(p.y()) + 2 && !in; ++j)
      for (int i = static_cast<int>(p.x()) - 2; i <= static_cast<int>(p.x()) + 2 && !in; ++i)
        in = (centres[static_cast<std::size_t>(j * n + i)] - p).norm() < r;
    covered += in;
  }
  // Binomial standard deviation sqrt(0.4 * 0.6 / 2e5) = 0.0011 (the cells
  // correlate the samples a little): 0.005 is over 4 of them.
  EXPECT_NEAR(static_cast<double>(covered) / samples, 0.4, 0.005);
}

TEST(Speckle, SameSeedSameDotsOtherSeedOthers) {
  const TargetSpec s = example();
  const std::vector<SpeckleDot> a = speckle_dots(s), b = speckle_dots(s);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].centre_mm, b[k].centre_mm) << k;
    ASSERT_EQ(a[k].radius_mm, 0.25);
  }
  TargetSpec other = s;
  other.seed = 2;
  const std::vector<SpeckleDot> c = speckle_dots(other);
  ASSERT_EQ(c.size(), a.size());  // the grid does not depend on the seed
  std::size_t same = 0;
  for (std::size_t k = 0; k < a.size(); ++k) same += a[k].centre_mm == c[k].centre_mm;
  EXPECT_EQ(same, 0u);
  // Pinned: the first dot of seed 1 is the first two draws of std::mt19937_64(1)
  // (the standard fixes the engine) as (draw >> 11) * 2^-53, in the first cell
  // narrowed to [0.25, cell] mm. A change of the rule or of the engine fails here.
  std::mt19937_64 rng(1);
  const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53, v = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  const SpeckleGrid g = speckle_grid(s);
  EXPECT_EQ(a[0].centre_mm.x(), 0.25 + u * (g.cell_width_mm - 0.25));
  EXPECT_EQ(a[0].centre_mm.y(), 0.25 + v * (g.cell_height_mm - 0.25));
  EXPECT_NEAR(a[0].centre_mm.x(), 0.306582393, 1e-9);
  EXPECT_NEAR(a[0].centre_mm.y(), 0.307344299, 1e-9);
}

TEST(Speckle, EveryDotInsideThePlateAndInItsCell) {
  for (const TargetSpec& s : {example(), small_plate(0.7, 3), small_plate(0.05, 4)}) {
    const SpeckleGrid g = speckle_grid(s);
    const std::vector<SpeckleDot> dots = speckle_dots(s);
    ASSERT_EQ(dots.size(), g.dot_count());
    const double r = s.dot_diameter_mm / 2;
    for (std::size_t k = 0; k < dots.size(); ++k) {
      const Eigen::Vector2d& c = dots[k].centre_mm;
      ASSERT_GE(c.x() - r, 0) << k;
      ASSERT_GE(c.y() - r, 0) << k;
      ASSERT_LE(c.x() + r, s.plate_size_mm.x()) << k;
      ASSERT_LE(c.y() + r, s.plate_size_mm.y()) << k;
      const int col = static_cast<int>(k % g.cols), row = static_cast<int>(k / g.cols);
      ASSERT_GE(c.x(), col * g.cell_width_mm - 1e-12) << k;
      ASSERT_LE(c.x(), (col + 1) * g.cell_width_mm + 1e-12) << k;
      ASSERT_GE(c.y(), row * g.cell_height_mm - 1e-12) << k;
      ASSERT_LE(c.y(), (row + 1) * g.cell_height_mm + 1e-12) << k;
    }
  }
}

// What periodicity is left at the grid's own frequency 1 / cell. The dot
// centres have none (their jitter is uniform over the whole cell), but where
// neighbouring dots overlap, near the cells' edges, their union inks less than
// two dots: the expected ink varies within a cell, by about +-3 % of full ink
// at fill 0.4 (0.43 at a cell's centre, 0.37 at its corner, from the rule's
// own integrand). Measured here: the amplitude A of the ink's component at
// 1 / cell along x and along y (A cos(2 pi x / cell)): 0.019 and 0.020 of full
// ink; the test bounds it by 0.03. For a correlation that is a secondary peak at a lag of one cell of
// A^2 / 2 against the ink's variance fill (1 - fill) = 0.24 at lag 0: under
// 0.1 % of the main peak. (A lattice jittered by only 0.3 of a cell, the most
// that keeps 0.5 mm dots from touching at fill 0.4, would keep about 3/4 of a
// perfect lattice's dot contrast at that lag.)
TEST(Speckle, LittlePeriodicityAtTheGridFrequency) {
  const TargetSpec s = example();
  const double px_per_mm = 8;
  const cv::Mat ink = target_ink_coverage(s, px_per_mm, 0);
  const SpeckleGrid g = speckle_grid(s);
  for (int axis = 0; axis < 2; ++axis) {
    // The ink summed across the other axis: a profile along this one.
    cv::Mat profile;
    cv::reduce(ink, profile, axis == 0 ? 0 : 1, cv::REDUCE_SUM, CV_64F);
    const int n = static_cast<int>(profile.total()), across = axis == 0 ? ink.rows : ink.cols;
    const double* p = profile.ptr<double>();
    const auto coefficient = [&](double cycles_per_px) {
      std::complex<double> sum = 0;
      for (int k = 0; k < n; ++k) sum += p[k] * std::polar(1.0, -2 * M_PI * cycles_per_px * (k + 0.5));
      return sum;
    };
    const double f0 = 1 / ((axis == 0 ? g.cell_width_mm : g.cell_height_mm) * px_per_mm);
    const double amplitude = 2 * std::abs(coefficient(f0)) / (static_cast<double>(n) * across);
    const double secondary = amplitude * amplitude / 2 / (s.fill * (1 - s.fill));
    std::printf("axis %d: ink at the grid frequency %.4f of full ink; secondary correlation peak %.2g of the main\n",
                axis, amplitude, secondary);
    EXPECT_LT(amplitude, 0.03) << axis;
  }
}

TEST(Speckle, DiscRectangleAreaClosedForms) {
  const Eigen::Vector2d o(0.3, -0.2);
  EXPECT_NEAR(disc_rectangle_area(o, 2, -5, -5, 5, 5), M_PI * 4, 1e-12);  // whole disc
  EXPECT_NEAR(disc_rectangle_area(o, 2, 0.3, -0.2, 5, 5), M_PI, 1e-12);  // a quarter
  EXPECT_NEAR(disc_rectangle_area(o, 2, -5, -5, 0.3, 5), 2 * M_PI, 1e-12);  // a half
  EXPECT_NEAR(disc_rectangle_area(o, 2, 0, -0.5, 0.5, 0), 0.25, 1e-15);  // inside
  EXPECT_EQ(disc_rectangle_area(o, 2, 3, 3, 4, 4), 0.0);  // apart
  // A circular segment: the part beyond the chord at distance h = 1 from the
  // centre, R^2 acos(h / R) - h sqrt(R^2 - h^2).
  EXPECT_NEAR(disc_rectangle_area(o, 2, 1.3, -5, 5, 5), 4 * std::acos(0.5) - std::sqrt(3.0), 1e-12);
}

// The measured fill of the example's coverage raster. Expected within 1 %
// (absolute) of `fill`: the rule fixes the expected fill of an unbounded grid;
// rounding the pitch to whole cells changes the cell area by under 0.5 %
// (under 0.2 % of fill), the narrowed jitter at the plate's edge moves a strip
// of 0.7 % of the area, and 39,917 dots leave a random spread of about 0.1 %.
TEST(Speckle, MeasuredFillOfTheExample) {
  const TargetSpec s = example();
  double max_error = 1;
  const double px_per_mm = 8;  // 16 px per 2 mm: about 4 px across a dot
  const cv::Mat ink = target_ink_coverage(s, px_per_mm, 0, &max_error);
  ASSERT_EQ(ink.type(), CV_32FC1);
  EXPECT_EQ(ink.cols, 1200);
  EXPECT_EQ(ink.rows, 960);
  const double fill = cv::sum(ink)[0] / (ink.cols * ink.rows);
  std::printf("speckle_150x120_0.5mm at %g px/mm: measured fill %.5f (spec 0.4), largest error bound %.2g\n", px_per_mm,
              fill, max_error);
  EXPECT_NEAR(fill, 0.4, 0.01);
  EXPECT_LT(max_error, 1e-4);
  double lo = 0, hi = 0;
  cv::minMaxLoc(ink, &lo, &hi);
  EXPECT_GE(lo, 0);
  EXPECT_LE(hi, 1);
  EXPECT_EQ(hi, 1) << "pixels wholly inside a dot";
}

// Many dots to a pixel: the error bound stays small, and the ink is the same
// as at a fine resolution (the fill is a sum of areas, whatever the pixels).
TEST(Speckle, CoarsePixelsHoldingManyDots) {
  const TargetSpec s = example();
  double fine_error = 1;
  const cv::Mat fine = target_ink_coverage(s, 8, 0, &fine_error);
  const double fine_ink = cv::sum(fine)[0] / (8.0 * 8.0);  // mm^2
  for (const double px_per_mm : {1.0, 0.25}) {  // 2.2 and 35 dots per pixel
    double max_error = 1;
    const cv::Mat ink = target_ink_coverage(s, px_per_mm, 0, &max_error);
    const double ink_mm2 = cv::sum(ink)[0] / (px_per_mm * px_per_mm);
    std::printf("%g px/mm: largest error bound %.2g, ink %.2f mm^2 (%.2f at 8 px/mm)\n", px_per_mm, max_error, ink_mm2,
                fine_ink);
    EXPECT_LT(max_error, 1e-4) << px_per_mm;
    // Summed over the plate's 18,000 mm^2, the two rasters' per-pixel bounds
    // (fractions of a pixel's area) allow 18,000 (1e-4 + fine_error) mm^2.
    EXPECT_NEAR(ink_mm2, fine_ink, 18000 * (1e-4 + fine_error)) << px_per_mm;
  }
}

// Independent reference: 64 x 64 point samples per pixel, each in or out of
// the union of the dots by distance alone. A sample's sub-square that no disc
// boundary crosses is wholly in or out, so the sampled value is exact there;
// each crossed sub-square can be off by at most 1/4096 of the pixel. Per
// pixel, |coverage - sampled| <= crossed / 4096 + the coverage's own bound.
TEST(Speckle, CoverageAgainstPointSampling) {
  // 2.5 px/mm: dots 3.75 px across; 0.7 px/mm: about a pixel, several to a pixel.
  for (const auto& [s, px_per_mm] : {std::pair{small_plate(0.4, 11), 2.5}, std::pair{small_plate(0.7, 12), 2.5},
                                     std::pair{small_plate(0.1, 13), 2.5}, std::pair{small_plate(0.7, 14), 0.7}}) {
    const double margin = 1;
    double max_error = 1;
    const cv::Mat ink = target_ink_coverage(s, px_per_mm, margin, &max_error);
    EXPECT_LT(max_error, 1e-4);
    const std::vector<SpeckleDot> dots = speckle_dots(s);
    const double r = s.dot_diameter_mm / 2;
    const int n = 64;
    const double sub = 1.0 / (n * px_per_mm);  // a sample's sub-square, mm
    double worst_excess = -1, sum_abs = 0;
    for (int j = 0; j < ink.rows; ++j)
      for (int i = 0; i < ink.cols; ++i) {
        int inside = 0, crossed = 0;
        for (int b = 0; b < n; ++b)
          for (int a = 0; a < n; ++a) {
            const Eigen::Vector2d p((i + (a + 0.5) / n) / px_per_mm - margin, (j + (b + 0.5) / n) / px_per_mm - margin);
            bool in = false, near = false;
            for (const SpeckleDot& d : dots) {
              const double dist = (d.centre_mm - p).norm();
              in = in || dist < r;
              near = near || std::abs(dist - r) <= sub * M_SQRT1_2;  // the boundary may cross the sub-square
            }
            inside += in;
            crossed += near;
          }
        const double sampled = static_cast<double>(inside) / (n * n);
        const double diff = std::abs(ink.at<float>(j, i) - sampled);
        // 1e-6: float storage of the coverage.
        worst_excess = std::max(worst_excess, diff - (static_cast<double>(crossed) / (n * n) + max_error + 1e-6));
        sum_abs += diff;
      }
    EXPECT_LE(worst_excess, 0) << "fill " << s.fill << ", " << px_per_mm << " px/mm";
    // The sampling errors are of both signs: their mean stays far below the bounds.
    EXPECT_LT(sum_abs / (ink.rows * ink.cols), 2e-3) << "fill " << s.fill << ", " << px_per_mm << " px/mm";
  }
}

TEST(Speckle, RenderTargetIsTheCoverage) {
  const TargetSpec s = small_plate(0.4, 5);
  const cv::Mat ink = target_ink_coverage(s, 3, 2);
  const TargetRender render = render_target(s, 3, 2);
  ASSERT_EQ(render.image.size(), ink.size());
  for (int j = 0; j < ink.rows; ++j)
    for (int i = 0; i < ink.cols; ++i)
      ASSERT_EQ(render.image.at<unsigned char>(j, i), std::lround(255 * (1 - ink.at<float>(j, i))));
  // Bounded like render_target: over 500 megapixels is refused.
  EXPECT_THROW(target_ink_coverage(example(), 200, 0), InputError);
}

TEST(Speckle, SvgCirclesAreTheDots) {
  const TargetSpec s = small_plate(0.4, 6);
  const std::string svg = target_svg(s);
  pugi::xml_document doc;
  ASSERT_TRUE(doc.load_string(svg.c_str()));
  const double margin = default_margin_mm(s);
  const std::vector<SpeckleDot> dots = speckle_dots(s);
  std::size_t k = 0;
  const pugi::xpath_node_set circles = doc.select_nodes("//g[@id='pattern']/circle");
  ASSERT_EQ(circles.size(), dots.size());
  EXPECT_EQ(doc.select_nodes("//circle").size(), dots.size());
  for (const pugi::xpath_node& node : circles) {
    const pugi::xml_node c = node.node();
    // Written to 1e-6 mm.
    EXPECT_NEAR(c.attribute("cx").as_double(), dots[k].centre_mm.x() + margin, 1e-6) << k;
    EXPECT_NEAR(c.attribute("cy").as_double(), dots[k].centre_mm.y() + margin, 1e-6) << k;
    EXPECT_NEAR(c.attribute("r").as_double(), 0.75, 1e-12) << k;
    ++k;
  }
  EXPECT_NE(svg.find("speckle plate 12 x 9 mm, dot diameter 1.5 mm, fill 0.4, seed 6"), std::string::npos) << svg;
}

// The PDF read back by poppler at 20 px/mm (30 px dots): the pattern where the
// coverage raster puts it. poppler's anti-aliasing is not an exact area
// average: measured, it inks 1.8 % more than the raster (each dot's edge about
// 0.13 px further out) and differs by 0.002 of full ink per pixel on average.
// The bound 0.01 on that mean is five times the measured value; the pattern is
// in place when the PDF's picture moved by any 1 or 2 px (0.05 or 0.1 mm)
// against the raster differs at least twice as much.
TEST(Speckle, PdfReadBackByPoppler) {
  const TargetSpec s = small_plate(0.4, 8);
  const std::string pdf = target_pdf(s);
  std::unique_ptr<poppler::document> doc(poppler::document::load_from_raw_data(pdf.data(), static_cast<int>(pdf.size())));
  ASSERT_TRUE(doc);
  ASSERT_EQ(doc->pages(), 1);
  const std::unique_ptr<poppler::page> page(doc->create_page(0));
  EXPECT_NE(page->text().to_latin1().find("speckle plate 12 x 9 mm, dot diameter 1.5 mm, fill 0.4, seed 8"),
            std::string::npos);
  const double px_per_mm = 20;
  poppler::page_renderer renderer;
  renderer.set_render_hint(poppler::page_renderer::antialiasing, true);
  renderer.set_image_format(poppler::image::format_gray8);
  const poppler::image image = renderer.render_page(page.get(), 25.4 * px_per_mm, 25.4 * px_per_mm);
  const double margin = default_margin_mm(s);
  const cv::Mat ink = target_ink_coverage(s, px_per_mm, margin);
  ASSERT_LT(ink.rows, image.height());
  ASSERT_LT(ink.cols, image.width());
  const auto pdf_ink = [&](int x, int y) {
    return 1.0 - reinterpret_cast<const unsigned char*>(image.const_data() + y * image.bytes_per_row())[x] / 255.0;
  };
  // The mean difference with the PDF's picture moved by (dx, dy) px.
  const auto mean_difference = [&](int dx, int dy) {
    double sum = 0;
    for (int y = 2; y + 2 < ink.rows; ++y)
      for (int x = 2; x + 2 < ink.cols; ++x) sum += std::abs(pdf_ink(x + dx, y + dy) - ink.at<float>(y, x));
    return sum / ((ink.rows - 4.0) * (ink.cols - 4.0));
  };
  const double mean = mean_difference(0, 0);
  double nearest_moved = 1;
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx)
      if (dx != 0 || dy != 0) nearest_moved = std::min(nearest_moved, mean_difference(dx, dy));
  double ink_pdf = 0, ink_raster = 0;
  for (int y = 0; y < ink.rows; ++y)
    for (int x = 0; x < ink.cols; ++x) {
      ink_pdf += pdf_ink(x, y);
      ink_raster += ink.at<float>(y, x);
    }
  std::printf("PDF at %g px/mm against the coverage: mean difference %.4f (at least %.4f moved by 1 or 2 px), ink "
              "%.1f vs %.1f px\n",
              px_per_mm, mean, nearest_moved, ink_pdf, ink_raster);
  EXPECT_LT(mean, 0.01);
  EXPECT_GT(nearest_moved, 2 * mean);
  EXPECT_NEAR(ink_pdf / ink_raster, 1, 0.03);
}

TEST(Speckle, YamlRoundTrip) {
  TargetSpec s = small_plate(0.35, 18446744073709551615ull);  // the largest seed
  s.name = "plate B";
  const std::string yaml = format_target_yaml(s);
  const TargetSpec back = parse_target_yaml(yaml, "b.yaml");
  EXPECT_EQ(back.kind, TargetKind::speckle);
  EXPECT_EQ(back.name, "plate B");
  EXPECT_EQ(back.plate_size_mm, s.plate_size_mm);
  EXPECT_EQ(back.dot_diameter_mm, s.dot_diameter_mm);
  EXPECT_EQ(back.fill, s.fill);
  EXPECT_EQ(back.seed, s.seed);
  EXPECT_NE(yaml.find("seed: 18446744073709551615"), std::string::npos) << yaml;
  const TargetSpec e = example();
  const TargetSpec e2 = parse_target_yaml(format_target_yaml(e), "e.yaml");
  EXPECT_EQ(speckle_dots(e2).back().centre_mm, speckle_dots(e).back().centre_mm);
}

// Expects `f` to throw InputError for `field`; returns its message.
template <typename F>
std::string error_field(F f, const std::string& field) {
  try {
    f();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no InputError for field '" << field << "'";
  return "";
}

TEST(Speckle, ValidationNamesTheField) {
  const std::string head = "glasspiv_target: 1\nkind: speckle\n";
  const auto parse = [&](const std::string& body) { return [=] { parse_target_yaml(head + body, "p.yaml"); }; };
  const std::string size = "plate_size_mm: [50, 40]\n", dot = "dot_diameter_mm: 1\n", fill = "fill: 0.4\n",
                    seed = "seed: 1\n";
  EXPECT_NO_THROW(parse(size + dot + fill + seed)());
  error_field(parse("plate_size_mm: [-50, 40]\n" + dot + fill + seed), "plate_size_mm[0]");
  error_field(parse("plate_size_mm: [50]\n" + dot + fill + seed), "plate_size_mm");
  error_field(parse("plate_size_mm: [2, 40]\n" + dot + fill + seed), "plate_size_mm");  // under 3 dots
  error_field(parse("plate_size_mm: [20000, 40]\n" + dot + fill + seed), "plate_size_mm[0]");
  error_field(parse(size + "dot_diameter_mm: 0\n" + fill + seed), "dot_diameter_mm");
  error_field(parse("plate_size_mm: [9000, 9000]\n" + dot + fill + seed), "dot_diameter_mm");  // 140 M dots
  EXPECT_NE(error_field(parse(size + dot + "fill: 0.9\n" + seed), "fill").find("(0, 0.7]"), std::string::npos);
  error_field(parse(size + dot + "fill: 0\n" + seed), "fill");
  error_field(parse(size + dot + "fill: .nan\n" + seed), "fill");
  for (const char* bad : {"-1", "1.5", "1e3", "0x10", "18446744073709551616", "[1]", "one"})
    error_field(parse(size + dot + fill + "seed: " + bad + "\n"), "seed");
  error_field(parse(size + dot + fill), "seed");  // required
  // Other kinds' fields are refused for speckle, and speckle's for them.
  error_field(parse(size + dot + fill + seed + "squares: [3, 4]\n"), "squares");
  error_field(parse(size + dot + fill + seed + "dictionary: DICT_4X4_50\n"), "dictionary");
  error_field([] { parse_target_yaml("glasspiv_target: 1\nkind: chessboard\nsquares: [9, 6]\nsquare_size_mm: 25\n"
                                     "fill: 0.4\n", "c.yaml"); },
              "fill");
  TargetSpec chess;
  chess.kind = TargetKind::chessboard;
  chess.squares_x = 9;
  chess.squares_y = 6;
  chess.square_size_mm = 25;
  EXPECT_NO_THROW(validate_target(chess));
  chess.seed = 3;
  error_field([&] { validate_target(chess); }, "seed");
  TargetSpec plate = small_plate(0.4, 1);
  plate.square_size_mm = 10;
  error_field([&] { validate_target(plate); }, "square_size_mm");
  // A detector has nothing to find.
  error_field([] { require_target_corners(small_plate(0.4, 1), "p.yaml", "calib detect"); }, "kind");
}

}  // namespace
}  // namespace glasspiv
