#pragma once
// Pictures of a render of the setup against its photo, for a user to judge an
// alignment by eye: BGR 8-bit, the photo's size. Each image is stretched on
// its own robust range (percentiles), so a dark render and a bright photo both
// show. No I/O: the caller writes the file.
#include <opencv2/core.hpp>

#include "align/setup_similarity.h"

namespace glasspiv {

struct OverlayOptions {
  double low_percentile = 1, high_percentile = 99;  // of each image's finite values, mapped to 0 and 255
  SimilarityOptions edges;                          // how overlay_edges finds edges (as the score does)
  bool draw_photo_edges = true;                     // overlay_edges: the photo's edges too
};

// CV_8UC1: (v - lo) * 255 / (hi - lo), rounded and clipped, lo and hi the
// percentiles of the finite values; NaN and inf are 0; a flat image is 128.
cv::Mat normalise_robust_8u(const cv::Mat& image32f, double low_percentile = 1, double high_percentile = 99);

// Render in blue + red (magenta), photo in green: where they agree the picture
// is grey, a misalignment shows as magenta and green fringes.
cv::Mat overlay_blend(const cv::Mat& render32f, const cv::Mat& photo32f, const OverlayOptions& options = {});

// The photo in grey; its edge pixels in green (if draw_photo_edges), the
// render's in magenta, pixels on both edges in yellow.
cv::Mat overlay_edges(const cv::Mat& render32f, const cv::Mat& photo32f, const OverlayOptions& options = {});

// Square tiles of tile_px alternating photo (the tile at the top-left) and
// render, both in grey: edges that jump at tile borders are misaligned.
cv::Mat overlay_checker(const cv::Mat& render32f, const cv::Mat& photo32f, int tile_px,
                        const OverlayOptions& options = {});

// The BGR colours used above.
inline const cv::Vec3b kOverlayRenderEdgeBgr(255, 0, 255), kOverlayPhotoEdgeBgr(0, 255, 0),
    kOverlayBothEdgesBgr(0, 255, 255);

}  // namespace glasspiv
