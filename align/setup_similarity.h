#pragma once
// How well a render of the setup (render/setup_render.h) agrees with a photo of
// it: intensity NCC, gradient-magnitude NCC (the smooth score an optimiser
// maximises) and a robust symmetric chamfer distance between their edges (the
// figure a user reads, in px). Marker-corner distances are computed elsewhere.
// No I/O.
//
// Both images are CV_32FC1 of one size, values typically in [0, 1] (non-finite
// photo pixels are ignored like masked ones; a render must be finite); pixel
// (0, 0) is the centre of the top-left pixel (docs/conventions.md). The photo
// side is prepared once (PhotoEdgeModel); each evaluation then processes only
// the new render.
//
// Edges (both images alike, so that neither exposure nor gain matters):
//  1. Gaussian blur, sigma edge_blur_px (kernel radius ceil(3 sigma), borders
//     replicated); gradient by central differences, magnitude |g| in image
//     units per px.
//  2. Canny-style non-maximum suppression across the edge (direction rounded
//     to the nearest of 4), then hysteresis (8-connected): high threshold =
//     edge_threshold x the edge_reference_percentile of the image's own |g|
//     over the compared pixels, low = edge_low_ratio x high, neither below
//     edge_min_gradient_per_px.
//  3. Sub-pixel position: a Gaussian (parabola in log |g|) through |g| at the
//     pixel and its two neighbours across the edge; exact for a blurred straight
//     step, whose |g| profile is Gaussian.
//
// Chamfer distance, sub-pixel: each edge point stands for a 1 px long piece of
// its edge (the segment through the sub-pixel point along the edge tangent),
// and the distance from a point to an edge set is the distance to the nearest
// such segment, found in a bucket grid (exact within the cutoff, no distance
// transform). For a straight edge this is the perpendicular distance to the
// edge, free of the 0.5 px quantisation of a distance transform on whole pixels.
#include <vector>

#include <opencv2/core.hpp>

namespace glasspiv {

struct SimilarityOptions {
  double edge_blur_px = 1.5;  // Gaussian sigma before the gradients (both images); 0 = none
  // Hysteresis thresholds relative to the image's own gradient distribution:
  // high = edge_threshold x percentile(|g|, edge_reference_percentile), low =
  // edge_low_ratio x high. Scaling an image scales both, so exposure drops out.
  double edge_threshold = 0.3;
  double edge_reference_percentile = 98;
  double edge_low_ratio = 0.5;
  // Absolute floor on both thresholds (image units per px): a flat image (a
  // render where the model leaves the view) gets no edges from rounding noise.
  // 1e-4 is 0.03 grey levels of 8 bit per px, far below any real edge.
  double edge_min_gradient_per_px = 1e-4;
  double chamfer_cutoff_px = 10;  // distances beyond this count as this (robust to clutter)

  void check() const;  // std::invalid_argument on a value out of range
};

struct Similarity {
  double ncc = 0;           // NCC of the intensities over valid pixels, [-1, 1]; 0 if either is flat
  double gradient_ncc = 0;  // NCC of the blurred gradient magnitudes: edge agreement, lighting-free, smooth in the pose
  // Symmetric robust edge distance (px): the mean of the two directed ones. A
  // direction with no edge points to measure from counts as the cutoff.
  double chamfer_px = 0;
  double chamfer_render_to_photo_px = 0, chamfer_photo_to_render_px = 0;
  long render_edge_pixels = 0, photo_edge_pixels = 0, valid_pixels = 0;
};

struct EdgePoint {
  float x_px = 0, y_px = 0;            // sub-pixel position on the edge
  float normal_x = 0, normal_y = 0;    // unit gradient direction (dark to bright)
  float gradient_per_px = 0;           // |g| at the pixel
};

// Edge points of one image (the steps above), in raster order of their pixels.
// mask8u as PhotoEdgeModel's.
std::vector<EdgePoint> detect_edges(const cv::Mat& image32f, const SimilarityOptions& options = {},
                                    const cv::Mat& mask8u = cv::Mat());

// Nearest-edge queries on a fixed set of edge points, truncated at a cutoff.
class EdgeDistanceIndex {
 public:
  EdgeDistanceIndex() = default;
  EdgeDistanceIndex(std::vector<EdgePoint> points, cv::Size image_size, double cutoff_px);
  // Distance (px) from (x, y) to the nearest edge segment, min(distance, cutoff).
  double distance_px(double x_px, double y_px) const;
  // Mean truncated distance from `from` to this set; the cutoff if `from` is empty.
  double mean_distance_px(const std::vector<EdgePoint>& from) const;
  const std::vector<EdgePoint>& points() const { return points_; }

 private:
  struct Packed { float x, y, nx, ny; };
  std::vector<EdgePoint> points_;  // sorted by cell
  std::vector<Packed> packed_;     // the same, what the search reads
  std::vector<int> cell_start_;    // cells_x_ * cells_y_ + 1 offsets into points_
  int cells_x_ = 0, cells_y_ = 0;
  double cell_px_ = 2, cutoff_px_ = 10;
};

// Buffers of one evaluation (9 bytes per pixel), kept between calls so that an
// optimiser's evaluations allocate nothing; one per thread.
struct SimilarityWorkspace {
  cv::Mat blurred, gradient, flags;
};

// The photo side, built once: its blurred gradient magnitude with the sums the
// NCCs need, its edges and their distance index. compare() is const and keeps
// no state, so one model serves parallel evaluations.
class PhotoEdgeModel {
 public:
  // mask8u: optional, same size, nonzero = compare. It is shrunk by the filter
  // support (blur radius + 2 px) so that ignored pixels cannot leak into the
  // compared ones; the outer 1 px frame is never compared (no central
  // difference there). A mask that moves with the pose means a new model.
  // Throws std::invalid_argument for a wrong type or size, or bad options.
  explicit PhotoEdgeModel(const cv::Mat& photo32f, const SimilarityOptions& options = {},
                          const cv::Mat& mask8u = cv::Mat());

  // Throws std::invalid_argument unless render32f is CV_32FC1 of the photo's size.
  // With a workspace kept by the caller nothing is allocated per call (at 1 MP
  // fresh buffers cost more than the evaluation itself); results are identical.
  Similarity compare(const cv::Mat& render32f) const;
  Similarity compare(const cv::Mat& render32f, SimilarityWorkspace& workspace) const;

  cv::Size size() const { return size_; }
  const SimilarityOptions& options() const { return options_; }
  const cv::Mat& valid_mask() const { return valid_; }          // CV_8U, 255 = compared
  const cv::Mat& gradient_magnitude() const { return grad_; }  // CV_32F, blurred photo, per px
  const std::vector<EdgePoint>& edges() const { return edges_.points(); }

 private:
  struct Run { int y, x0, x1; };  // valid pixels [x0, x1) of row y
  SimilarityOptions options_;
  cv::Size size_;
  cv::Mat photo_, grad_, valid_;
  std::vector<Run> runs_;
  long valid_pixels_ = 0;
  double sum_p_ = 0, sum_pp_ = 0, sum_g_ = 0, sum_gg_ = 0;
  EdgeDistanceIndex edges_;

  friend struct SimilarityDetail;
};

// The feature gradient_ncc compares: |gradient| by central differences of the
// image blurred by sigma_px (0 on the outer 1 px frame). For callers that
// compare per pixel (align/align_refine.h's least squares).
cv::Mat blurred_gradient_magnitude(const cv::Mat& image32f, double sigma_px);

// One-off comparison (builds a PhotoEdgeModel); mask8u as there.
Similarity compare_render_to_photo(const cv::Mat& render32f, const cv::Mat& photo32f,
                                   const SimilarityOptions& options = {}, const cv::Mat& mask8u = cv::Mat());

}  // namespace glasspiv
