// Light-transport map and forward render: closed-form pinhole and slab
// crossings, Fresnel weights, weight conservation through the render,
// determinism over thread counts, the ball lens's inverted image.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "render/forward_render.h"
#include "render/path_tracer.h"
#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"
#include "render/transport_map.h"
#include "tests/render/test_maps.h"

namespace glasspiv {
namespace {

constexpr double kD = 200;  // camera-to-sheet distance (mm)

CameraModel pinhole() { return CameraModel(40, 30, 120.0, 110.0, 19.3, 14.6); }

TraceScene empty_scene() {
  TraceScene scene;
  scene.sheet.origin_mm = Eigen::Vector3d(0, 0, kD);
  scene.sheet.extent_s_mm = 1000;
  scene.sheet.extent_t_mm = 1000;
  return scene;
}

TraceScene slab_scene(double n, double thickness) {
  TraceScene scene = empty_scene();
  scene.solids.push_back(
      {make_slab(Eigen::Vector3d(0, 0, 60 + 0.5 * thickness), Eigen::Vector3d::UnitZ(), thickness, 1000),
       TraceMaterial::glass(n)});
  return scene;
}

// Tolerance of a float that stores a double: the float's rounding plus 1e-9 mm.
double float_tol(double exact) { return 1e-9 + std::abs(exact) * std::numeric_limits<float>::epsilon(); }

double fresnel_unpolarized(double n1, double n2, double cos_i) {
  const double sin_i = std::sqrt(std::max(0.0, 1 - cos_i * cos_i));
  const double sin_t = n1 / n2 * sin_i;
  const double cos_t = std::sqrt(1 - sin_t * sin_t);
  const double rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
  const double rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
  return 0.5 * (rs * rs + rp * rp);
}

TEST(TransportMap, EmptySceneIsThePinholeIntersection) {
  const CameraModel cam = pinhole();
  const TraceScene scene = empty_scene();
  const TransportMap map = build_transport_map(scene, cam, RigidTransform{}, TraceOptions{});
  ASSERT_EQ(map.pixel_offsets.size(), 40u * 30u + 1);
  EXPECT_EQ(map.stats.camera_rays, 40 * 30);
  EXPECT_EQ(map.stats.crossings, 40 * 30);
  EXPECT_EQ(map.stats.pixels_without_solid_hit, 40 * 30);
  for (int v = 0; v < 30; ++v) {
    for (int u = 0; u < 40; ++u) {
      const std::size_t p = static_cast<std::size_t>(v) * 40 + u;
      ASSERT_EQ(map.pixel_offsets[p + 1] - map.pixel_offsets[p], 1u);
      const std::uint32_t i = map.pixel_offsets[p];
      const double s = (u - cam.cx_px()) / cam.fx_px() * kD;
      const double t = (v - cam.cy_px()) / cam.fy_px() * kD;
      EXPECT_EQ(map.weight[i], 1.0f);
      EXPECT_EQ(map.tag[i], static_cast<std::uint8_t>(CrossingTag::direct));
      EXPECT_NEAR(map.s_mm[i], s, float_tol(s));
      EXPECT_NEAR(map.t_mm[i], t, float_tol(t));
      EXPECT_EQ(map.background_weight[p], 1.0f);  // the sheet is transparent: the ray goes on
      // The double-precision crossing the map was built from: 1e-9 mm.
      const auto ray = pixel_world_ray(cam, RigidTransform{}, Eigen::Vector2d(u, v));
      ASSERT_TRUE(ray);
      const TraceResult r = trace_ray(scene, ray->origin_mm, ray->direction);
      ASSERT_EQ(r.crossings.size(), 1u);
      EXPECT_NEAR(r.crossings[0].s_mm, s, 1e-9);
      EXPECT_NEAR(r.crossings[0].t_mm, t, 1e-9);
    }
  }
}

TEST(TransportMap, SupersamplingSplitsTheWeight) {
  const TransportMap map = build_transport_map(empty_scene(), pinhole(), RigidTransform{}, TraceOptions{}, 3);
  EXPECT_EQ(map.stats.camera_rays, 9 * 40 * 30);
  for (std::size_t p = 0; p < map.pixel_count(); ++p) {
    ASSERT_EQ(map.pixel_offsets[p + 1] - map.pixel_offsets[p], 9u);
    double sum = 0;
    for (std::uint32_t i = map.pixel_offsets[p]; i < map.pixel_offsets[p + 1]; ++i) sum += map.weight[i];
    EXPECT_NEAR(sum, 1.0, 1e-6);
  }
}

TEST(TransportMap, SlabShiftAndFresnelWeight) {
  const double n = 1.5, thickness = 10;
  const CameraModel cam = pinhole();
  const TraceScene scene = slab_scene(n, thickness);
  TraceOptions options;
  options.reflections = false;
  const TransportMap map = build_transport_map(scene, cam, RigidTransform{}, options);
  EXPECT_EQ(map.stats.pixels_without_solid_hit, 0);
  for (int v = 0; v < 30; v += 3) {
    for (int u = 0; u < 40; u += 3) {
      const double xn = (u - cam.cx_px()) / cam.fx_px(), yn = (v - cam.cy_px()) / cam.fy_px();
      const double rn = std::hypot(xn, yn);
      const double theta = std::atan(rn);
      const double sin_t = std::sin(theta), cos_t = std::cos(theta);
      // Perpendicular displacement of the ray, then its shift in the sheet plane.
      const double lateral = thickness * sin_t * (1 - cos_t / std::sqrt(n * n - sin_t * sin_t));
      const double radius = kD * rn - lateral / cos_t;
      const double s = rn > 0 ? xn / rn * radius : 0, t = rn > 0 ? yn / rn * radius : 0;
      const double one_minus_r = 1 - fresnel_unpolarized(1.0, n, cos_t);
      const std::size_t p = static_cast<std::size_t>(v) * 40 + u;
      ASSERT_EQ(map.pixel_offsets[p + 1] - map.pixel_offsets[p], 1u);
      const std::uint32_t i = map.pixel_offsets[p];
      EXPECT_EQ(map.tag[i], static_cast<std::uint8_t>(CrossingTag::refracted_only));
      EXPECT_NEAR(map.s_mm[i], s, float_tol(s) + 1e-7);
      EXPECT_NEAR(map.t_mm[i], t, float_tol(t) + 1e-7);
      EXPECT_NEAR(map.weight[i], one_minus_r * one_minus_r, 1e-7);
      const auto ray = pixel_world_ray(cam, RigidTransform{}, Eigen::Vector2d(u, v));
      const TraceResult r = trace_ray(scene, ray->origin_mm, ray->direction, options);
      ASSERT_EQ(r.crossings.size(), 1u);
      EXPECT_NEAR(r.crossings[0].s_mm, s, 1e-9);
      EXPECT_NEAR(r.crossings[0].t_mm, t, 1e-9);
      EXPECT_NEAR(r.crossings[0].weight, one_minus_r * one_minus_r, 1e-12);
    }
  }
}

TEST(ForwardRender, ConstantTextureGivesTheSheetWeight) {
  const SheetSampler one = [](double, double) { return 1.0f; };
  {
    const TransportMap map = build_transport_map(empty_scene(), pinhole(), RigidTransform{}, TraceOptions{});
    const cv::Mat image = forward_render(map, one, 0.0);
    ASSERT_EQ(image.type(), CV_32F);
    ASSERT_EQ(image.rows, 30);
    ASSERT_EQ(image.cols, 40);
    for (int v = 0; v < 30; ++v)
      for (int u = 0; u < 40; ++u) EXPECT_EQ(image.at<float>(v, u), 1.0f);
  }
  TraceOptions options;
  options.reflections = true;
  options.min_weight = 1e-14;
  options.max_depth = 64;
  const TransportMap map = build_transport_map(slab_scene(1.5, 10), pinhole(), RigidTransform{}, options);
  const cv::Mat image = forward_render(map, one, 0.0);
  const cv::Mat with_background = forward_render(map, one, 1.0);
  bool multiple = false;
  for (int v = 0; v < 30; ++v) {
    for (int u = 0; u < 40; ++u) {
      const std::size_t p = static_cast<std::size_t>(v) * 40 + u;
      double sum = 0;
      for (std::uint32_t i = map.pixel_offsets[p]; i < map.pixel_offsets[p + 1]; ++i) sum += map.weight[i];
      multiple |= map.pixel_offsets[p + 1] - map.pixel_offsets[p] > 1;
      EXPECT_NEAR(image.at<float>(v, u), sum, 1e-6);
      // Lossless slab, all inter-reflections: T^2 sum R^2k = (1 - R) / (1 + R).
      const double xn = (u - 19.3) / 120.0, yn = (v - 14.6) / 110.0;
      const double r = fresnel_unpolarized(1.0, 1.5, 1 / std::sqrt(1 + xn * xn + yn * yn));
      EXPECT_NEAR(image.at<float>(v, u), (1 - r) / (1 + r), 1e-6);
      // The sheet is transparent: every bit of weight ends in the background.
      EXPECT_NEAR(with_background.at<float>(v, u) - image.at<float>(v, u), 1.0, 1e-6);
    }
  }
  EXPECT_TRUE(multiple);  // inter-reflections in the slab reach the sheet
}

TEST(TransportMap, DeterministicOverThreadCounts) {
  TraceScene scene = slab_scene(1.5, 10);
  scene.solids.push_back({Sphere{Eigen::Vector3d(3, -2, 120), 15}, TraceMaterial::glass(1.6, 0.01)});
  TraceOptions options;
  options.min_weight = 1e-5;
  const TransportMap a = build_transport_map(scene, pinhole(), RigidTransform{}, options, 2, 1);
  const TransportMap b = build_transport_map(scene, pinhole(), RigidTransform{}, options, 2, 2);
  EXPECT_EQ(a.stats.threads, 1);
  EXPECT_EQ(b.stats.threads, 2);
  expect_same_map_arrays(a, b);
  EXPECT_EQ(a.stats.branches_traced, b.stats.branches_traced);
  EXPECT_GT(a.crossing_count(), a.pixel_count());
}

// The map stores float32; the tracer works in double. Every stored crossing
// equals the double tracer's to float rounding: |s| <= 65 mm here, so half an
// ulp is <= 65 * 2^-24 mm = 3.9 nm. The figure is reported in micrometres.
TEST(TransportMap, FloatMapMatchesTheDoubleTracerToFloatRounding) {
  const Scene scene = read_scene(std::string(GLASSPIV_SOURCE_DIR) + "/data/scenes/reactor.yaml");
  const TraceScene ts = build_trace_scene(scene);
  const Camera& camera = scene.cameras[0].camera;
  const CameraModel cam = binned(camera.model, 32);  // 80 x 67 px over the whole view
  const TransportMap map = build_transport_map(ts, cam, *camera.camera_from_world, TraceOptions{}, 1, 2);
  const auto index = make_scene_index(ts);
  TraceResult r;
  std::size_t i = 0;
  double worst_um = 0, worst_rel_jacobian = 0;
  for (int row = 0; row < cam.height_px(); ++row) {
    for (int col = 0; col < cam.width_px(); ++col) {
      trace_ray(ts, *index, *pixel_camera_ray(cam, *camera.camera_from_world, Eigen::Vector2d(col, row)), TraceOptions{}, &r);
      for (const SheetCrossing& c : r.crossings) {
        ASSERT_LT(i, map.crossing_count());
        EXPECT_LE(std::abs(c.s_mm - map.s_mm[i]), float_tol(c.s_mm));
        EXPECT_LE(std::abs(c.t_mm - map.t_mm[i]), float_tol(c.t_mm));
        worst_um = std::max({worst_um, 1e3 * std::abs(c.s_mm - map.s_mm[i]), 1e3 * std::abs(c.t_mm - map.t_mm[i])});
        const double j = c.dst_dpixel.norm();
        worst_rel_jacobian = std::max(worst_rel_jacobian, std::abs(c.dst_dpixel(0, 0) - map.ds_dcol[i]) / j);
        ++i;
      }
    }
  }
  EXPECT_EQ(i, map.crossing_count());
  EXPECT_GT(i, 1000u);
  EXPECT_LT(worst_rel_jacobian, 1e-7);
  std::printf("float map vs double tracer: %zu crossings, worst %.4f um on the sheet, footprint %.1e relative\n", i,
              worst_um, worst_rel_jacobian);
}

TEST(TraceSceneBuilder, ConvertsSolidsAndSheet) {
  Scene scene;
  scene.fluid = "water";
  SphereSolid s;
  s.centre_mm = Eigen::Vector3d(1, 2, 3);
  s.diameter_mm = 10;
  s.material = "N-BK7";
  scene.spheres.push_back(s);
  CylinderSolid c;
  c.base_centre_mm = Eigen::Vector3d(0, 0, 50);
  c.axis = Eigen::Vector3d::UnitY();
  c.radius_mm = 4;
  c.length_mm = 20;
  c.material = "PMMA";
  scene.cylinders.push_back(c);
  Sheet sheet;
  sheet.extent_mm = {80, 60};
  scene.sheet = sheet;
  TraceSceneBuildInfo info;
  const TraceScene ts = build_trace_scene(scene, &info);
  EXPECT_EQ(info.spheres, 1);
  EXPECT_EQ(info.cylinders, 1);
  ASSERT_EQ(ts.solids.size(), 2u);
  EXPECT_DOUBLE_EQ(ts.fluid_index, material_from_name("water").refractive_index(532));
  EXPECT_DOUBLE_EQ(ts.solids[0].material.refractive_index, material_from_name("N-BK7").refractive_index(532));
  EXPECT_DOUBLE_EQ(std::get<Sphere>(ts.solids[0].shape).radius_mm, 5);
  const Cylinder& cyl = std::get<Cylinder>(ts.solids[1].shape);
  EXPECT_TRUE(cyl.centre_mm.isApprox(Eigen::Vector3d(0, 10, 50)));
  EXPECT_DOUBLE_EQ(cyl.half_length_mm, 10);
  EXPECT_DOUBLE_EQ(ts.sheet.extent_s_mm, 80);
  EXPECT_DOUBLE_EQ(ts.sheet.extent_t_mm, 60);
  scene.sheet.reset();
  EXPECT_THROW(build_trace_scene(scene), std::invalid_argument);
}

// The ball lens images the sheet behind it upside down: inside the sphere's
// disc s runs against the image column, outside it runs with it.
TEST(TransportMap, BallLensInvertsTheImage) {
  const Scene scene = read_scene(GLASSPIV_SOURCE_DIR "/data/scenes/ball_lens.yaml");
  const TraceScene ts = build_trace_scene(scene);
  const Camera& full = scene.cameras.at(0).camera;
  const int k = 8;
  const CameraModel& m = full.model;
  const CameraModel cam(m.width_px() / k, m.height_px() / k, m.fx_px() / k, m.fy_px() / k,
                        (m.cx_px() + 0.5) / k - 0.5, (m.cy_px() + 0.5) / k - 0.5, m.distortion());
  const RigidTransform& pose = *full.camera_from_world;
  TraceOptions options;
  options.min_weight = 1e-4;
  const TransportMap map = build_transport_map(ts, cam, pose, options);
  const auto centre = cam.project(pose.apply(Eigen::Vector3d::Zero()));
  ASSERT_TRUE(centre);
  const int uc = static_cast<int>(std::lround(centre->x())), vc = static_cast<int>(std::lround(centre->y()));
  auto main_s = [&](int u, int v) {
    const std::size_t p = static_cast<std::size_t>(v) * map.width + u;
    float best_w = -1, s = std::numeric_limits<float>::quiet_NaN();
    for (std::uint32_t i = map.pixel_offsets[p]; i < map.pixel_offsets[p + 1]; ++i)
      if (map.weight[i] > best_w) best_w = map.weight[i], s = map.s_mm[i];
    return s;
  };
  const double ds_du_inside = 0.5 * (main_s(uc + 1, vc) - main_s(uc - 1, vc));
  const int uo = uc + 60;  // the disc: ~38 px radius; the sheet (+-50 mm): ~88 px
  ASSERT_LT(uo + 1, map.width);
  const double ds_du_outside = 0.5 * (main_s(uo + 1, vc) - main_s(uo - 1, vc));
  ASSERT_TRUE(std::isfinite(ds_du_inside));
  ASSERT_TRUE(std::isfinite(ds_du_outside));
  EXPECT_NE(ds_du_inside, 0);
  EXPECT_LT(ds_du_inside * ds_du_outside, 0) << ds_du_inside << " vs " << ds_du_outside;
  EXPECT_GT(map.stats.pixels_without_solid_hit, 0);
  EXPECT_LT(map.stats.pixels_without_solid_hit, static_cast<long>(map.pixel_count()));
}

}  // namespace
}  // namespace glasspiv
