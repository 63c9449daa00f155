// PDF targets (targets/target_pdf.h), read back by an independent reader,
// poppler: the page is target_svg_size_mm() at 72 points per inch, and the
// page rendered back at 10 px/mm shows the 100 mm bar 100 mm long, the first
// black square its size, the pattern where render_target() puts it, and the
// caption as text.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <regex>
#include <string>

#include <gtest/gtest.h>
#include <poppler/cpp/poppler-document.h>
#include <poppler/cpp/poppler-image.h>
#include <poppler/cpp/poppler-page-renderer.h>
#include <poppler/cpp/poppler-page.h>

#include "targets/target_image.h"
#include "targets/target_pdf.h"
#include "targets/target_yaml.h"
#include "util/atomic_file.h"

namespace glasspiv {
namespace {

constexpr double kPxPerMm = 10;  // rendering resolution: 254 dpi

TargetSpec data_target(const std::string& name) {
  return read_target_yaml(std::string(GLASSPIV_SOURCE_DIR) + "/data/targets/" + name);
}

struct Rendered {
  int width = 0, height = 0;
  std::vector<double> ink;  // 1 = black, 0 = white, row-major
  double at(int x, int y) const { return ink[static_cast<std::size_t>(y) * width + x]; }
};

// poppler reads `pdf` in place: it must outlive the document.
std::unique_ptr<poppler::document> load(const std::string& pdf) {
  std::unique_ptr<poppler::document> doc(poppler::document::load_from_raw_data(pdf.data(), static_cast<int>(pdf.size())));
  EXPECT_TRUE(doc) << "poppler cannot read the PDF";
  return doc;
}

Rendered render(const poppler::document& doc) {
  const std::unique_ptr<poppler::page> page(doc.create_page(0));
  poppler::page_renderer renderer;
  renderer.set_render_hint(poppler::page_renderer::antialiasing, true);
  renderer.set_image_format(poppler::image::format_gray8);
  const poppler::image image = renderer.render_page(page.get(), 25.4 * kPxPerMm, 25.4 * kPxPerMm);
  Rendered out;
  out.width = image.width();
  out.height = image.height();
  out.ink.resize(static_cast<std::size_t>(out.width) * out.height);
  for (int y = 0; y < out.height; ++y) {
    const auto* row = reinterpret_cast<const unsigned char*>(image.const_data() + y * image.bytes_per_row());
    for (int x = 0; x < out.width; ++x) out.ink[static_cast<std::size_t>(y) * out.width + x] = 1.0 - row[x] / 255.0;
  }
  return out;
}

// The ink along the pixel row through page height y_mm between x0_mm and x1_mm,
// in mm: the length of black it crosses (anti-aliased edges count by coverage).
double ink_along_row_mm(const Rendered& r, double y_mm, double x0_mm, double x1_mm) {
  const int y = static_cast<int>(y_mm * kPxPerMm);
  double sum = 0;
  for (int x = std::max(0, static_cast<int>(x0_mm * kPxPerMm)); x < std::min(r.width, static_cast<int>(x1_mm * kPxPerMm));
       ++x)
    sum += r.at(x, y);
  return sum / kPxPerMm;
}
double ink_along_column_mm(const Rendered& r, double x_mm, double y0_mm, double y1_mm) {
  const int x = static_cast<int>(x_mm * kPxPerMm);
  double sum = 0;
  for (int y = std::max(0, static_cast<int>(y0_mm * kPxPerMm));
       y < std::min(r.height, static_cast<int>(y1_mm * kPxPerMm)); ++y)
    sum += r.at(x, y);
  return sum / kPxPerMm;
}

TEST(Pdf, PageIsTheSvgsSizeInPoints) {
  for (const char* name : {"chessboard_9x6.yaml", "charuco_11x8_15mm.yaml", "aprilgrid_6x6.yaml"}) {
    const TargetSpec spec = data_target(name);
    const std::string pdf = target_pdf(spec);
    const Eigen::Vector2d size_mm = target_svg_size_mm(spec);
    // The MediaBox as written, and as poppler reads it.
    std::smatch box;
    ASSERT_TRUE(std::regex_search(pdf, box, std::regex(R"(/MediaBox \[\s*0 0 ([0-9.]+) ([0-9.]+)\s*\])"))) << name;
    EXPECT_NEAR(std::stod(box[1]), size_mm.x() * 72 / 25.4, 1e-3) << name;
    EXPECT_NEAR(std::stod(box[2]), size_mm.y() * 72 / 25.4, 1e-3) << name;
    const auto doc = load(pdf);
    ASSERT_TRUE(doc);
    ASSERT_EQ(doc->pages(), 1) << name;
    const std::unique_ptr<poppler::page> page(doc->create_page(0));
    const poppler::rectf rect = page->page_rect(poppler::media_box);
    EXPECT_NEAR(rect.width(), size_mm.x() * 72 / 25.4, 1e-3) << name;
    EXPECT_NEAR(rect.height(), size_mm.y() * 72 / 25.4, 1e-3) << name;
  }
}

TEST(Pdf, ScaleBarSquareAndCaptionAtSize) {
  const TargetSpec spec = data_target("chessboard_9x6.yaml");  // 25 mm squares
  const TargetPage layout = target_page(spec);
  const std::string pdf = target_pdf(spec);
  const auto doc = load(pdf);
  ASSERT_TRUE(doc);
  const Rendered r = render(*doc);
  EXPECT_EQ(r.width, static_cast<int>(std::lround(layout.size_mm.x() * kPxPerMm)));
  EXPECT_EQ(r.height, static_cast<int>(std::lround(layout.size_mm.y() * kPxPerMm)));

  // The bar: 100 mm of black along its middle row (its ticks hang below it).
  const BoardRect& bar = layout.scale_bar.front();
  ASSERT_DOUBLE_EQ(bar.x1 - bar.x0, 100.0);
  const double bar_mm = ink_along_row_mm(r, (bar.y0 + bar.y1) / 2, bar.x0 - 2, bar.x1 + 2);
  EXPECT_NEAR(bar_mm, 100.0, 0.05);
  std::printf("PDF rendered at %g px/mm: scale bar %.3f mm (100 mm drawn)\n", kPxPerMm, bar_mm);

  // The top-left black square, across and down (its neighbours are white).
  const BoardRect& square = layout.pattern.front();
  ASSERT_DOUBLE_EQ(square.x1 - square.x0, 25.0);
  EXPECT_NEAR(ink_along_row_mm(r, (square.y0 + square.y1) / 2, square.x0 - 5, square.x1 + 1), 25.0, 0.05);
  EXPECT_NEAR(ink_along_column_mm(r, (square.x0 + square.x1) / 2, square.y0 - 5, square.y1 + 1), 25.0, 0.05);

  const std::unique_ptr<poppler::page> page(doc->create_page(0));
  const std::string text = page->text().to_latin1();
  EXPECT_NE(text.find("this bar is 100 mm"), std::string::npos) << text;
  EXPECT_NE(text.find("chessboard, 9 x 6 squares, square 25 mm"), std::string::npos) << text;
}

// Every mark in place: the rendered pattern region against render_target()'s
// exact area average at the same resolution and margin.
TEST(Pdf, PatternMatchesTheRaster) {
  const TargetSpec spec = data_target("charuco_11x8_15mm.yaml");
  const std::string pdf = target_pdf(spec);
  const auto doc = load(pdf);
  ASSERT_TRUE(doc);
  const Rendered r = render(*doc);
  const TargetRender raster = render_target(spec, kPxPerMm, default_margin_mm(spec));
  ASSERT_LE(raster.image.cols, r.width);
  ASSERT_LE(raster.image.rows, r.height);
  double sum = 0, worst = 0;
  for (int y = 0; y < raster.image.rows; ++y)
    for (int x = 0; x < raster.image.cols; ++x) {
      const double d = std::abs(r.at(x, y) - (1.0 - raster.image.at<unsigned char>(y, x) / 255.0));
      sum += d;
      worst = std::max(worst, d);
    }
  const double mean = sum / (static_cast<double>(raster.image.rows) * raster.image.cols);
  std::printf("PDF against render_target at %g px/mm: mean |difference| %.4f, worst %.3f (of full ink)\n", kPxPerMm,
              mean, worst);
  // Edges fall on pixel borders at 10 px/mm (15 mm squares, 11 mm markers of
  // 7 cells): beyond anti-aliasing rounding the two pictures are the same.
  EXPECT_LT(mean, 0.005);
  EXPECT_LT(worst, 0.6);
}

TEST(Pdf, WrittenAtomically) {
  const std::string dir = ::testing::TempDir() + "/glasspiv_pdf_test";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/board.pdf";
  const TargetSpec spec = data_target("aprilgrid_6x6.yaml");
  write_target_pdf(path, spec);
  const std::string bytes = read_file(path);
  EXPECT_EQ(bytes.rfind("%PDF-", 0), 0u);
  const auto doc = load(bytes);
  ASSERT_TRUE(doc);
  EXPECT_EQ(doc->pages(), 1);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace glasspiv
