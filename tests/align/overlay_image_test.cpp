// Overlay pictures of a render against a photo: sizes and types, the robust
// stretch, the checker's tiles pixel for pixel, grey where the images agree.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "align/overlay_image.h"

namespace glasspiv {
namespace {

cv::Mat scene(float scale, float offset) {  // a disc and a bar on a ramp, values scale * [0, 1] + offset
  cv::Mat img(120, 160, CV_32F);
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) img.at<float>(y, x) = 0.3f * x / img.cols;
  cv::circle(img, {60, 55}, 25, cv::Scalar(0.9), cv::FILLED);
  cv::rectangle(img, cv::Rect(100, 20, 30, 80), cv::Scalar(0.1), cv::FILLED);
  cv::GaussianBlur(img, img, cv::Size(0, 0), 0.8);
  return img * scale + offset;
}

TEST(OverlayImage, SizesAndTypes) {
  const cv::Mat render = scene(1, 0), photo = scene(1, 0);
  for (const cv::Mat& out :
       {overlay_blend(render, photo), overlay_edges(render, photo), overlay_checker(render, photo, 16)}) {
    EXPECT_EQ(out.type(), CV_8UC3);
    EXPECT_EQ(out.size(), photo.size());
  }
  EXPECT_THROW(overlay_blend(render, photo(cv::Rect(0, 0, 50, 50)).clone()), std::invalid_argument);
  EXPECT_THROW(overlay_edges(render, cv::Mat()), std::invalid_argument);
  cv::Mat d;
  photo.convertTo(d, CV_64F);
  EXPECT_THROW(overlay_checker(render, d, 8), std::invalid_argument);
  EXPECT_THROW(overlay_checker(render, photo, 0), std::invalid_argument);
}

// A render 20 times darker than the photo (and offset) shows the same: each is
// stretched on its own 1st..99th percentiles.
TEST(OverlayImage, DarkAndBrightImagesStretchAlike) {
  const cv::Mat bright = normalise_robust_8u(scene(1, 0));
  const cv::Mat dark = normalise_robust_8u(scene(0.05f, 0.01f));
  cv::Mat diff;
  cv::absdiff(bright, dark, diff);
  double worst = 0;
  cv::minMaxLoc(diff, nullptr, &worst);
  EXPECT_LE(worst, 1);  // float rounding may flip a level
  double lo = 0, hi = 0;
  cv::minMaxLoc(bright, &lo, &hi);
  EXPECT_EQ(lo, 0);
  EXPECT_EQ(hi, 255);
  // Non-finite values are black and do not spoil the range; a flat image is mid grey.
  cv::Mat holes = scene(1, 0);
  holes.at<float>(3, 4) = std::numeric_limits<float>::quiet_NaN();
  holes.at<float>(5, 6) = std::numeric_limits<float>::infinity();
  const cv::Mat n = normalise_robust_8u(holes);
  EXPECT_EQ(n.at<uchar>(3, 4), 0);
  EXPECT_EQ(n.at<uchar>(5, 6), 0);
  EXPECT_EQ(cv::countNonZero(normalise_robust_8u(cv::Mat(4, 4, CV_32F, cv::Scalar(0.3))) != 128), 0);
}

TEST(OverlayImage, CheckerAlternatesPhotoAndRenderTilesExactly) {
  const cv::Mat render = scene(0.5f, 0.2f);
  cv::Mat photo;
  cv::flip(scene(1, 0), photo, 1);  // different content, so every tile tells which image it shows
  const int tile = 13;              // not a divisor of the size: partial tiles at the borders
  const cv::Mat out = overlay_checker(render, photo, tile);
  const cv::Mat r = normalise_robust_8u(render), p = normalise_robust_8u(photo);
  long photo_px = 0, render_px = 0;
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      const bool photo_tile = (x / tile + y / tile) % 2 == 0;
      const uchar want = photo_tile ? p.at<uchar>(y, x) : r.at<uchar>(y, x);
      const cv::Vec3b got = out.at<cv::Vec3b>(y, x);
      ASSERT_EQ(got, cv::Vec3b(want, want, want)) << x << ", " << y;
      (photo_tile ? photo_px : render_px) += 1;
    }
  EXPECT_GT(photo_px, 0);
  EXPECT_GT(render_px, 0);
  EXPECT_EQ(out.at<cv::Vec3b>(0, 0)[0], p.at<uchar>(0, 0));  // the top-left tile is the photo's
}

TEST(OverlayImage, BlendOfIdenticalImagesIsGreyAndMisalignmentIsColoured) {
  const cv::Mat img = scene(1, 0);
  const cv::Mat same = overlay_blend(img, img * 3 + 0.5f);  // gain and offset drop out too
  for (int y = 0; y < same.rows; ++y)
    for (int x = 0; x < same.cols; ++x) {
      const cv::Vec3b v = same.at<cv::Vec3b>(y, x);
      ASSERT_LE(std::abs(v[0] - v[1]), 1) << x << ", " << y;
      ASSERT_EQ(v[0], v[2]);
    }
  const cv::Mat exact = overlay_blend(img, img);
  std::vector<cv::Mat> ch;
  cv::split(exact, ch);
  EXPECT_EQ(cv::countNonZero(ch[0] != ch[1]), 0);
  EXPECT_EQ(cv::countNonZero(ch[1] != ch[2]), 0);

  // Render moved right by 3 px: at the disc's left edge the photo is bright
  // and the render dark (green), at its right edge the other way (magenta).
  const cv::Mat m = (cv::Mat_<double>(2, 3) << 1, 0, 3, 0, 1, 0);
  cv::Mat moved;
  cv::warpAffine(img, moved, m, img.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  const cv::Mat fringe = overlay_blend(moved, img);
  const cv::Vec3b left = fringe.at<cv::Vec3b>(55, 36), right = fringe.at<cv::Vec3b>(55, 86);
  EXPECT_GT(left[1], left[0] + 60);   // green over magenta
  EXPECT_GT(right[0], right[1] + 60); // magenta over green
  EXPECT_EQ(right[0], right[2]);
}

TEST(OverlayImage, EdgesAreDrawnOverTheGreyPhoto) {
  const cv::Mat photo = scene(1, 0);
  const cv::Mat m = (cv::Mat_<double>(2, 3) << 1, 0, 4, 0, 1, 0);
  cv::Mat render;
  cv::warpAffine(photo, render, m, photo.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  OverlayOptions options;
  const cv::Mat out = overlay_edges(render, photo, options);
  const auto count = [&](const cv::Mat& img, const cv::Vec3b& c) {
    long n = 0;
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x) n += img.at<cv::Vec3b>(y, x) == c;
    return n;
  };
  const long render_edges = long(detect_edges(render).size()), photo_edges = long(detect_edges(photo).size());
  EXPECT_GT(count(out, kOverlayRenderEdgeBgr), render_edges / 2);
  EXPECT_GT(count(out, kOverlayPhotoEdgeBgr), photo_edges / 2);
  EXPECT_LE(count(out, kOverlayRenderEdgeBgr) + count(out, kOverlayBothEdgesBgr), render_edges);
  // Off the edges the picture is the grey photo.
  const cv::Mat p = normalise_robust_8u(photo);
  EXPECT_EQ(out.at<cv::Vec3b>(55, 60), cv::Vec3b(p.at<uchar>(55, 60), p.at<uchar>(55, 60), p.at<uchar>(55, 60)));

  options.draw_photo_edges = false;
  const cv::Mat only_render = overlay_edges(render, photo, options);
  EXPECT_EQ(count(only_render, kOverlayPhotoEdgeBgr), 0);
  EXPECT_EQ(count(only_render, kOverlayRenderEdgeBgr), render_edges);  // one point per pixel
}

}  // namespace
}  // namespace glasspiv
