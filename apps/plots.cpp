#include "apps/plots.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "apps/png_file.h"

namespace glasspiv {
namespace {

constexpr int kMaxPlotWidth = 900;
constexpr int kMargin = 40, kBarWidth = 22, kLegendWidth = 110;

double max_magnitude(const GridValues& values) {
  double m = 0;
  for (const auto& v : values.vector_px)
    if (v.allFinite()) m = std::max(m, v.norm());
  return m;
}

// A figure for the caption: "no figure" where there is none (no nan on a picture).
std::string figure(double value, const std::string& unit) {
  return std::isfinite(value) ? fmt::format("{:.4g} {}", value, unit) : "no figure";
}

}  // namespace

cv::Point HeatMapPicture::at(double x_px, double y_px) const {
  return {plot.x + static_cast<int>(std::lround(x_px * scale)), plot.y + static_cast<int>(std::lround(y_px * scale))};
}

HeatMapPicture draw_magnitude_map(const GridValues& values, int width_px, int height_px, const PlotLabels& labels,
                                  double top) {
  if (!(top > 0)) top = max_magnitude(values);
  HeatMapPicture c;
  c.scale = std::min(1.0, static_cast<double>(kMaxPlotWidth) / width_px);
  const int pw = std::max(1, static_cast<int>(std::lround(width_px * c.scale)));
  const int ph = std::max(1, static_cast<int>(std::lround(height_px * c.scale)));
  c.plot = cv::Rect(kMargin, kMargin, pw, ph);
  c.image = cv::Mat(ph + 2 * kMargin, pw + 2 * kMargin + kLegendWidth, CV_8UC3, cv::Scalar(255, 255, 255));

  // Magnitudes on the sample grid, bilinearly resized to the plot; NaN cells grey.
  const PixelGrid& g = values.grid;
  cv::Mat magnitude(g.rows, g.cols, CV_32F), valid(g.rows, g.cols, CV_8U);
  for (int j = 0; j < g.rows; ++j)
    for (int i = 0; i < g.cols; ++i) {
      const Eigen::Vector2d& v = values.vector_px[j * g.cols + i];
      const bool ok = v.allFinite();
      valid.at<uchar>(j, i) = ok ? 255 : 0;
      magnitude.at<float>(j, i) = ok ? static_cast<float>(top > 0 ? std::min(1.0, v.norm() / top) : 0.0) : 0.f;
    }
  cv::Mat mag_plot, valid_plot, mag8, colour;
  cv::resize(magnitude, mag_plot, cv::Size(pw, ph), 0, 0, labels.cells ? cv::INTER_NEAREST : cv::INTER_LINEAR);
  cv::resize(valid, valid_plot, cv::Size(pw, ph), 0, 0, cv::INTER_NEAREST);
  mag_plot.convertTo(mag8, CV_8U, 255.0);
  cv::applyColorMap(mag8, colour, cv::COLORMAP_VIRIDIS);
  colour.setTo(cv::Scalar(160, 160, 160), valid_plot == 0);
  colour.copyTo(c.image(c.plot));
  cv::rectangle(c.image, c.plot, cv::Scalar(0, 0, 0), 1);

  // Colour bar.
  const cv::Rect bar(kMargin + pw + 20, kMargin, kBarWidth, ph);
  cv::Mat ramp(ph, 1, CV_8U);
  for (int y = 0; y < ph; ++y) ramp.at<uchar>(y, 0) = static_cast<uchar>(255 - (255 * y) / std::max(1, ph - 1));
  cv::Mat ramp_colour;
  cv::applyColorMap(ramp, ramp_colour, cv::COLORMAP_VIRIDIS);
  cv::resize(ramp_colour, ramp_colour, cv::Size(kBarWidth, ph), 0, 0, cv::INTER_NEAREST);
  ramp_colour.copyTo(c.image(bar));
  cv::rectangle(c.image, bar, cv::Scalar(0, 0, 0), 1);
  const auto text = [&](const std::string& s, cv::Point at, double size = 0.45) {
    cv::putText(c.image, s, at, cv::FONT_HERSHEY_SIMPLEX, size, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  };
  text(fmt::format("{:.3g}", top), {bar.x + kBarWidth + 4, bar.y + 10});
  text("0", {bar.x + kBarWidth + 4, bar.y + ph});
  text(labels.value_name, {bar.x - 10, bar.y + ph + 22}, 0.4);
  text(labels.title, {kMargin, 25}, 0.55);
  text(fmt::format("RMS {}   max {}   {} of {} samples valid", figure(values.rms_px, labels.unit),
                   figure(values.max_px, labels.unit), values.valid_count, values.grid.size()),
       {kMargin, kMargin + ph + 25}, 0.45);
  return c;
}

void write_magnitude_png(const GridValues& values, int width_px, int height_px, const PlotLabels& labels,
                         const std::string& path) {
  write_png(path, draw_magnitude_map(values, width_px, height_px, labels).image);
}

void write_vector_field_png(const GridValues& values, int width_px, int height_px, const PlotLabels& labels,
                            const std::string& path) {
  const double top = max_magnitude(values);
  HeatMapPicture c = draw_magnitude_map(values, width_px, height_px, labels, top);
  const PixelGrid& g = values.grid;
  // Longest arrow ~ 0.9 of the sample spacing on the plot.
  const double spacing_plot = std::min(g.step_x_px, g.step_y_px) * c.scale;
  const double arrow_scale = top > 0 ? 0.9 * spacing_plot / top : 0.0;  // plot px per value px
  for (int j = 0; j < g.rows; ++j)
    for (int i = 0; i < g.cols; ++i) {
      const Eigen::Vector2d& v = values.vector_px[j * g.cols + i];
      if (!v.allFinite()) continue;
      const Eigen::Vector2d p = g.pixel(i, j) * c.scale;
      const cv::Point2d from(c.plot.x + p.x(), c.plot.y + p.y());
      const cv::Point2d to = from + cv::Point2d(v.x(), v.y()) * arrow_scale;
      cv::arrowedLine(c.image, from, to, cv::Scalar(255, 255, 255), 1, cv::LINE_AA, 0, 0.3);
    }
  cv::putText(c.image, fmt::format("arrows x{:.3g}", arrow_scale / c.scale), {c.plot.x + c.plot.width - 130, 25},
              cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  write_png(path, c.image);
}

}  // namespace glasspiv
