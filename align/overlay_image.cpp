#include "align/overlay_image.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace glasspiv {

namespace {

void check_pair(const cv::Mat& render, const cv::Mat& photo) {
  if (render.empty() || photo.empty() || render.type() != CV_32FC1 || photo.type() != CV_32FC1)
    throw std::invalid_argument("overlay: render and photo must be non-empty CV_32FC1 images");
  if (render.size() != photo.size()) throw std::invalid_argument("overlay: render and photo differ in size");
}

// Percentile by linear interpolation between order statistics (numpy's default).
double percentile_of(std::vector<float>& values, double percentile) {
  const double rank = std::clamp(percentile, 0.0, 100.0) / 100.0 * double(values.size() - 1);
  const std::size_t lo = std::size_t(std::floor(rank));
  std::nth_element(values.begin(), values.begin() + lo, values.end());
  const double v_lo = values[lo];
  if (lo + 1 >= values.size()) return v_lo;
  const double v_hi = *std::min_element(values.begin() + lo + 1, values.end());
  return v_lo + (rank - double(lo)) * (v_hi - v_lo);
}

}  // namespace

cv::Mat normalise_robust_8u(const cv::Mat& image32f, double low_percentile, double high_percentile) {
  if (image32f.empty() || image32f.type() != CV_32FC1)
    throw std::invalid_argument("normalise_robust_8u: image must be a non-empty CV_32FC1 image");
  if (!(low_percentile >= 0 && low_percentile < high_percentile && high_percentile <= 100))
    throw std::invalid_argument("normalise_robust_8u: need 0 <= low_percentile < high_percentile <= 100");
  cv::Mat finite = image32f.clone();
  std::vector<float> values;
  values.reserve(finite.total());
  for (int y = 0; y < finite.rows; ++y) {
    float* row = finite.ptr<float>(y);
    for (int x = 0; x < finite.cols; ++x) {
      if (std::isfinite(row[x])) {
        values.push_back(row[x]);
      } else {
        row[x] = 0;
      }
    }
  }
  cv::Mat out(image32f.size(), CV_8U, cv::Scalar(0));
  if (values.empty()) return out;
  const double lo = percentile_of(values, low_percentile);
  const double hi = percentile_of(values, high_percentile);
  if (!(hi > lo)) {  // flat: mid grey where finite
    for (int y = 0; y < out.rows; ++y)
      for (int x = 0; x < out.cols; ++x)
        if (std::isfinite(image32f.at<float>(y, x))) out.at<std::uint8_t>(y, x) = 128;
    return out;
  }
  const double scale = 255.0 / (hi - lo);
  finite.convertTo(out, CV_8U, scale, -lo * scale);
  for (int y = 0; y < out.rows; ++y)  // non-finite pixels are 0, not wherever -lo maps
    for (int x = 0; x < out.cols; ++x)
      if (!std::isfinite(image32f.at<float>(y, x))) out.at<std::uint8_t>(y, x) = 0;
  return out;
}

cv::Mat overlay_blend(const cv::Mat& render32f, const cv::Mat& photo32f, const OverlayOptions& options) {
  check_pair(render32f, photo32f);
  const cv::Mat r = normalise_robust_8u(render32f, options.low_percentile, options.high_percentile);
  const cv::Mat p = normalise_robust_8u(photo32f, options.low_percentile, options.high_percentile);
  cv::Mat out;
  cv::merge(std::vector<cv::Mat>{r, p, r}, out);
  return out;
}

cv::Mat overlay_edges(const cv::Mat& render32f, const cv::Mat& photo32f, const OverlayOptions& options) {
  check_pair(render32f, photo32f);
  cv::Mat out;
  cv::cvtColor(normalise_robust_8u(photo32f, options.low_percentile, options.high_percentile), out,
               cv::COLOR_GRAY2BGR);
  const auto pixel_of = [&](const EdgePoint& p, cv::Point* at) {
    at->x = int(std::lround(p.x_px));
    at->y = int(std::lround(p.y_px));
    return at->x >= 0 && at->y >= 0 && at->x < out.cols && at->y < out.rows;
  };
  cv::Point at;
  if (options.draw_photo_edges)
    for (const EdgePoint& p : detect_edges(photo32f, options.edges))
      if (pixel_of(p, &at)) out.at<cv::Vec3b>(at) = kOverlayPhotoEdgeBgr;
  for (const EdgePoint& p : detect_edges(render32f, options.edges)) {
    if (!pixel_of(p, &at)) continue;
    cv::Vec3b& px = out.at<cv::Vec3b>(at);
    px = (options.draw_photo_edges && px == kOverlayPhotoEdgeBgr) ? kOverlayBothEdgesBgr : kOverlayRenderEdgeBgr;
  }
  return out;
}

cv::Mat overlay_checker(const cv::Mat& render32f, const cv::Mat& photo32f, int tile_px,
                        const OverlayOptions& options) {
  check_pair(render32f, photo32f);
  if (tile_px < 1) throw std::invalid_argument("overlay_checker: tile_px must be at least 1");
  const cv::Mat r = normalise_robust_8u(render32f, options.low_percentile, options.high_percentile);
  const cv::Mat p = normalise_robust_8u(photo32f, options.low_percentile, options.high_percentile);
  cv::Mat grey(p.size(), CV_8U);
  for (int y = 0; y < grey.rows; ++y)
    for (int x = 0; x < grey.cols; ++x)
      grey.at<std::uint8_t>(y, x) = ((x / tile_px + y / tile_px) % 2 == 0) ? p.at<std::uint8_t>(y, x)
                                                                            : r.at<std::uint8_t>(y, x);
  cv::Mat out;
  cv::cvtColor(grey, out, cv::COLOR_GRAY2BGR);
  return out;
}

}  // namespace glasspiv
