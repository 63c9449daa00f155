#include "sim/pareto_plot.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

namespace glasspiv {

cv::Mat draw_pareto_plot(const std::vector<ChainRow>& rows, const std::vector<std::size_t>& front, double no_glass_px,
                         const std::string& title) {
  const int W = 1280, H = 720, left = 70, plot_right = 880, top = 50, bottom = 70;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  double tmin = 1e300, tmax = 0, emin = no_glass_px > 0 ? no_glass_px : 1e300,
         emax = no_glass_px > 0 ? no_glass_px : 0;
  for (const ChainRow& r : rows)
    if (std::isfinite(r.error.rms_px)) {
      tmin = std::min(tmin, r.frame_ms);
      tmax = std::max(tmax, r.frame_ms);
      emin = std::min(emin, r.error.rms_px);
      emax = std::max(emax, r.error.rms_px);
    }
  if (!(tmax > 0 && emax > 0)) {  // no row with an error: an empty frame of one decade each
    tmin = tmax = 1;
    emin = emax = 0.1;
  }
  const double lx0 = std::floor(std::log10(tmin)), lx1 = std::max(std::ceil(std::log10(tmax)), lx0 + 1);
  const double ly0 = std::floor(std::log10(emin)), ly1 = std::max(std::ceil(std::log10(emax)), ly0 + 1);
  const auto X = [&](double ms) { return left + (std::log10(ms) - lx0) / (lx1 - lx0) * (plot_right - left); };
  const auto Y = [&](double e) { return H - bottom - (std::log10(e) - ly0) / (ly1 - ly0) * (H - top - bottom); };
  const cv::Scalar grey(200, 200, 200), light(235, 235, 235), black(0, 0, 0), blue(180, 90, 20), red(30, 30, 220);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  for (double d = lx0; d <= lx1; d += 1)
    for (double m : {1.0, 2.0, 5.0}) {
      const double ms = m * std::pow(10.0, d);
      if (std::log10(ms) > lx1 + 1e-9) continue;
      const int x = static_cast<int>(X(ms));
      cv::line(img, {x, top}, {x, H - bottom}, m == 1 ? grey : light, 1);
      cv::putText(img, fmt::format("{:g}", ms), {x - 10, H - bottom + 18}, font, 0.45, black, 1, cv::LINE_AA);
    }
  for (double d = ly0; d <= ly1; d += 1)
    for (double m : {1.0, 2.0, 5.0}) {
      const double e = m * std::pow(10.0, d);
      if (std::log10(e) > ly1 + 1e-9) continue;
      const int y = static_cast<int>(Y(e));
      cv::line(img, {left, y}, {plot_right, y}, m == 1 ? grey : light, 1);
      cv::putText(img, fmt::format("{:g}", e), {left - 45, y + 5}, font, 0.45, black, 1, cv::LINE_AA);
    }
  cv::rectangle(img, {left, top}, {plot_right, H - bottom}, black, 1);
  cv::putText(img, "correction time per frame (ms, log scale)", {left + 250, H - 25}, font, 0.55, black, 1, cv::LINE_AA);
  cv::putText(img, "PIV RMS error vs truth (px, log scale)", {10, top - 12}, font, 0.55, black, 1, cv::LINE_AA);
  cv::putText(img, title, {left + 380, top - 12}, font, 0.5, black, 1, cv::LINE_AA);
  if (no_glass_px > 0) {
    const int y = static_cast<int>(Y(no_glass_px));
    for (int x = left; x < plot_right; x += 12) cv::line(img, {x, y}, {std::min(x + 6, plot_right), y}, blue, 1);
    cv::putText(img, fmt::format("no glass {:.3f} px", no_glass_px), {plot_right - 150, y - 6}, font, 0.45, blue, 1, cv::LINE_AA);
  }
  for (std::size_t k = 1; k < front.size(); ++k) {
    const ChainRow &a = rows[front[k - 1]], &b = rows[front[k]];
    cv::line(img, {int(X(a.frame_ms)), int(Y(a.error.rms_px))}, {int(X(b.frame_ms)), int(Y(b.error.rms_px))}, red, 2,
             cv::LINE_AA);
  }
  int legend_y = top + 10;
  cv::putText(img, "settings (red: on the Pareto front; ringed: default)", {plot_right + 15, legend_y}, font, 0.42,
              black, 1, cv::LINE_AA);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const ChainRow& r = rows[i];
    const bool on = on_front(front, i);
    const std::string id = std::to_string(i + 1);
    legend_y += 22;
    const bool named = r.setting.label.find("default") != std::string::npos;
    cv::putText(img, id + "  " + r.setting.label + (r.setting.is_default && !named ? " (default)" : ""),
                {plot_right + 15, legend_y}, font, 0.42, on ? red : black, 1, cv::LINE_AA);
    if (!std::isfinite(r.error.rms_px)) continue;
    const cv::Point p(int(X(r.frame_ms)), int(Y(r.error.rms_px)));
    cv::circle(img, p, 4, on ? red : black, cv::FILLED, cv::LINE_AA);
    if (r.setting.is_default) cv::circle(img, p, 9, red, 2, cv::LINE_AA);
    // Numbers fanned around the point so that neighbours stay readable.
    const int k = static_cast<int>(i % 4);
    const cv::Point off = k == 0 ? cv::Point(6, -6) : k == 1 ? cv::Point(6, 16) : k == 2 ? cv::Point(-20, -6) : cv::Point(-20, 16);
    cv::putText(img, id, p + off, font, 0.42, on ? red : black, 1, cv::LINE_AA);
  }
  return img;
}


}  // namespace glasspiv
