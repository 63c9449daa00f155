// fit_camera_pose (calib/fit/extrinsic_fit.h) against synthetic truth, against
// OpenCV's solvePnP + solvePnPRefineLM on the same detections, with outliers,
// a focal error, the projector hook, degenerate inputs, and the covariance
// against Monte Carlo scatter.
//
// The scene: 20 square markers (40 mm, 4 corners each) on a 5 x 4 grid 160 mm
// apart, at depths +-90 mm, seen from ~1.3 m by the OpenCV5 reference camera
// of the intrinsic fit tests. Noise: independent Gaussian, 0.1 px on x and y.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "calib/fit/extrinsic_fit.h"
#include "calib/fit/marginal_covariance.h"
#include "truth_cameras.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

constexpr double kNoisePx = 0.1;
constexpr int kMarkers = 20, kCornersPerMarker = 4;

RigidTransform truth_camera_from_world() {
  return RigidTransform::from_rvec_tvec(Eigen::Vector3d(0.12, -0.18, 0.05), Eigen::Vector3d(-30, 20, 1300));
}

// The marker corners' world positions, marker by marker.
std::vector<Eigen::Vector3d> marker_corners_world() {
  std::vector<Eigen::Vector3d> out;
  for (int m = 0; m < kMarkers; ++m) {
    const double x = (m % 5 - 2) * 160.0, y = (m / 5 - 1.5) * 160.0, z = 90 * std::sin(1.7 * m);
    const double h = 20;
    for (const auto& [dx, dy] : {std::pair{-h, -h}, std::pair{h, -h}, std::pair{h, h}, std::pair{-h, h}})
      out.emplace_back(x + dx, y + dy, z);
  }
  return out;
}

std::vector<PointObservation> observe_points(const CameraModel& camera, const RigidTransform& camera_from_world,
                                             const std::vector<Eigen::Vector3d>& world, double noise_px,
                                             unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, noise_px);
  std::vector<PointObservation> points;
  for (std::size_t i = 0; i < world.size(); ++i) {
    const std::optional<Eigen::Vector2d> pixel = camera.project(camera_from_world.apply(world[i]));
    EXPECT_TRUE(pixel && pixel->x() > 0 && pixel->y() > 0 && pixel->x() < camera.width_px() - 1 &&
                pixel->y() < camera.height_px() - 1)
        << "corner " << i << " leaves the image";
    PointObservation p;
    p.point_world_mm = world[i];
    p.pixel_px = *pixel + Eigen::Vector2d(noise(rng), noise(rng));
    p.group = static_cast<int>(i) / kCornersPerMarker;
    p.label = "marker " + std::to_string(p.group) + " corner " + std::to_string(i % kCornersPerMarker);
    points.push_back(p);
  }
  return points;
}

std::vector<PointObservation> scene(double noise_px, unsigned seed) {
  return observe_points(testing::truth_opencv5(), truth_camera_from_world(), marker_corners_world(), noise_px, seed);
}

// (rvec, t) of a pose, the covariance's parameterisation.
Eigen::Matrix<double, 6, 1> parameters(const RigidTransform& pose) {
  Eigen::Matrix<double, 6, 1> p;
  p << pose.rvec(), pose.translation_mm;
  return p;
}
Eigen::Vector3d centre(const RigidTransform& camera_from_world) { return camera_from_world.inverse().translation_mm; }

// Every pose parameter and every axis of the camera centre within 4 sigma of truth.
void expect_within_4_sigma(const ExtrinsicFit& fit, const RigidTransform& truth) {
  const Eigen::Matrix<double, 6, 1> error = parameters(fit.camera_from_world) - parameters(truth);
  for (int i = 0; i < 6; ++i) EXPECT_LT(std::abs(error(i)), 4 * std::sqrt(fit.covariance(i, i))) << "parameter " << i;
  const Eigen::Vector3d centre_error = centre(fit.camera_from_world) - centre(truth);
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(centre_error(i)), 4 * fit.position_sigma_mm(i)) << "axis " << i;
}

TEST(ExtrinsicFit, RecoversThePoseWithinItsCovariance) {
  const std::vector<PointObservation> points = scene(kNoisePx, 1);
  const ExtrinsicFit fit = fit_camera_pose(testing::truth_opencv5(), points);
  EXPECT_EQ(fit.inlier_count, kMarkers * kCornersPerMarker);
  EXPECT_EQ(fit.outlier_count, 0);
  EXPECT_EQ(fit.termination, "CONVERGENCE");
  // For 0.1 px per axis: RMS -> sqrt(2) 0.1, sigma -> 0.1 (80 points: +-10%).
  EXPECT_NEAR(fit.sigma_px, kNoisePx, 0.25 * kNoisePx);
  EXPECT_NEAR(fit.rms_px, std::sqrt(2.0) * kNoisePx, 0.25 * kNoisePx);
  EXPECT_GT(fit.initial_rms_px, 0);
  ASSERT_EQ(fit.covariance.rows(), 6);
  expect_within_4_sigma(fit, truth_camera_from_world());
  // Per-marker residuals, markers ascending; residuals in input order.
  ASSERT_EQ(fit.groups.size(), static_cast<std::size_t>(kMarkers));
  for (int m = 0; m < kMarkers; ++m) {
    EXPECT_EQ(fit.groups[m].group, m);
    EXPECT_EQ(fit.groups[m].points, kCornersPerMarker);
    EXPECT_LT(fit.groups[m].rms_px, 5 * kNoisePx);
  }
  for (std::size_t i = 0; i < points.size(); ++i) EXPECT_EQ(fit.residuals[i].point, static_cast<int>(i));
  const Eigen::Vector3d centre_error = centre(fit.camera_from_world) - centre(truth_camera_from_world());
  std::cout << "pose vs truth: camera centre error " << centre_error.transpose() << " mm, 1-sigma "
            << fit.position_sigma_mm.transpose() << " mm; rotation 1-sigma " << fit.rotation_sigma_deg
            << " deg; rms " << fit.rms_px << " px, reciprocal condition " << fit.reciprocal_condition << "\n";
}

TEST(ExtrinsicFit, NoiseFreeIsExact) {
  const ExtrinsicFit fit = fit_camera_pose(testing::truth_opencv5(), scene(0, 1));
  EXPECT_LT((centre(fit.camera_from_world) - centre(truth_camera_from_world())).norm(), 1e-9);
  EXPECT_LT((fit.camera_from_world.translation_mm - truth_camera_from_world().translation_mm).norm(), 1e-9);
  EXPECT_LT((fit.camera_from_world.rvec() - truth_camera_from_world().rvec()).norm(), 1e-12);
  EXPECT_LT(fit.rms_px, 1e-9);
  // The covariance is scaled by the floor, not by the round-off sigma.
  const ExtrinsicFit noisy = fit_camera_pose(testing::truth_opencv5(), scene(kObservabilitySigmaFloorPx, 1));
  EXPECT_NEAR(fit.position_sigma_mm.norm(), noisy.position_sigma_mm.norm() * kObservabilitySigmaFloorPx /
                                                std::max(noisy.sigma_px, kObservabilitySigmaFloorPx),
              0.05 * fit.position_sigma_mm.norm());
}

// OpenCV: solvePnP (iterative, from its own start) then solvePnPRefineLM, the
// camera matrix and distortion of the same model; both pixel conventions put
// (0, 0) at the centre of the top-left pixel, so the pixels go in unchanged.
TEST(ExtrinsicFit, AgreesWithOpenCV) {
  const CameraModel camera = testing::truth_opencv5();
  for (unsigned seed : {1u, 2u, 3u}) {
    const std::vector<PointObservation> points = scene(kNoisePx, seed);
    std::vector<cv::Point3d> object;
    std::vector<cv::Point2d> pixels;
    for (const PointObservation& p : points) {
      object.emplace_back(p.point_world_mm.x(), p.point_world_mm.y(), p.point_world_mm.z());
      pixels.emplace_back(p.pixel_px.x(), p.pixel_px.y());
    }
    cv::Matx33d k;
    const Eigen::Matrix3d km = camera.camera_matrix();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) k(r, c) = km(r, c);
    const std::vector<double> distortion = camera.distortion();
    cv::Mat rvec, tvec;
    ASSERT_TRUE(cv::solvePnP(object, pixels, k, distortion, rvec, tvec, false, cv::SOLVEPNP_ITERATIVE));
    cv::solvePnPRefineLM(object, pixels, k, distortion, rvec, tvec,
                         cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-15));
    std::vector<cv::Point2d> projected;
    cv::projectPoints(object, rvec, tvec, k, distortion, projected);
    double sum = 0;
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      const cv::Point2d d = projected[i] - pixels[i];
      sum += d.dot(d);
    }
    const double opencv_rms = std::sqrt(sum / pixels.size());

    ExtrinsicFitOptions options;
    options.outlier_k = 0;  // OpenCV has no outlier loop
    const ExtrinsicFit fit = fit_camera_pose(camera, points, options);
    const double ratio = fit.rms_px / opencv_rms;
    EXPECT_NEAR(ratio, 1.0, 1e-6);
    const Eigen::Vector3d opencv_t(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
    std::cout << "seed " << seed << ": rms " << fit.rms_px << " px, OpenCV " << opencv_rms << " px, ratio - 1 = "
              << ratio - 1 << "; translation difference " << (fit.camera_from_world.translation_mm - opencv_t).norm()
              << " mm\n";
  }
}

TEST(ExtrinsicFit, RefineFocalRecoversAOnePercentError) {
  const CameraModel truth = testing::truth_opencv5();
  const CameraModel wrong(truth.width_px(), truth.height_px(), 1.01 * truth.fx_px(), 1.01 * truth.fy_px(),
                          truth.cx_px(), truth.cy_px(), truth.distortion());
  ExtrinsicFitOptions options;
  options.refine_focal = true;
  const ExtrinsicFit fit = fit_camera_pose(wrong, scene(kNoisePx, 4), options);
  ASSERT_EQ(fit.covariance.rows(), 7);
  const double scale_sigma = std::sqrt(fit.covariance(6, 6));
  EXPECT_LT(std::abs(fit.focal_scale * 1.01 - 1), 4 * scale_sigma);
  EXPECT_LT(scale_sigma, 0.002);  // the depth spread determines the focal length to better than 0.2 %
  EXPECT_NEAR(fit.camera.fx_px(), truth.fx_px(), 4 * scale_sigma * truth.fx_px());
  EXPECT_DOUBLE_EQ(fit.camera.fy_px() / fit.camera.fx_px(), truth.fy_px() / truth.fx_px());
  EXPECT_EQ(fit.camera.cx_px(), truth.cx_px());
  expect_within_4_sigma(fit, truth_camera_from_world());
  std::cout << "refine_focal: fx " << fit.camera.fx_px() << " px (truth " << truth.fx_px() << ", start "
            << wrong.fx_px() << "), scale 1-sigma " << scale_sigma << "\n";
}

TEST(ExtrinsicFit, ProjectorEqualToThePinholeGivesTheSamePose) {
  const CameraModel camera = testing::truth_opencv5();
  const std::vector<PointObservation> points = scene(kNoisePx, 5);
  const ExtrinsicFit plain = fit_camera_pose(camera, points);
  for (bool refine_focal : {false, true}) {
    ExtrinsicFitOptions options;
    options.refine_focal = refine_focal;
    options.projector = [&](const RigidTransform& camera_from_world, int i, Eigen::Vector2d* pixel) {
      const std::optional<Eigen::Vector2d> p = camera.project(camera_from_world.apply(points[i].point_world_mm));
      if (!p) return false;
      *pixel = *p;
      return true;
    };
    const ExtrinsicFit hooked = fit_camera_pose(camera, points, options);
    ExtrinsicFitOptions autodiff;
    autodiff.refine_focal = refine_focal;
    const ExtrinsicFit reference = refine_focal ? fit_camera_pose(camera, points, autodiff) : plain;
    const double dt = (hooked.camera_from_world.translation_mm - reference.camera_from_world.translation_mm).norm();
    const double dr = (hooked.camera_from_world.rvec() - reference.camera_from_world.rvec()).norm();
    // With the focal scale free, depth trades against focal length (a valley of
    // the cost): the central differences' round-off moves the optimum along it
    // by ~1e-8 mm; without it the poses agree to ~1e-10 mm.
    EXPECT_LT(dt, refine_focal ? 1e-7 : 1e-8);
    EXPECT_LT(dr, 1e-8);
    EXPECT_NEAR(hooked.focal_scale, reference.focal_scale, 1e-10);
    EXPECT_NEAR(hooked.position_sigma_mm.norm(), reference.position_sigma_mm.norm(),
                1e-4 * reference.position_sigma_mm.norm());
    std::cout << "projector" << (refine_focal ? " + focal" : "") << ": translation difference " << dt
              << " mm, rotation difference " << dr << " rad\n";
  }
}

TEST(ExtrinsicFit, DropsOutliersAndKeepsThePose) {
  std::vector<PointObservation> points = scene(kNoisePx, 6);
  const std::vector<int> moved = {3, 17, 30, 51, 77};
  for (int i : moved) points[i].pixel_px += Eigen::Vector2d(20 * std::cos(i), 20 * std::sin(i));
  const ExtrinsicFit fit = fit_camera_pose(testing::truth_opencv5(), points);
  EXPECT_EQ(fit.outlier_count, static_cast<int>(moved.size()));
  for (std::size_t i = 0; i < points.size(); ++i)
    EXPECT_EQ(fit.residuals[i].outlier, std::find(moved.begin(), moved.end(), static_cast<int>(i)) != moved.end())
        << "point " << i;
  EXPECT_GE(fit.rounds, 2);
  EXPECT_GT(fit.initial_rms_px, 1.0);  // the start saw the outliers
  EXPECT_NEAR(fit.sigma_px, kNoisePx, 0.25 * kNoisePx);
  expect_within_4_sigma(fit, truth_camera_from_world());
  // The marker with a moved corner reports 3 inliers.
  EXPECT_EQ(fit.groups[3 / kCornersPerMarker].points, kCornersPerMarker - 1);
}

// Each refusal: InputError, field "fiducials", one line, saying what is wrong.
void expect_refused(const std::vector<PointObservation>& points, const std::string& words,
                    const ExtrinsicFitOptions& options = {}) {
  try {
    fit_camera_pose(testing::truth_opencv5(), points, options);
    ADD_FAILURE() << "not refused; expected \"" << words << "\"";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "fiducials");
    EXPECT_EQ(std::string(e.problem()).find('\n'), std::string::npos) << e.problem();
    EXPECT_NE(e.problem().find(words), std::string::npos) << e.problem();
    std::cout << "refused: " << e.problem() << "\n";
  }
}

TEST(ExtrinsicFit, RefusesThreePoints) {
  std::vector<PointObservation> points = scene(kNoisePx, 7);
  points.resize(3);
  expect_refused(points, "3 points given");
}

TEST(ExtrinsicFit, RefusesCollinearPoints) {
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 10; ++i) line.emplace_back(-200 + 40.0 * i, 0.5 * (-200 + 40.0 * i), 10.0 * i);
  expect_refused(observe_points(testing::truth_opencv5(), truth_camera_from_world(), line, kNoisePx, 8), "collinear");
}

// 16 corners on a 20 mm patch 3 m away (about 16 px across): the pixels fit, but
// the distance is not determined. Noise-free too: the sigma floor decides.
TEST(ExtrinsicFit, RefusesAnUnconstrainedPose) {
  const RigidTransform camera_from_world =
      RigidTransform::from_rvec_tvec(Eigen::Vector3d(0.05, 0.02, 0), Eigen::Vector3d(0, 0, 3000));
  std::vector<Eigen::Vector3d> patch;
  for (int i = 0; i < 16; ++i) patch.emplace_back((i % 4) * 6.0 - 9, (i / 4) * 6.0 - 9, (i % 3) * 2.0);
  for (double noise : {kNoisePx, 0.0})
    expect_refused(observe_points(testing::truth_opencv5(), camera_from_world, patch, noise, 9),
                   "the pose is not determined: camera position 1-sigma");
}

TEST(ExtrinsicFit, RefusesANonFinitePixel) {
  std::vector<PointObservation> points = scene(kNoisePx, 10);
  points[12].pixel_px.y() = std::numeric_limits<double>::quiet_NaN();
  expect_refused(points, "point 12 (marker 3 corner 0) has a non-finite pixel");
}

TEST(ExtrinsicFit, RefusesAStartWithThePointsBehindTheCamera) {
  ExtrinsicFitOptions options;
  options.initial_camera_from_world =
      RigidTransform::from_rvec_tvec(Eigen::Vector3d(0, M_PI, 0), Eigen::Vector3d(0, 0, -1300));
  expect_refused(scene(kNoisePx, 11), "have an image at the start pose", options);
}

// The reported covariance predicts the scatter of the pose over noise draws:
// per pose parameter and per axis of the camera centre, the observed standard
// deviation over 50 seeds within a factor 1.5 of the predicted 1-sigma (the
// standard deviation of 50 draws is itself uncertain by ~10 %).
TEST(ExtrinsicFit, CovariancePredictsTheScatter) {
  constexpr int kSeeds = 50;
  const RigidTransform truth = truth_camera_from_world();
  Eigen::Matrix<double, 9, 1> sum_squares = Eigen::Matrix<double, 9, 1>::Zero(),
                              predicted = Eigen::Matrix<double, 9, 1>::Zero();
  for (int seed = 0; seed < kSeeds; ++seed) {
    const ExtrinsicFit fit = fit_camera_pose(testing::truth_opencv5(), scene(kNoisePx, 100 + seed));
    Eigen::Matrix<double, 9, 1> error;
    error << parameters(fit.camera_from_world) - parameters(truth), centre(fit.camera_from_world) - centre(truth);
    sum_squares += error.cwiseAbs2();
    for (int i = 0; i < 6; ++i) predicted(i) += std::sqrt(fit.covariance(i, i)) / kSeeds;
    predicted.tail<3>() += fit.position_sigma_mm / kSeeds;
  }
  const Eigen::Matrix<double, 9, 1> observed = (sum_squares / kSeeds).cwiseSqrt();  // about the truth: no bias
  const Eigen::Matrix<double, 9, 1> ratio = observed.cwiseQuotient(predicted);
  for (int i = 0; i < 9; ++i) {
    EXPECT_GT(ratio(i), 1 / 1.5) << "component " << i;
    EXPECT_LT(ratio(i), 1.5) << "component " << i;
  }
  std::cout << "Monte Carlo observed / predicted std (rvec x3, t x3, centre x3): " << ratio.transpose() << "\n";
}


// --- The rig bundle: three cameras around the 20 markers, each marker a
// fiducial with its corners at (+-20, +-20, 0) in its own frame, tilted; markers
// 0, 7, 12 held at their places, the rest free. Cameras and free markers start
// off by millimetres and hundredths of a radian.
struct Rig {
  std::vector<RigidTransform> camera_from_world, world_from_fiducial;  // truth
  std::vector<RigCamera> cameras;
  std::vector<RigFiducial> fiducials;
  std::vector<RigObservation> observations;
};

Rig make_rig(double noise_px, unsigned seed) {
  Rig rig;
  const CameraModel camera = testing::truth_opencv5();
  const Eigen::Vector3d t(-30, 20, 1300);
  for (const Eigen::Vector3d& rvec :
       {Eigen::Vector3d(0.12, -0.18, 0.05), Eigen::Vector3d(-0.1, 0.2, 0.0), Eigen::Vector3d(0.05, 0.05, 0.3)})
    rig.camera_from_world.push_back(RigidTransform::from_rvec_tvec(rvec, t));
  for (int m = 0; m < kMarkers; ++m) {
    const Eigen::Vector3d centre((m % 5 - 2) * 160.0, (m / 5 - 1.5) * 160.0, 90 * std::sin(1.7 * m));
    rig.world_from_fiducial.push_back(RigidTransform::from_rvec_tvec(
        Eigen::Vector3d(0.2 * std::sin(m), 0.2 * std::cos(m), 0.1 * m), centre));
  }
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, noise_px), offset(0, 1);
  const auto perturbed = [&](const RigidTransform& pose, double mm, double rad) {
    return RigidTransform::from_rvec_tvec(pose.rvec() + rad * Eigen::Vector3d(offset(rng), offset(rng), offset(rng)),
                                          pose.translation_mm + mm * Eigen::Vector3d(offset(rng), offset(rng), offset(rng)));
  };
  for (const RigidTransform& pose : rig.camera_from_world) rig.cameras.push_back({camera, perturbed(pose, 5, 0.01)});
  for (int m = 0; m < kMarkers; ++m) {
    const bool held = m == 0 || m == 7 || m == 12;
    rig.fiducials.push_back({held ? rig.world_from_fiducial[m] : perturbed(rig.world_from_fiducial[m], 2, 0.02), held});
  }
  for (int c = 0; c < 3; ++c)
    for (int m = 0; m < kMarkers; ++m)
      for (int k = 0; k < kCornersPerMarker; ++k) {
        const Eigen::Vector3d point(k == 1 || k == 2 ? 20 : -20, k >= 2 ? 20 : -20, 0);
        const std::optional<Eigen::Vector2d> pixel =
            camera.project(rig.camera_from_world[c].apply(rig.world_from_fiducial[m].apply(point)));
        EXPECT_TRUE(pixel && pixel->x() > 0 && pixel->y() > 0 && pixel->x() < camera.width_px() - 1 &&
                    pixel->y() < camera.height_px() - 1);
        rig.observations.push_back({c, m, point, *pixel + Eigen::Vector2d(noise(rng), noise(rng)),
                                    "camera " + std::to_string(c) + " marker " + std::to_string(m)});
      }
  return rig;
}

TEST(RigFit, RecoversCamerasAndFreeFiducials) {
  const Rig rig = make_rig(kNoisePx, 20);
  const RigFit fit = fit_rig(rig.cameras, rig.fiducials, rig.observations);
  EXPECT_EQ(fit.termination, "CONVERGENCE");
  EXPECT_EQ(fit.outlier_count, 0);
  EXPECT_NEAR(fit.sigma_px, kNoisePx, 0.25 * kNoisePx);
  EXPECT_GT(fit.initial_rms_px, 10 * fit.rms_px);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(fit.camera_points[c], kMarkers * kCornersPerMarker);
    // 120 free parameters for 480 residuals: the RMS is sqrt(2 (480 - 120) / 480) sigma.
    EXPECT_NEAR(fit.camera_rms_px[c], fit.rms_px, 0.3 * kNoisePx);
    const Eigen::Vector3d error = centre(fit.camera_from_world[c]) - centre(rig.camera_from_world[c]);
    for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(error(i)), 4 * fit.camera_sigma[c].position_sigma_mm(i));
    std::cout << "rig camera " << c << ": centre error " << error.transpose() << " mm, 1-sigma "
              << fit.camera_sigma[c].position_sigma_mm.transpose() << " mm, rms " << fit.camera_rms_px[c] << " px\n";
  }
  for (int m = 0; m < kMarkers; ++m) {
    EXPECT_EQ(fit.fiducial_points[m], 3 * kCornersPerMarker);
    const Eigen::Vector3d error = fit.world_from_fiducial[m].translation_mm - rig.world_from_fiducial[m].translation_mm;
    if (rig.fiducials[m].held) {
      EXPECT_EQ(error.norm(), 0.0);
      EXPECT_EQ(fit.fiducial_sigma[m].position_sigma_mm.norm(), 0.0);
      continue;
    }
    for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(error(i)), 4 * fit.fiducial_sigma[m].position_sigma_mm(i));
  }
}

TEST(RigFit, DropsAnOutlier) {
  Rig rig = make_rig(kNoisePx, 21);
  rig.observations[100].pixel_px += Eigen::Vector2d(15, -12);
  const RigFit fit = fit_rig(rig.cameras, rig.fiducials, rig.observations);
  EXPECT_EQ(fit.outlier_count, 1);
  EXPECT_TRUE(fit.residuals[100].outlier);
  EXPECT_EQ(fit.camera_points[rig.observations[100].camera], kMarkers * kCornersPerMarker - 1);
}

void expect_rig_refused(const Rig& rig, const std::string& field, const std::string& words) {
  try {
    fit_rig(rig.cameras, rig.fiducials, rig.observations);
    ADD_FAILURE() << "not refused; expected \"" << words << "\"";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), field);
    EXPECT_NE(e.problem().find(words), std::string::npos) << e.problem();
    std::cout << "refused: " << e.problem() << "\n";
  }
}

TEST(RigFit, RefusesGaugeFreedomAndUnseenFiducials) {
  Rig free_rig = make_rig(kNoisePx, 22);
  for (RigFiducial& f : free_rig.fiducials) f.held = false;
  expect_rig_refused(free_rig, "fiducials", "gauge freedom");

  Rig unseen = make_rig(kNoisePx, 23);
  unseen.observations.erase(std::remove_if(unseen.observations.begin(), unseen.observations.end(),
                                           [](const RigObservation& o) { return o.fiducial == 5; }),
                            unseen.observations.end());
  expect_rig_refused(unseen, "fiducials", "fiducial 5 is free but no camera sees it");

  // A free marker seen by one camera only, its corners all but on top of each
  // other: its place is not determined.
  Rig weak = make_rig(kNoisePx, 24);
  std::vector<RigObservation> kept;
  for (RigObservation o : weak.observations) {
    if (o.fiducial == 9 && o.camera != 0) continue;
    if (o.fiducial == 9) o.point_fiducial_mm *= 0.01;
    kept.push_back(o);
  }
  weak.observations = kept;
  // The pixels of marker 9 then belong to its shrunk corners at the truth.
  for (RigObservation& o : weak.observations)
    if (o.fiducial == 9)
      o.pixel_px = *testing::truth_opencv5().project(
          weak.camera_from_world[0].apply(weak.world_from_fiducial[9].apply(o.point_fiducial_mm)));
  expect_rig_refused(weak, "fiducials", "fiducial 9 is not determined: position 1-sigma");
}
}  // namespace
}  // namespace glasspiv
