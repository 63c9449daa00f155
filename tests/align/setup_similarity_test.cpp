// Render-versus-photo scores on synthetic scenes drawn with OpenCV: the "photo"
// is the "render" moved by a known sub-pixel shift (cubic warpAffine), with a
// gain, an offset and noise of 0.5/255. Independent references: the shift
// itself (a straight edge moved by s lies s away), first-order edge geometry
// (an edge with unit normal n moved by s lies |s . n| away), and a brute-force
// nearest-segment search for the bucket index.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "align/setup_similarity.h"

namespace glasspiv {
namespace {

// Discs, rectangles and a rotated square on a shaded background, slightly
// blurred as optics would; `scale` stretches the 400 x 300 layout.
cv::Mat scene(double scale = 1) {
  const int w = int(std::lround(400 * scale)), h = int(std::lround(300 * scale));
  cv::Mat img(h, w, CV_32F);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at<float>(y, x) = float(0.25 + 0.15 * x / w + 0.05 * y / h);
  const auto s = [&](double v) { return int(std::lround(v * scale)); };
  cv::circle(img, {s(100), s(95)}, s(45), cv::Scalar(0.85), cv::FILLED);
  cv::circle(img, {s(290), s(205)}, s(38), cv::Scalar(0.08), cv::FILLED);
  cv::rectangle(img, cv::Rect(s(190), s(35), s(130), s(70)), cv::Scalar(0.65), cv::FILLED);
  const std::vector<cv::Point> square{{s(70), s(200)}, {s(125), s(175)}, {s(150), s(230)}, {s(95), s(255)}};
  cv::fillConvexPoly(img, square, cv::Scalar(0.5));
  // Smooth shading over everything (lighting falls off to the right and down).
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img.at<float>(y, x) *= float(0.85 + 0.15 * std::cos(2.0 * x / w) * std::cos(1.5 * y / h));
  cv::GaussianBlur(img, img, cv::Size(0, 0), 0.8 * scale);
  return img;
}

// A single vertical step at x = 120 px, 0.2 to 0.7.
cv::Mat straight_edge() {
  cv::Mat img(200, 256, CV_32F, cv::Scalar(0.2));
  img.colRange(120, 256).setTo(0.7);
  cv::GaussianBlur(img, img, cv::Size(0, 0), 0.8);
  return img;
}

cv::Mat shifted(const cv::Mat& img, double dx_px, double dy_px) {
  const cv::Mat m = (cv::Mat_<double>(2, 3) << 1, 0, dx_px, 0, 1, dy_px);
  cv::Mat out;
  cv::warpAffine(img, out, m, img.size(), cv::INTER_CUBIC, cv::BORDER_REPLICATE);
  return out;
}

cv::Mat as_photo(const cv::Mat& img, double gain, double offset, double noise_sigma, int seed) {
  cv::Mat out = img * gain + offset;
  if (noise_sigma > 0) {
    cv::Mat noise(img.size(), CV_32F);
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::NORMAL, 0, noise_sigma);
    out += noise;
  }
  return out;
}

constexpr double kNoise = 0.5 / 255;
const double kDirX = 0.8, kDirY = 0.6;  // unit shift direction, oblique to every edge of the scene

TEST(SetupSimilarity, IdenticalImagesAgreePerfectly) {
  const cv::Mat img = scene();
  const Similarity s = compare_render_to_photo(img, img);
  EXPECT_NEAR(s.ncc, 1, 1e-12);
  EXPECT_NEAR(s.gradient_ncc, 1, 1e-12);
  EXPECT_NEAR(s.chamfer_px, 0, 1e-9);
  EXPECT_GT(s.render_edge_pixels, 1000);
  EXPECT_EQ(s.render_edge_pixels, s.photo_edge_pixels);
  EXPECT_EQ(s.valid_pixels, long(img.cols - 2) * (img.rows - 2));  // the 1 px frame is never compared
}

// The sub-pixel edge position on an exactly drawn edge (erf profile, as a step
// blurred by a Gaussian of sigma 0.8 px): the Gaussian peak fit across the
// edge is exact for it, to 1e-3 px (measured 2e-4), at any phase.
TEST(SetupSimilarity, EdgePointsLieOnAnAnalyticEdge) {
  for (double edge_x = 119.5; edge_x <= 120.5; edge_x += 0.125) {
    cv::Mat img(40, 256, CV_32F);
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x)
        img.at<float>(y, x) = float(0.2 + 0.25 * (1 + std::erf((x - edge_x) / (0.8 * std::sqrt(2.0)))));
    const std::vector<EdgePoint> edges = detect_edges(img);
    ASSERT_EQ(edges.size(), 38u);
    for (const EdgePoint& p : edges) {
      EXPECT_NEAR(p.x_px, edge_x, 1e-3);
      EXPECT_NEAR(p.normal_x, 1, 1e-6);
    }
  }
}

// A straight edge moved by s lies s away from the original. Tolerance 0.05 px:
// the edge points themselves are exact (above), and the noise of 0.5/255
// against a step of 0.35 moves them by well under 0.01 px, but cubic
// warpAffine (OpenCV's a = -0.75 kernel) reshapes the steep edge: the shifted
// edge lands up to 0.03 px off at phases 1/4 and 3/4, exact at 0 and 1/2.
TEST(SetupSimilarity, ChamferOfAShiftedStraightEdgeIsTheShift) {
  const cv::Mat render = straight_edge();
  std::printf("straight edge: shift_px chamfer_px r_to_p p_to_r\n");
  for (const double s_px : {0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0}) {
    const cv::Mat photo = as_photo(shifted(render, s_px, 0), 0.7, 0.1, kNoise, 7);
    const Similarity s = compare_render_to_photo(render, photo);
    std::printf("  %.2f %.4f %.4f %.4f\n", s_px, s.chamfer_px, s.chamfer_render_to_photo_px,
                s.chamfer_photo_to_render_px);
    EXPECT_NEAR(s.chamfer_px, s_px, 0.05) << "shift " << s_px;
    EXPECT_NEAR(s.chamfer_render_to_photo_px, s_px, 0.05) << "shift " << s_px;
    EXPECT_NEAR(s.chamfer_photo_to_render_px, s_px, 0.05) << "shift " << s_px;
    EXPECT_NEAR(double(s.render_edge_pixels), 198, 2);  // one point per row inside the frame
  }
}

// Chamfer grows monotonically with the shift and measures it: to first order
// an edge point with normal n moved by s lies |s . n| from its old edge, so the
// expected chamfer is s times the mean |d . n| over the render's edge points.
TEST(SetupSimilarity, ChamferGrowsWithTheShiftAndMeasuresIt) {
  const cv::Mat render = scene();
  const std::vector<EdgePoint> edges = detect_edges(render);
  double mean_projection = 0;
  for (const EdgePoint& p : edges) mean_projection += std::abs(kDirX * p.normal_x + kDirY * p.normal_y);
  mean_projection /= double(edges.size());
  double previous = -1;
  std::printf("scene: shift_px chamfer_px expected_px gradient_ncc ncc\n");
  for (int i = 0; i <= 12; ++i) {
    const double s_px = 0.25 * i;
    const cv::Mat photo = as_photo(shifted(render, s_px * kDirX, s_px * kDirY), 1.3, -0.05, kNoise, 11);
    const Similarity s = compare_render_to_photo(render, photo);
    const double expected = s_px * mean_projection;
    std::printf("  %.2f %.4f %.4f %.6f %.6f\n", s_px, s.chamfer_px, expected, s.gradient_ncc, s.ncc);
    EXPECT_GT(s.chamfer_px, previous + 0.05) << "shift " << s_px;
    EXPECT_NEAR(s.chamfer_px, expected, 0.05 + 0.1 * expected) << "shift " << s_px;
    previous = s.chamfer_px;
  }
}

TEST(SetupSimilarity, GradientNccIgnoresGainAndOffset) {
  const cv::Mat render = scene();
  for (const double s_px : {0.0, 0.7, 2.0}) {
    const cv::Mat moved = shifted(render, s_px * kDirX, s_px * kDirY);
    const Similarity plain = compare_render_to_photo(render, moved);
    const Similarity lit = compare_render_to_photo(render, as_photo(moved, 0.45, 0.3, 0, 0));
    EXPECT_NEAR(lit.gradient_ncc, plain.gradient_ncc, 1e-6) << "shift " << s_px;
    EXPECT_NEAR(lit.ncc, plain.ncc, 1e-6) << "shift " << s_px;
    if (s_px == 0) {
      EXPECT_NEAR(lit.gradient_ncc, 1, 1e-6);
    }
  }
}

// What makes gradient_ncc usable by an optimiser: over 0..3 px in steps of
// 0.25 px it falls at every step, and its slope changes gradually. The curve
// is a smooth peak at 0 (slope 0 there, so the first step is the smallest); a
// plateau would show as a step near 0 further out, a kink as a second
// difference as large as the steps themselves.
TEST(SetupSimilarity, GradientNccFallsSmoothlyWithTheShift) {
  const cv::Mat render = scene();
  const PhotoEdgeModel model(render);  // render and photo swap roles: the shift is symmetric
  std::vector<double> curve;
  for (int i = 0; i <= 12; ++i) {
    const double s_px = 0.25 * i;
    const cv::Mat photo = as_photo(shifted(render, s_px * kDirX, s_px * kDirY), 0.8, 0.1, kNoise, 3);
    curve.push_back(model.compare(photo).gradient_ncc);
  }
  std::printf("gradient_ncc over shift 0..3 px by 0.25:");
  for (const double v : curve) std::printf(" %.4f", v);
  std::printf("\n");
  double largest_step = 0;
  for (int i = 1; i <= 12; ++i) {
    const double step = curve[i - 1] - curve[i];
    EXPECT_GT(step, 2e-3) << "plateau at " << 0.25 * i << " px";
    if (i >= 2) {
      EXPECT_GT(step, 0.5 * (curve[i - 2] - curve[i - 1])) << "slope collapses at " << 0.25 * i << " px";
    }
    largest_step = std::max(largest_step, step);
  }
  for (int i = 1; i < 12; ++i)
    EXPECT_LT(std::abs(curve[i + 1] - 2 * curve[i] + curve[i - 1]), 0.5 * largest_step)
        << "kink at " << 0.25 * i << " px";
  EXPECT_GT(curve[0], 0.99);
  EXPECT_LT(curve[12], 0.8);
}

// A corrupted patch of the photo (bright blobs where the model shows nothing)
// is ignored through the mask: the scores equal those of the clean photo under
// the same mask, to rounding, because the mask is shrunk by the filter support.
TEST(SetupSimilarity, MaskExcludesACorruptedRegion) {
  const cv::Mat render = scene();
  const cv::Mat photo = as_photo(shifted(render, 0.6, -0.3), 1.1, 0.02, kNoise, 5);
  cv::Mat corrupted = photo.clone();
  const cv::Rect bad(150, 120, 90, 60);
  cv::RNG rng(9);
  for (int i = 0; i < 25; ++i) {  // blobs wholly inside `bad`
    const int r = rng.uniform(3, 12);
    const int x = rng.uniform(bad.x + r, bad.x + bad.width - r), y = rng.uniform(bad.y + r, bad.y + bad.height - r);
    const cv::Point centre(x, y);
    cv::circle(corrupted, centre, r, cv::Scalar(rng.uniform(0.0, 1.0)), cv::FILLED);
  }
  cv::Mat mask(render.size(), CV_8U, cv::Scalar(255));
  mask(bad).setTo(0);

  const Similarity clean = compare_render_to_photo(render, photo, {}, mask);
  const Similarity masked = compare_render_to_photo(render, corrupted, {}, mask);
  const Similarity unmasked = compare_render_to_photo(render, corrupted);
  EXPECT_NEAR(masked.ncc, clean.ncc, 1e-12);
  EXPECT_NEAR(masked.gradient_ncc, clean.gradient_ncc, 1e-12);
  EXPECT_NEAR(masked.chamfer_px, clean.chamfer_px, 1e-12);
  EXPECT_EQ(masked.photo_edge_pixels, clean.photo_edge_pixels);
  EXPECT_LT(masked.valid_pixels, long(render.total()) - bad.area());
  // Without the mask the blobs do matter.
  EXPECT_LT(unmasked.gradient_ncc, clean.gradient_ncc - 0.05);
  EXPECT_GT(unmasked.chamfer_px, clean.chamfer_px + 0.3);
}

// Clutter (extra blobs in the photo, away from the model's edges) can only add
// photo edge points, each of which counts at most the cutoff: the photo-to-render
// distance rises by at most cutoff x the clutter's share of the photo edges, the
// render-to-photo one does not rise. Without a cutoff the same clutter costs far more.
TEST(SetupSimilarity, ClutterMovesTheChamferLessThanTheCutoffBounds) {
  const cv::Mat render = scene();
  const cv::Mat photo = as_photo(shifted(render, 0.8, 0.6), 1.0, 0.0, kNoise, 21);
  cv::Mat cluttered = photo.clone();
  const std::vector<EdgePoint> model_edges = detect_edges(render);
  cv::RNG rng(17);
  for (int placed = 0; placed < 40;) {
    const int x = rng.uniform(10, render.cols - 10), y = rng.uniform(10, render.rows - 10);  // in this order
    const cv::Point c(x, y);
    const int r = rng.uniform(2, 7);
    bool clear = true;  // no clutter near the model's edges
    for (const EdgePoint& p : model_edges) clear = clear && std::hypot(p.x_px - c.x, p.y_px - c.y) > r + 15;
    if (!clear) continue;
    cv::circle(cluttered, c, r, cv::Scalar(rng.uniform(0.0, 0.9)), cv::FILLED);
    ++placed;
  }
  SimilarityOptions options;
  const Similarity clean = compare_render_to_photo(render, photo, options);
  const Similarity busy = compare_render_to_photo(render, cluttered, options);
  const double extra = double(busy.photo_edge_pixels - clean.photo_edge_pixels);
  ASSERT_GT(extra, 100);
  const double share = extra / double(busy.photo_edge_pixels);
  std::printf("clutter: %.0f extra photo edge points (%.0f %%); chamfer %.4f -> %.4f"
              " (r->p %.4f -> %.4f, p->r %.4f -> %.4f)\n",
              extra, 100 * share, clean.chamfer_px, busy.chamfer_px, clean.chamfer_render_to_photo_px,
              busy.chamfer_render_to_photo_px, clean.chamfer_photo_to_render_px, busy.chamfer_photo_to_render_px);
  EXPECT_LE(busy.chamfer_render_to_photo_px, clean.chamfer_render_to_photo_px + 0.02);
  EXPECT_LE(busy.chamfer_photo_to_render_px,
            (1 - share) * clean.chamfer_photo_to_render_px + share * options.chamfer_cutoff_px + 0.02);
  EXPECT_LE(busy.chamfer_px - clean.chamfer_px, 0.5 * share * options.chamfer_cutoff_px + 0.02);

  SimilarityOptions no_cutoff;
  no_cutoff.chamfer_cutoff_px = 1000;
  const double unbounded = compare_render_to_photo(render, cluttered, no_cutoff).chamfer_px -
                           compare_render_to_photo(render, photo, no_cutoff).chamfer_px;
  std::printf("clutter without a cutoff moves the chamfer by %.3f px, with one by %.3f px\n", unbounded,
              busy.chamfer_px - clean.chamfer_px);
  EXPECT_GT(unbounded, 2 * (busy.chamfer_px - clean.chamfer_px));
}

// The ring search of the bucket index against a brute-force nearest segment.
TEST(SetupSimilarity, EdgeIndexFindsTheNearestSegment) {
  cv::RNG rng(123);
  std::vector<EdgePoint> points(300);
  for (EdgePoint& p : points) {
    p.x_px = float(rng.uniform(0.0, 120.0));
    p.y_px = float(rng.uniform(0.0, 80.0));
    const double a = rng.uniform(0.0, 2 * CV_PI);
    p.normal_x = float(std::cos(a));
    p.normal_y = float(std::sin(a));
  }
  const double cutoff = 7;
  const EdgeDistanceIndex index(points, cv::Size(120, 80), cutoff);
  for (int i = 0; i < 2000; ++i) {
    const double x = rng.uniform(-5.0, 125.0), y = rng.uniform(-5.0, 85.0);
    double best = cutoff;
    for (const EdgePoint& p : points) {
      const double dx = x - p.x_px, dy = y - p.y_px;
      const double across = dx * p.normal_x + dy * p.normal_y;
      const double along = std::max(0.0, std::abs(dx * p.normal_y - dy * p.normal_x) - 0.6);
      best = std::min(best, std::hypot(across, along));
    }
    ASSERT_NEAR(index.distance_px(x, y), best, 1e-4) << x << ", " << y;  // the index works in float
  }
  EXPECT_EQ(EdgeDistanceIndex({}, cv::Size(10, 10), 3).distance_px(5, 5), 3);
}

// NaN in a float photo acts as a masked pixel.
TEST(SetupSimilarity, NonFinitePhotoPixelsAreIgnoredLikeMaskedOnes) {
  const cv::Mat render = scene();
  const cv::Mat photo = as_photo(shifted(render, 0.5, 0.5), 1, 0, kNoise, 2);
  cv::Mat holes = photo.clone();
  holes(cv::Rect(200, 150, 20, 10)).setTo(std::nan(""));
  cv::Mat mask(render.size(), CV_8U, cv::Scalar(255));
  mask(cv::Rect(200, 150, 20, 10)).setTo(0);
  const Similarity with_holes = compare_render_to_photo(render, holes);
  const Similarity masked = compare_render_to_photo(render, photo, {}, mask);
  EXPECT_TRUE(std::isfinite(with_holes.ncc) && std::isfinite(with_holes.gradient_ncc));
  EXPECT_EQ(with_holes.ncc, masked.ncc);
  EXPECT_EQ(with_holes.gradient_ncc, masked.gradient_ncc);
  EXPECT_EQ(with_holes.chamfer_px, masked.chamfer_px);
  EXPECT_EQ(with_holes.valid_pixels, masked.valid_pixels);
}

TEST(SetupSimilarity, AFlatRenderHasNoEdgesAndScoresWorst) {
  const cv::Mat photo = scene();
  const Similarity s = compare_render_to_photo(cv::Mat(photo.size(), CV_32F, cv::Scalar(0.4)), photo);
  EXPECT_EQ(s.render_edge_pixels, 0);
  EXPECT_EQ(s.ncc, 0);
  EXPECT_EQ(s.gradient_ncc, 0);
  EXPECT_EQ(s.chamfer_render_to_photo_px, 10);
  EXPECT_EQ(s.chamfer_photo_to_render_px, 10);
}

TEST(SetupSimilarity, RefusesMismatchedImages) {
  const cv::Mat a = scene();
  EXPECT_THROW(compare_render_to_photo(a, a(cv::Rect(0, 0, 100, 100)).clone()), std::invalid_argument);
  cv::Mat d;
  a.convertTo(d, CV_64F);
  EXPECT_THROW(compare_render_to_photo(d, d), std::invalid_argument);
  EXPECT_THROW(compare_render_to_photo(a, cv::Mat()), std::invalid_argument);
  EXPECT_THROW(compare_render_to_photo(a, a, {}, cv::Mat(10, 10, CV_8U, cv::Scalar(255))), std::invalid_argument);
  EXPECT_THROW(compare_render_to_photo(a, a, {}, cv::Mat(a.size(), CV_32F, cv::Scalar(1))), std::invalid_argument);
  SimilarityOptions bad;
  bad.chamfer_cutoff_px = 0;
  EXPECT_THROW(PhotoEdgeModel(a, bad), std::invalid_argument);
  const PhotoEdgeModel model(a);
  EXPECT_THROW(model.compare(a.t()), std::invalid_argument);
}

// Cost of one evaluation at 1 MP on one core (reported, not asserted).
TEST(SetupSimilarity, TimePerEvaluationAtOneMegapixel) {
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const cv::Mat render = scene(1024.0 / 300);  // 1365 x 1024
  const cv::Mat crop = render(cv::Rect(0, 0, 1024, 1024)).clone();
  const cv::Mat photo = as_photo(shifted(crop, 0.7, 0.4), 0.9, 0.05, kNoise, 1);
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  const PhotoEdgeModel model(photo);
  const auto t1 = clock::now();
  Similarity s;
  SimilarityWorkspace workspace;
  const int n = 20;
  double eval_ms = 1e9;  // the fastest of n: other processes only ever add time
  for (int i = 0; i < n; ++i) {
    const auto start = clock::now();
    s = model.compare(crop, workspace);
    eval_ms = std::min(eval_ms, std::chrono::duration<double, std::milli>(clock::now() - start).count());
  }
  const auto t2 = clock::now();
  Similarity fresh = model.compare(crop);
  const double fresh_ms = std::chrono::duration<double, std::milli>(clock::now() - t2).count();
  cv::setNumThreads(threads);
  const double build_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  std::printf("1024 x 1024, one thread: model %.2f ms, evaluation %.2f ms with a workspace, %.2f ms without"
              " (%ld render, %ld photo edge points, chamfer %.3f px)\n",
              build_ms, eval_ms, fresh_ms, s.render_edge_pixels, s.photo_edge_pixels, s.chamfer_px);
  EXPECT_EQ(fresh.chamfer_px, s.chamfer_px);
  EXPECT_EQ(fresh.gradient_ncc, s.gradient_ncc);
  RecordProperty("evaluation_ms", std::to_string(eval_ms));
  EXPECT_GT(s.gradient_ncc, 0.9);
}

}  // namespace
}  // namespace glasspiv
