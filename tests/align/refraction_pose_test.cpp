// Tests of align/refraction_pose.h against closed forms: no glass gives the
// pinhole projection; behind a flat window the apparent shift is the slab's
// lateral shift d sin(theta) (1 - cos(theta) / sqrt(n^2 - sin^2(theta))); a ball
// lens shows the point inverted and the returned pixel's ray lands on it; total
// internal reflection, a hidden point and a point outside the image give their
// statuses; the Jacobian agrees with finite differences of the projection.
#include "align/refraction_pose.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "calib/fit/extrinsic_fit.h"
#include "render/scene.h"
#include "render/trace_scene_builder.h"

namespace glasspiv {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
constexpr double kNBk7 = 1.5195;
constexpr double kPi = 3.14159265358979323846;

CameraModel camera() { return CameraModel(640, 480, 800, 800, 319.5, 239.5); }

Rectangle marker(const Vector3d& centre, const Vector3d& normal, double half_size) {
  Rectangle r;
  r.centre_mm = centre;
  const Vector3d n = normal.normalized();
  r.right = n.unitOrthogonal();
  r.up = n.cross(r.right);
  r.half_width_mm = r.half_height_mm = half_size;
  return r;
}

Vector2d pinhole(const CameraModel& model, const RigidTransform& camera_from_world, const Vector3d& p) {
  return *model.project(camera_from_world.apply(p));
}

// Where the pixel's refracted-only path ends on an opaque solid (independent of
// the solver: the reference tracer, no index).
std::optional<OpaqueHit> landing(const TraceScene& scene, const CameraModel& model,
                                 const RigidTransform& camera_from_world, const Vector2d& pixel) {
  const std::optional<WorldRay> ray = pixel_world_ray(model, camera_from_world, pixel);
  if (!ray) return std::nullopt;
  TraceOptions o;
  o.reflections = false;
  o.min_weight = 1e-12;
  const TraceResult r = trace_ray(scene, ray->origin_mm, ray->direction, o);
  if (r.opaque_hits.empty()) return std::nullopt;
  return r.opaque_hits.front();
}

// Slab lateral shift (perpendicular to the ray) for incidence theta in air.
double slab_shift(double d, double n, double theta) {
  const double s = std::sin(theta);
  return d * s * (1 - std::cos(theta) / std::sqrt(n * n - s * s));
}

TEST(RefractionPose, NoGlassIsPinhole) {
  TraceScene scene;
  scene.solids.push_back({marker(Vector3d(20, -10, 600), Vector3d(0.2, 0.1, -1), 80), TraceMaterial::opaque(0.5)});
  const auto index = make_scene_index(scene);
  const CameraModel model = camera();
  const RigidTransform pose =
      camera_from_world_look_at(Vector3d(30, 15, -20), Vector3d(20, -10, 600), Vector3d(0, -1, 0));
  const Rectangle& r = std::get<Rectangle>(scene.solids[0].shape);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 20; ++k) {
    const Vector3d p = r.centre_mm + 70 * u(rng) * r.right + 70 * u(rng) * r.up;
    const Vector2d expected = pinhole(model, pose, p);
    const TracedProjection exact = project_through_scene(scene, *index, model, pose, p, 0, expected);
    ASSERT_TRUE(exact.ok()) << to_string(exact.status);
    EXPECT_LE((exact.pixel_px - expected).norm(), 1e-8);
    EXPECT_LE(exact.iterations, 1);
    const TracedProjection off =
        project_through_scene(scene, *index, model, pose, p, 0, expected + Vector2d(3 * u(rng), 3 * u(rng)));
    ASSERT_TRUE(off.ok()) << to_string(off.status);
    EXPECT_LE((off.pixel_px - expected).norm(), 1e-8);
    EXPECT_LE(off.iterations, 3);
    EXPECT_LE(off.residual_mm, 1e-7);
  }
}

// A window z in [200, 210] in air, a marker at z = 400; the camera at the origin
// looking obliquely at it. The apparent point is shifted radially (away from the
// foot of the normal through the camera) by the slab shift / cos(theta).
struct WindowSetup {
  TraceScene scene;
  std::unique_ptr<SceneIndex> index;
  CameraModel model = camera();
  RigidTransform pose;
  double thickness = 10, n = kNBk7, z_marker = 400;

  explicit WindowSetup(const Vector3d& look_at) {
    scene.solids.push_back(
        {make_slab(Vector3d(0, 0, 205), Vector3d::UnitZ(), thickness, 1e5), TraceMaterial::glass(n)});
    scene.solids.push_back({marker(Vector3d(0, 0, z_marker), Vector3d::UnitZ(), 1e5), TraceMaterial::opaque(0.5)});
    index = make_scene_index(scene);
    pose = camera_from_world_look_at(Vector3d::Zero(), look_at, Vector3d(0, -1, 0));
  }
  // The closed-form landing point of the pixel's ray on the marker plane.
  Vector3d closed_form_landing(const Vector2d& pixel) const {
    const Vector3d d = pixel_world_ray(model, pose, pixel)->direction;
    const double theta = std::acos(d.z());
    const Vector2d radial = Vector2d(d.x(), d.y()).normalized();
    const double rho = z_marker * std::tan(theta) - slab_shift(thickness, n, theta) / std::cos(theta);
    return Vector3d(rho * radial.x(), rho * radial.y(), z_marker);
  }
};

TEST(RefractionPose, WindowShiftMatchesClosedForm) {
  for (double look_deg : {0.0, 25.0, 50.0}) {
    const double a = look_deg * kPi / 180;
    WindowSetup w(Vector3d(400 * std::tan(a), 0.3 * 400 * std::tan(a), 400));
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-60, 60);
    for (int k = 0; k < 10; ++k) {
      const Vector3d centre = w.closed_form_landing(Vector2d(319.5, 239.5));
      const Vector3d p = centre + Vector3d(u(rng), u(rng), 0);
      const Vector2d start = pinhole(w.model, w.pose, p);
      const TracedProjection tp = project_through_scene(w.scene, *w.index, w.model, w.pose, p, 1, start);
      ASSERT_TRUE(tp.ok()) << to_string(tp.status) << " at " << look_deg << " deg";
      EXPECT_LE((w.closed_form_landing(tp.pixel_px) - p).norm(), 1e-9) << look_deg << " deg";
      EXPECT_LE(tp.iterations, 5);
      if (look_deg > 0) {
        EXPECT_GT((tp.pixel_px - start).norm(), 1.0);  // the window shifts the image
      }
    }
  }
  // Along the normal: no shift, the pinhole pixel.
  WindowSetup w(Vector3d(0, 0, 400));
  const Vector3d p(0, 0, 400);
  const TracedProjection tp = project_through_scene(w.scene, *w.index, w.model, w.pose, p, 1, Vector2d(300, 250));
  ASSERT_TRUE(tp.ok());
  EXPECT_LE((tp.pixel_px - Vector2d(319.5, 239.5)).norm(), 1e-8);
}

TEST(RefractionPose, GrazingWindowConvergesOrSaysWhy) {
  // Incidence 80 .. 89.5 deg on the window: a correct pixel or a failure status.
  for (double theta_deg : {80.0, 85.0, 88.0, 89.5}) {
    const double t = theta_deg * kPi / 180;
    WindowSetup w(Vector3d(std::sin(t), 0, std::cos(t)));
    const Vector3d p = w.closed_form_landing(Vector2d(319.5, 239.5)) + Vector3d(0, 5, 0);
    const TracedProjection tp =
        project_through_scene(w.scene, *w.index, w.model, w.pose, p, 1, pinhole(w.model, w.pose, p));
    if (theta_deg <= 85) {
      ASSERT_TRUE(tp.ok()) << theta_deg << " deg: " << to_string(tp.status);
    }
    if (tp.ok()) {
      const double rel = (w.closed_form_landing(tp.pixel_px) - p).norm() / p.norm();
      EXPECT_LE(rel, 1e-11) << theta_deg << " deg";
    }
  }
}

// A ball lens (r = 20 mm at z = 200) with a marker at z = 300, beyond its focus
// (EFL = n D / (4 (n - 1)) = 29.3 mm from the centre): the image is inverted.
TEST(RefractionPose, BallLensImageIsInvertedAndLandsOnThePoint) {
  TraceScene scene;
  scene.solids.push_back({Sphere{Vector3d(0, 0, 200), 20}, TraceMaterial::glass(kNBk7)});
  scene.solids.push_back({marker(Vector3d(0, 0, 300), Vector3d::UnitZ(), 200), TraceMaterial::opaque(0.5)});
  const auto index = make_scene_index(scene);
  const CameraModel model = camera();
  const RigidTransform pose = camera_from_world_look_at(Vector3d::Zero(), Vector3d(0, 0, 200), Vector3d(0, -1, 0));
  const Vector2d axis_px(319.5, 239.5);
  int converged = 0;
  for (const Vector3d& p : {Vector3d(2, 1, 300), Vector3d(-5, 3, 300), Vector3d(8, -6, 300), Vector3d(0.1, 0, 300)}) {
    const Vector2d start = pinhole(model, pose, p);
    const TracedProjection tp = project_through_scene(scene, *index, model, pose, p, 1, start);
    ASSERT_TRUE(tp.ok()) << to_string(tp.status) << " for " << p.transpose();
    ++converged;
    EXPECT_LT((tp.pixel_px - axis_px).dot(start - axis_px), 0) << "not inverted";
    const std::optional<OpaqueHit> hit = landing(scene, model, pose, tp.pixel_px);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->solid_index, 1);
    EXPECT_LE((hit->point_mm - p).norm(), 1e-7);
    EXPECT_LE(tp.residual_mm, 1e-7);
  }
  EXPECT_EQ(converged, 4);
}

// Behind a 3 x 3 layer of touching glass spheres (d = 40 mm): whatever the
// status, an ok pixel's ray lands on the point (independent reference trace).
TEST(RefractionPose, PackingNeverGivesAWrongPixel) {
  TraceScene scene;
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      scene.solids.push_back({Sphere{Vector3d(40.0 * i, 40.0 * j, 250), 20}, TraceMaterial::glass(kNBk7)});
  scene.solids.push_back({marker(Vector3d(0, 0, 330), Vector3d(0.05, 0.1, -1), 70), TraceMaterial::opaque(0.5)});
  const int target = 9;
  const auto index = make_scene_index(scene);
  const CameraModel model = camera();
  const RigidTransform pose = camera_from_world_look_at(Vector3d(5, -3, 0), Vector3d(0, 0, 300), Vector3d(0, -1, 0));
  const Rectangle& r = std::get<Rectangle>(scene.solids[target].shape);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-65, 65);
  int counts[5] = {0, 0, 0, 0, 0};
  for (int k = 0; k < 400; ++k) {
    const Vector3d p = r.centre_mm + u(rng) * r.right + u(rng) * r.up;
    const TracedProjection tp = project_through_scene(scene, *index, model, pose, p, target, pinhole(model, pose, p));
    ++counts[static_cast<int>(tp.status)];
    if (!tp.ok()) continue;
    const std::optional<OpaqueHit> hit = landing(scene, model, pose, tp.pixel_px);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->solid_index, target);
    EXPECT_LE((hit->point_mm - p).norm(), 1e-7);
  }
  std::printf("packing: ok %d, not_converged %d, blocked %d, left_image %d, no_path %d of 400\n", counts[0], counts[1],
              counts[2], counts[3], counts[4]);
  EXPECT_GT(counts[0], 200);
}

TEST(RefractionPose, HiddenPointIsBlocked) {
  TraceScene scene;
  scene.solids.push_back({marker(Vector3d(0, 0, 200), Vector3d::UnitZ(), 30), TraceMaterial::opaque(0.2)});  // blocker
  scene.solids.push_back({marker(Vector3d(0, 0, 400), Vector3d::UnitZ(), 100), TraceMaterial::opaque(0.5)});
  const auto index = make_scene_index(scene);
  const CameraModel model = camera();
  const RigidTransform pose;
  const Vector3d p(10, 5, 400);
  const TracedProjection tp = project_through_scene(scene, *index, model, pose, p, 1, pinhole(model, pose, p));
  EXPECT_EQ(tp.status, TracedProjectionStatus::blocked);
  // Visible beside the blocker.
  const Vector3d q(80, 5, 400);
  EXPECT_TRUE(project_through_scene(scene, *index, model, pose, q, 1, pinhole(model, pose, q)).ok());
  EXPECT_THROW(project_through_scene(scene, *index, model, pose, q, 2, Vector2d(0, 0)), std::invalid_argument);
}

TEST(RefractionPose, TotalInternalReflectionIsNoPath) {
  // A glass cube seen through its front face at 45 deg: inside, the ray meets
  // the side face at 62 deg incidence, past the critical angle (41 deg).
  TraceScene scene;
  Box cube;
  cube.centre_mm = Vector3d(0, 0, 100);
  cube.half_extent_mm = Vector3d(10, 10, 10);
  scene.solids.push_back({cube, TraceMaterial::glass(kNBk7)});
  scene.solids.push_back({marker(Vector3d(45, 0, 130), Vector3d(1, 0, 1), 20), TraceMaterial::opaque(0.5)});
  const auto index = make_scene_index(scene);
  const CameraModel model = camera();
  const RigidTransform pose = camera_from_world_look_at(Vector3d(-85, 0, 0), Vector3d(45, 0, 130), Vector3d(0, -1, 0));
  const Vector3d p(45, 0, 130);
  const TracedProjection tp = project_through_scene(scene, *index, model, pose, p, 1, pinhole(model, pose, p));
  EXPECT_EQ(tp.status, TracedProjectionStatus::no_path) << to_string(tp.status);
}

TEST(RefractionPose, PointOutsideTheImageLeavesIt) {
  TraceScene scene;
  scene.solids.push_back({marker(Vector3d(0, 0, 400), Vector3d::UnitZ(), 1000), TraceMaterial::opaque(0.5)});
  const auto index = make_scene_index(scene);
  const CameraModel model = camera();
  const RigidTransform pose;
  const Vector3d p(200, 0, 400);  // pinhole column 719.5: past the right edge
  const TracedProjection tp = project_through_scene(scene, *index, model, pose, p, 0, Vector2d(600, 240));
  EXPECT_EQ(tp.status, TracedProjectionStatus::left_image) << to_string(tp.status);
}

// d(pixel)/d(in-plane point) from finite differences of the projection itself
// against the inverse of the returned dplane_dpixel.
void expect_inverse_jacobian(const TraceScene& scene, const SceneIndex& index, const CameraModel& model,
                             const RigidTransform& pose, const Vector3d& p, int target) {
  const Rectangle& r = std::get<Rectangle>(scene.solids[static_cast<std::size_t>(target)].shape);
  const TracedProjection tp = project_through_scene(scene, index, model, pose, p, target, pinhole(model, pose, p));
  ASSERT_TRUE(tp.ok());
  const Eigen::Matrix2d dpixel_dplane = tp.dplane_dpixel.inverse();
  const double h = 1e-3;
  Eigen::Matrix2d fd;
  for (int a = 0; a < 2; ++a) {
    const Vector3d axis = a == 0 ? r.right : r.up;
    const TracedProjection plus = project_through_scene(scene, index, model, pose, p + h * axis, target, tp.pixel_px);
    const TracedProjection minus = project_through_scene(scene, index, model, pose, p - h * axis, target, tp.pixel_px);
    ASSERT_TRUE(plus.ok() && minus.ok());
    fd.col(a) = (plus.pixel_px - minus.pixel_px) / (2 * h);
  }
  EXPECT_LE((fd - dpixel_dplane).norm(), 1e-6 * dpixel_dplane.norm()) << "fd\n"
                                                                      << fd << "\nanalytic\n"
                                                                      << dpixel_dplane;
}

TEST(RefractionPose, InverseJacobianMatchesFiniteDifferences) {
  WindowSetup w(Vector3d(150, 40, 400));
  expect_inverse_jacobian(w.scene, *w.index, w.model, w.pose, w.closed_form_landing(Vector2d(300, 200)), 1);

  TraceScene scene;
  scene.solids.push_back({Sphere{Vector3d(0, 0, 200), 20}, TraceMaterial::glass(kNBk7)});
  scene.solids.push_back({marker(Vector3d(0, 0, 300), Vector3d(0.1, 0, 1), 200), TraceMaterial::opaque(0.5)});
  const auto index = make_scene_index(scene);
  const RigidTransform pose = camera_from_world_look_at(Vector3d::Zero(), Vector3d(0, 0, 200), Vector3d(0, -1, 0));
  expect_inverse_jacobian(scene, *index, camera(), pose, Vector3d(-4, 3, 300 + 0.4), 1);
}

TEST(RefractionPose, ProjectorIsRepeatableAndSmoothInThePose) {
  WindowSetup w(Vector3d(120, 30, 400));
  std::vector<Vector3d> points = {w.closed_form_landing(Vector2d(100, 100)), w.closed_form_landing(Vector2d(500, 400))};
  const auto project = traced_point_projector(w.scene, *w.index, w.model, points, {1, 1});
  Vector2d a, b;
  ASSERT_TRUE(project(w.pose, 0, &a));
  ASSERT_TRUE(project(w.pose, 0, &b));
  EXPECT_EQ(a, b);
  EXPECT_LE((a - Vector2d(100, 100)).norm(), 1e-8);
  ASSERT_TRUE(project(w.pose, 1, &a));
  EXPECT_LE((a - Vector2d(500, 400)).norm(), 1e-8);
  EXPECT_FALSE(project(w.pose, 2, &a));
  // Numerical derivative w.r.t. a rotation: steps h and 2h agree (no solver noise).
  auto pixel_at = [&](double angle) {
    RigidTransform pose = w.pose;
    pose.rotation = Eigen::AngleAxisd(angle, Vector3d::UnitY()).toRotationMatrix() * pose.rotation;
    Vector2d px;
    EXPECT_TRUE(project(pose, 0, &px));
    return px;
  };
  const double h = 1e-6;
  const Vector2d d1 = (pixel_at(h) - pixel_at(-h)) / (2 * h);
  const Vector2d d2 = (pixel_at(2 * h) - pixel_at(-2 * h)) / (4 * h);
  EXPECT_GT(d1.norm(), 100);  // ~ f px per rad
  EXPECT_LE((d1 - d2).norm(), 1e-5 * d1.norm());
  EXPECT_THROW(traced_point_projector(w.scene, *w.index, w.model, points, {1}), std::invalid_argument);
  EXPECT_THROW(traced_point_projector(w.scene, *w.index, w.model, points, {0, 1}), std::invalid_argument);
}

// End to end: markers behind a window, pixels made with the traced projection
// at a known pose; the extrinsic fit with the traced projector finds that pose,
// the pinhole fit is biased by the window.
TEST(RefractionPose, ExtrinsicFitThroughAWindowFindsThePose) {
  TraceScene scene;
  scene.solids.push_back({make_slab(Vector3d(0, 0, 205), Vector3d::UnitZ(), 12, 1e4), TraceMaterial::glass(kNBk7)});
  scene.solids.push_back({marker(Vector3d(-60, -30, 420), Vector3d(0.3, 0, -1), 40), TraceMaterial::opaque(0.5)});
  scene.solids.push_back({marker(Vector3d(70, 20, 480), Vector3d(-0.2, 0.1, -1), 40), TraceMaterial::opaque(0.5)});
  scene.solids.push_back({marker(Vector3d(-20, 55, 380), Vector3d(0, -0.3, -1), 40), TraceMaterial::opaque(0.5)});
  const auto index = make_scene_index(scene);
  const CameraModel model = camera();
  const RigidTransform truth =
      camera_from_world_look_at(Vector3d(15, -10, -30), Vector3d(0, 0, 430), Vector3d(0, -1, 0));
  std::vector<PointObservation> obs;
  std::vector<Vector3d> points;
  std::vector<int> targets;
  for (int solid = 1; solid <= 3; ++solid) {
    const Rectangle& r = std::get<Rectangle>(scene.solids[static_cast<std::size_t>(solid)].shape);
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j) {
        const Vector3d p = r.centre_mm + 25.0 * i * r.right + 25.0 * j * r.up;
        const TracedProjection tp =
            project_through_scene(scene, *index, model, truth, p, solid, pinhole(model, truth, p));
        ASSERT_TRUE(tp.ok()) << to_string(tp.status) << " solid " << solid << " " << i << " " << j;
        obs.push_back({p, tp.pixel_px, solid, ""});
        points.push_back(p);
        targets.push_back(solid);
      }
  }
  ExtrinsicFitOptions options;
  options.outlier_k = 0;
  const ExtrinsicFit plain = fit_camera_pose(model, obs, options);
  options.projector = traced_point_projector(scene, *index, model, points, targets);
  const ExtrinsicFit traced = fit_camera_pose(model, obs, options);
  const Vector3d centre_truth = -truth.rotation.transpose() * truth.translation_mm;
  auto centre = [](const RigidTransform& t) -> Vector3d { return -t.rotation.transpose() * t.translation_mm; };
  EXPECT_LE(traced.rms_px, 1e-6);
  EXPECT_LE((centre(traced.camera_from_world) - centre_truth).norm(), 1e-5);
  EXPECT_GT((centre(plain.camera_from_world) - centre_truth).norm(), 1.0);  // the window biases the pinhole pose
  std::printf(
      "pose through a 12 mm window: pinhole fit %.3g px rms, centre off by %.3g mm; traced fit %.3g px, %.3g mm\n",
      plain.rms_px, (centre(plain.camera_from_world) - centre_truth).norm(), traced.rms_px,
      (centre(traced.camera_from_world) - centre_truth).norm());
}

TEST(RefractionPose, TimePerProjection) {
  WindowSetup w(Vector3d(150, 40, 400));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  const int n = 2000;
  int ok = 0, iterations = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < n; ++k) {
    const Vector3d p = w.closed_form_landing(Vector2d(20 + 600 * u(rng), 20 + 440 * u(rng)));
    const TracedProjection tp =
        project_through_scene(w.scene, *w.index, w.model, w.pose, p, 1, pinhole(w.model, w.pose, p));
    ok += tp.ok();
    iterations += tp.iterations;
  }
  const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / n;
  std::printf("window: %d/%d ok, %.2f Newton steps on average, %.1f us per projection\n", ok, n, double(iterations) / n,
              us);
  EXPECT_EQ(ok, n);
}

}  // namespace
}  // namespace glasspiv
