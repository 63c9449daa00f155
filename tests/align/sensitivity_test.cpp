// Tests of align/sensitivity.h against closed forms: without glass the index
// moves nothing; behind a flat window the index moves the seen sheet point by
// the derivative of the slab shift, d sin(theta) n / (n^2 - sin^2(theta))^(3/2)
// per unit index, along the sheet; a camera moved by t parallel to a
// fronto-parallel sheet moves the seen point by t (mm) and its image by f t / Z
// (px); Monte Carlo is reproducible from its seed and agrees with first order.
#include "align/sensitivity.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "render/scene.h"
#include "render/trace_scene_builder.h"

namespace glasspiv {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
constexpr double kNBk7 = 1.5195;

SheetPlane sheet_z(double z, double extent = 1e5) {
  SheetPlane s;
  s.origin_mm = Vector3d(0, 0, z);
  s.extent_s_mm = s.extent_t_mm = extent;
  return s;
}

ModelTolerances none() {
  ModelTolerances t;
  t.camera_position_mm = t.camera_rotation_deg = t.glass_position_mm = t.sphere_diameter_mm = t.refractive_index = 0;
  return t;
}

const SensitivityParameter& parameter(const SensitivityMap& m, const std::string& name) {
  for (const auto& p : m.parameters)
    if (p.name == name) return p;
  throw std::runtime_error("no parameter " + name);
}

TEST(Sensitivity, NoGlassIndexMovesNothing) {
  TraceScene scene;
  scene.sheet = sheet_z(500);
  scene.solids.push_back({Sphere{Vector3d(0, 0, 300), 20}, TraceMaterial::opaque(0.5)});
  ModelTolerances tol = none();
  tol.refractive_index = 1e-3;
  const CameraModel model(160, 120, 200, 200, 79.5, 59.5);
  const SensitivityMap m = model_sensitivity(scene, model, RigidTransform{}, tol, 0, 0);
  ASSERT_EQ(m.parameters.size(), 1u);
  EXPECT_EQ(m.width, 20);
  EXPECT_EQ(m.height, 15);
  EXPECT_GT(m.valid_points, 200);
  EXPECT_LT(m.valid_points, 300);  // the opaque sphere hides the sheet in the middle
  for (std::size_t i = 0; i < m.valid.size(); ++i) {
    EXPECT_EQ(m.displacement_mm[i], 0.f);
    EXPECT_EQ(m.displacement_px[i], 0.f);
  }
}

// Slab lateral shift (perpendicular to the ray) for incidence theta in air.
double slab_shift(double d, double n, double theta) {
  const double s = std::sin(theta);
  return d * s * (1 - std::cos(theta) / std::sqrt(n * n - s * s));
}

TEST(Sensitivity, WindowIndexGivesSlabShiftDerivative) {
  const double d = 10, n = kNBk7, sigma = 5e-4;
  TraceScene scene;
  scene.sheet = sheet_z(400);
  scene.solids.push_back({make_slab(Vector3d(0, 0, 205), Vector3d::UnitZ(), d, 1e4), TraceMaterial::glass(n)});
  ModelTolerances tol = none();
  tol.refractive_index = sigma;
  const CameraModel model(96, 72, 80, 80, 47.5, 35.5);
  const RigidTransform pose = camera_from_world_look_at(Vector3d::Zero(), Vector3d(300, 100, 400), Vector3d(0, -1, 0));
  const SensitivityMap m = model_sensitivity(scene, model, pose, tol, 0, 0);
  ASSERT_EQ(m.valid_points, m.width * m.height);
  const SensitivityParameter& p = parameter(m, "refractive_index");
  for (int row = 0; row < m.height; ++row)
    for (int col = 0; col < m.width; ++col) {
      const std::size_t i = static_cast<std::size_t>(row * m.width + col);
      const double theta = std::acos(pixel_world_ray(model, pose, m.pixel_px(col, row))->direction.z());
      // Along the sheet (perpendicular to the normal) the shift is shift / cos(theta).
      const double central =
          0.5 * std::abs(slab_shift(d, n + sigma, theta) - slab_shift(d, n - sigma, theta)) / std::cos(theta);
      const double s = std::sin(theta);
      const double derivative = d * s * n / std::pow(n * n - s * s, 1.5) * sigma;
      EXPECT_NEAR(p.displacement_mm[i], central, 1e-6 * central + 1e-12);
      EXPECT_NEAR(p.displacement_mm[i], derivative, 1e-5 * derivative);
      EXPECT_EQ(m.displacement_mm[i], p.displacement_mm[i]);  // one parameter: the total is its contribution
    }
  EXPECT_GT(p.p95_mm, 1e-4);
}

TEST(Sensitivity, CameraTranslationParallelToTheSheet) {
  const double z = 500, f = 200, t = 0.1;
  TraceScene scene;
  scene.sheet = sheet_z(z);
  const CameraModel model(160, 120, f, f, 79.5, 59.5);
  ModelTolerances tol = none();
  tol.camera_position_mm = t;
  const SensitivityMap m = model_sensitivity(scene, model, RigidTransform{}, tol, 0, 0);
  ASSERT_EQ(m.valid_points, m.width * m.height);
  for (const char* name : {"camera_position_x", "camera_position_y"}) {
    const SensitivityParameter& p = parameter(m, name);
    for (std::size_t i = 0; i < m.valid.size(); ++i) {
      EXPECT_NEAR(p.displacement_mm[i], t, 1e-7 * t) << name;
      EXPECT_NEAR(p.displacement_px[i], f * t / z, 1e-6 * f * t / z) << name;
    }
    EXPECT_NEAR(p.median_mm, t, 1e-7 * t);
  }
  // The same from a pose covariance: translation of camera_from_world along x only.
  ModelTolerances cov = none();
  Eigen::Matrix<double, 6, 6> c = Eigen::Matrix<double, 6, 6>::Zero();
  c(3, 3) = t * t;
  cov.pose_covariance = c;
  const SensitivityMap mc = model_sensitivity(scene, model, RigidTransform{}, cov, 0, 0);
  ASSERT_EQ(mc.parameters.size(), 1u);
  for (std::size_t i = 0; i < mc.valid.size(); ++i) {
    EXPECT_NEAR(mc.displacement_mm[i], t, 1e-7 * t);
    EXPECT_NEAR(mc.displacement_px[i], f * t / z, 1e-6 * f * t / z);
  }
}

// A ball lens in front of the sheet, all tolerances at their defaults.
TraceScene ball_lens_scene() {
  TraceScene scene;
  scene.sheet = sheet_z(300, 400);
  scene.solids.push_back({Sphere{Vector3d(0, 0, 250), 20}, TraceMaterial::glass(kNBk7)});
  scene.solids.push_back({make_slab(Vector3d(0, 0, 150), Vector3d::UnitZ(), 10, 1e3), TraceMaterial::glass(kNBk7)});
  return scene;
}

TEST(Sensitivity, MonteCarloIsReproducibleFromItsSeed) {
  const TraceScene scene = ball_lens_scene();
  const CameraModel model(160, 120, 300, 300, 79.5, 59.5);
  const RigidTransform pose = camera_from_world_look_at(Vector3d(0, 0, -100), Vector3d(0, 0, 300), Vector3d(0, -1, 0));
  SensitivityOptions mc;
  mc.method = SensitivityMethod::monte_carlo;
  const SensitivityMap a = model_sensitivity(scene, model, pose, ModelTolerances{}, 64, 42, mc);
  const SensitivityMap b = model_sensitivity(scene, model, pose, ModelTolerances{}, 64, 42, mc);
  const SensitivityMap c = model_sensitivity(scene, model, pose, ModelTolerances{}, 64, 43, mc);
  EXPECT_EQ(a.displacement_mm, b.displacement_mm);
  EXPECT_EQ(a.displacement_px, b.displacement_px);
  EXPECT_EQ(a.valid, b.valid);
  EXPECT_NE(a.displacement_mm, c.displacement_mm);
  // Against first order: the medians agree within the sampling error (~9 % for 64 samples).
  const SensitivityMap f = model_sensitivity(scene, model, pose, ModelTolerances{}, 0, 0);
  EXPECT_GT(f.valid_points, 100);
  EXPECT_NEAR(a.median_mm, f.median_mm, 0.35 * f.median_mm);
  EXPECT_NEAR(a.median_px, f.median_px, 0.35 * f.median_px);
  // Thread count does not change the result.
  SensitivityOptions one;
  one.threads = 1;
  EXPECT_EQ(model_sensitivity(scene, model, pose, ModelTolerances{}, 0, 0, one).displacement_mm, f.displacement_mm);
}

TEST(Sensitivity, RejectsBadInput) {
  const TraceScene scene = ball_lens_scene();
  const CameraModel model(16, 12, 30, 30, 7.5, 5.5);
  ModelTolerances bad;
  bad.refractive_index = -1;
  EXPECT_THROW(model_sensitivity(scene, model, RigidTransform{}, bad, 0, 0), std::invalid_argument);
  SensitivityOptions mc;
  mc.method = SensitivityMethod::monte_carlo;
  EXPECT_THROW(model_sensitivity(scene, model, RigidTransform{}, ModelTolerances{}, 1, 0, mc), std::invalid_argument);
  ModelTolerances cov;
  cov.pose_covariance = -Eigen::Matrix<double, 6, 6>::Identity();
  EXPECT_THROW(model_sensitivity(scene, model, RigidTransform{}, cov, 0, 0), std::invalid_argument);
}

// The refusal's tolerance and a phrase of its message.
void expect_refused(const TraceScene& scene, const CameraModel& model, const RigidTransform& pose,
                    const ModelTolerances& tol, const std::string& tolerance, const std::string& problem_has,
                    int samples = 0) {
  SensitivityOptions options;
  if (samples > 0) options.method = SensitivityMethod::monte_carlo;
  try {
    model_sensitivity(scene, model, pose, tol, samples, 1, options);
    ADD_FAILURE() << "no error for " << tolerance;
  } catch (const SensitivityError& e) {
    EXPECT_EQ(e.tolerance(), tolerance) << e.what();
    EXPECT_NE(std::string(e.what()).find(problem_has), std::string::npos) << e.what();
  }
}

// Perturbed models must be scenes the tracer may trace: an index perturbation
// that takes the glass below 0.5 (refract_with_fresnel asserted n > 0 at -1
// sigma of --index 2), a diameter perturbation that makes a sphere vanish, a
// glass shift into an opaque solid, touching spheres grown into each other,
// and a rotation tolerance of no meaning are refused before any trace.
TEST(Sensitivity, InvalidPerturbedModelsAreRefusedNamingTheTolerance) {
  TraceScene scene = ball_lens_scene();
  const CameraModel model(32, 24, 60, 60, 15.5, 11.5);
  const RigidTransform pose = camera_from_world_look_at(Vector3d(0, 0, -100), Vector3d(0, 0, 300), Vector3d(0, -1, 0));
  ModelTolerances tol = none();
  tol.refractive_index = 2;
  expect_refused(scene, model, pose, tol, "refractive_index", "refractive index");
  tol.refractive_index = 0.4;  // 1.12 to 1.92: a valid model, measured
  EXPECT_GT(model_sensitivity(scene, model, pose, tol, 0, 0).valid_points, 0);
  tol = none();
  tol.sphere_diameter_mm = 50;  // -1 sigma: -10 mm across
  expect_refused(scene, model, pose, tol, "sphere_diameter_mm", "mm across");
  tol = none();
  tol.camera_rotation_deg = 1e300;
  expect_refused(scene, model, pose, tol, "camera_rotation_deg", "deg");
  tol = none();
  tol.camera_position_mm = 2e6;
  expect_refused(scene, model, pose, tol, "camera_position_mm", "beyond");

  // An opaque sphere 5 mm beside the ball lens: a 10 mm glass shift runs into it.
  scene.solids.push_back({Sphere{Vector3d(0, 45, 250), 20}, TraceMaterial::opaque(0.5)});
  tol = none();
  tol.glass_position_mm = 10;
  expect_refused(scene, model, pose, tol, "glass_position_mm", "overlap");
  tol.glass_position_mm = 1;
  EXPECT_GT(model_sensitivity(scene, model, pose, tol, 0, 0).valid_points, 0);
  // Monte Carlo draws are checked too: 4 mm 1-sigma reaches the 5 mm gap in some of 64 draws.
  tol.glass_position_mm = 4;
  expect_refused(scene, model, pose, tol, "", "Monte Carlo draw", 64);

  // Two touching glass spheres: a small diameter change is a contact, a large one an overlap.
  TraceScene pair;
  pair.sheet = sheet_z(300, 400);
  pair.solids.push_back({Sphere{Vector3d(-20, 0, 250), 20}, TraceMaterial::glass(kNBk7)});
  pair.solids.push_back({Sphere{Vector3d(20, 0, 250), 20}, TraceMaterial::glass(kNBk7)});
  tol = none();
  tol.sphere_diameter_mm = 0.02;
  EXPECT_GT(model_sensitivity(pair, model, pose, tol, 0, 0).valid_points, 0);
  tol.sphere_diameter_mm = 1;  // 2.5 % of 40 mm
  expect_refused(pair, model, pose, tol, "sphere_diameter_mm", "overlap");
}

// Nothing to measure is refused, not a table of zeros: every tolerance 0, a
// camera that sees no sheet, tolerances so large that no point keeps its view.
TEST(Sensitivity, NothingToMeasureIsRefused) {
  const TraceScene scene = ball_lens_scene();
  const CameraModel model(32, 24, 60, 60, 15.5, 11.5);
  const RigidTransform pose = camera_from_world_look_at(Vector3d(0, 0, -100), Vector3d(0, 0, 300), Vector3d(0, -1, 0));
  expect_refused(scene, model, pose, none(), "", "every tolerance is 0");
  const RigidTransform away = camera_from_world_look_at(Vector3d(0, 0, -100), Vector3d(0, 0, -300), Vector3d(0, -1, 0));
  expect_refused(scene, model, away, ModelTolerances{}, "", "sees the sheet directly");
  ModelTolerances tol = none();
  tol.camera_position_mm = 5e4;  // the sheet is 400 mm wide
  expect_refused(scene, model, pose, tol, "camera_position_mm", "none keeps its view");
}

void print_table(const char* what, const SensitivityMap& m, double seconds) {
  std::printf("%s: %dx%d grid, %d valid, %.2f s; total median %.4f px %.5f mm, p95 %.4f px %.5f mm\n", what, m.width,
              m.height, m.valid_points, seconds, m.median_px, m.median_mm, m.p95_px, m.p95_mm);
  for (const auto& p : m.parameters)
    std::printf("  %-20s sigma %-8g median %.4f px %.5f mm  p95 %.4f px %.5f mm\n", p.name.c_str(), p.sigma,
                p.median_px, p.median_mm, p.p95_px, p.p95_mm);
}

TEST(Sensitivity, MegapixelCameraTakesSeconds) {
  // 1000 x 1000 px, every 8th pixel; a window and a ball lens in front of the sheet.
  const TraceScene scene = ball_lens_scene();
  const CameraModel model(1000, 1000, 2000, 2000, 499.5, 499.5);
  const RigidTransform pose = camera_from_world_look_at(Vector3d(10, 5, -100), Vector3d(0, 0, 300), Vector3d(0, -1, 0));
  const auto t0 = std::chrono::steady_clock::now();
  const SensitivityMap m = model_sensitivity(scene, model, pose, ModelTolerances{}, 0, 0);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  print_table("window + ball lens, first order", m, s);
  EXPECT_GT(m.valid_points, m.width * m.height / 2);
  EXPECT_LT(s, 60);

  // Closer, so that the ball lens fills most of the picture; Monte Carlo as well.
  const RigidTransform near = camera_from_world_look_at(Vector3d(0, 0, 170), Vector3d(0, 0, 300), Vector3d(0, -1, 0));
  const CameraModel narrow(1000, 1000, 4000, 4000, 499.5, 499.5);
  const auto t1 = std::chrono::steady_clock::now();
  const SensitivityMap b = model_sensitivity(scene, narrow, near, ModelTolerances{}, 0, 0);
  print_table("ball lens, first order", b,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count());
  SensitivityOptions mc;
  mc.method = SensitivityMethod::monte_carlo;
  const auto t2 = std::chrono::steady_clock::now();
  const SensitivityMap c = model_sensitivity(scene, narrow, near, ModelTolerances{}, 32, 1, mc);
  print_table("ball lens, Monte Carlo 32", c,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t2).count());
  EXPECT_GT(b.valid_points, 0);
}

}  // namespace
}  // namespace glasspiv
