// Meshes in the tracer: a refined smooth icosphere ball lens converges to the
// analytic sphere on the sheet (positions and footprints), a flat-shaded one
// converges more slowly, and a scene file's mesh reaches the tracer.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "render/path_tracer.h"
#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"
#include "render/transport_map_file.h"
#include "tests/render/test_meshes.h"

namespace glasspiv {
namespace {

TraceScene lens_scene(Shape lens) {
  TraceScene scene;
  scene.sheet.origin_mm = Eigen::Vector3d(0, 0, 60);
  scene.sheet.extent_s_mm = scene.sheet.extent_t_mm = 1000;
  scene.solids.push_back({std::move(lens), TraceMaterial::glass(1.5168)});
  return scene;
}

struct Worst {
  double point_mm = 0, jacobian = 0;
};

// Rays from a point 400 mm in front of the lens, over impact parameters up to
// 0.8 R, refraction only: the first crossing of each through the mesh vs
// through the exact sphere.
Worst compare(const TraceScene& mesh_scene, const TraceScene& exact_scene) {
  const auto mesh_index = make_scene_index(mesh_scene), exact_index = make_scene_index(exact_scene);
  TraceOptions options;
  options.reflections = false;
  TraceResult rm, re;
  Worst w;
  for (int i = 0; i < 400; ++i) {
    const double phi = 2.399963 * i, rho = 0.8 * 20 * std::sqrt((i + 0.5) / 400);  // sunflower over the aperture
    CameraRay ray;
    ray.origin_mm = Eigen::Vector3d(0, 0, -400);
    ray.direction = Eigen::Vector3d(rho * std::cos(phi), rho * std::sin(phi), 400).normalized();
    ray.ddirection_dpixel << 1e-3, 0, 0, 1e-3, 0, 0;
    trace_ray(mesh_scene, *mesh_index, ray, options, &rm);
    trace_ray(exact_scene, *exact_index, ray, options, &re);
    EXPECT_EQ(rm.crossings.size(), 1u) << i;
    EXPECT_EQ(re.crossings.size(), 1u) << i;
    if (rm.crossings.size() != 1 || re.crossings.size() != 1) continue;
    const SheetCrossing &a = rm.crossings[0], &b = re.crossings[0];
    w.point_mm = std::max(w.point_mm, std::hypot(a.s_mm - b.s_mm, a.t_mm - b.t_mm));
    w.jacobian = std::max(w.jacobian, (a.dst_dpixel - b.dst_dpixel).norm() / b.dst_dpixel.norm());
  }
  return w;
}

TEST(MeshTracer, SmoothIcosphereConvergesToTheAnalyticBallLens) {
  const TraceScene exact = lens_scene(Sphere{Eigen::Vector3d::Zero(), 20});
  std::vector<Worst> smooth, flat;
  for (int level = 3; level <= 6; ++level) {
    MeshBuildOptions so;
    so.shading = MeshShading::smooth;
    smooth.push_back(compare(lens_scene(build_triangle_mesh(icosphere(level), so)), exact));
    MeshBuildOptions fo;
    fo.shading = MeshShading::flat;
    flat.push_back(compare(lens_scene(build_triangle_mesh(icosphere(level), fo)), exact));
    std::printf("level %d: smooth %.3e mm (footprint %.2e rel), flat %.3e mm (footprint %.2e rel)\n", level,
                smooth.back().point_mm, smooth.back().jacobian, flat.back().point_mm, flat.back().jacobian);
  }
  // Each level halves the edge length h. Positions on the sheet depend on
  // the surface point (error ~h^2) and the normal: smooth normals err ~h^2,
  // so the crossing errs ~h^2 (ratio 4 per level); flat facets' normals err
  // ~h, so they converge like h at best (ratio ~2).
  for (std::size_t i = 1; i < smooth.size(); ++i) {
    const double ratio = smooth[i - 1].point_mm / smooth[i].point_mm;
    EXPECT_GT(ratio, 3.0) << "level " << i + 3;
    EXPECT_LT(ratio, 5.5) << "level " << i + 3;
    EXPECT_LT(flat[i - 1].point_mm / flat[i].point_mm, 3.0) << "level " << i + 3;
  }
  // Level 6 (81920 triangles, h ~ 0.5 mm on a 40 mm lens).
  EXPECT_LT(smooth.back().point_mm, 0.05);
  EXPECT_LT(smooth.back().jacobian, 0.05);
  EXPECT_LT(smooth.back().point_mm, flat.back().point_mm / 5);
}

TEST(MeshTracer, SceneFileMeshReachesTheTracerAndTheFingerprint) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("glasspiv_mesh_tracer_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  // A 20 mm cube of glass, as an OBJ with outward faces.
  const auto write_cube = [&](double size) {
    std::ofstream obj(dir / "cube.obj");
    const double h = size / 2;
    for (int i = 0; i < 8; ++i) obj << "v " << (i & 1 ? h : -h) << ' ' << (i & 2 ? h : -h) << ' ' << (i & 4 ? h : -h) << '\n';
    obj << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
  };
  write_cube(20);
  std::ofstream(dir / "scene.yaml") << R"(glasspiv_scene: 1
fluid: air
meshes:
  - {file: cube.obj, material: N-BK7, normals: flat}
sheet: {origin_mm: [0, 0, 50], s_axis: [1, 0, 0], t_axis: [0, 1, 0], extent_mm: [200, 200], thickness_mm: 1}
cameras:
  - name: c
    model: {image_size_px: [40, 30], lens_model: pinhole, focal_length_px: [100, 100], principal_point_px: [19.5, 14.5]}
    pose: {position_mm: [0, 0, -300], look_at_mm: [0, 0, 0], up: [0, 1, 0]}
)";
  const Scene scene = read_scene((dir / "scene.yaml").string());
  TraceSceneBuildInfo info;
  const TraceScene ts = build_trace_scene(scene, &info);
  EXPECT_EQ(info.meshes, 1);
  ASSERT_EQ(ts.solids.size(), 1u);
  ASSERT_TRUE(std::holds_alternative<TriangleMesh>(ts.solids[0].shape));
  // On the axis the cube is a 20 mm slab at normal incidence: the ray goes
  // straight through with transmittance (1 - R)^2 and no shift.
  TraceOptions options;
  options.reflections = false;
  const TraceResult r = trace_ray(ts, Eigen::Vector3d(0, 0, -300), Eigen::Vector3d(0, 0, 1), options);
  ASSERT_EQ(r.crossings.size(), 1u);
  const double n = ts.solids[0].material.refractive_index / ts.fluid_index, R = std::pow((n - 1) / (n + 1), 2);
  EXPECT_NEAR(r.crossings[0].weight, (1 - R) * (1 - R), 1e-12);
  EXPECT_NEAR(r.crossings[0].s_mm, 0, 1e-12);
  const Camera& cam = scene.cameras[0].camera;
  const std::uint64_t f1 = transport_map_fingerprint(ts, cam.model, *cam.camera_from_world, options, 1);
  write_cube(20.001);
  const TraceScene ts2 = build_trace_scene(read_scene((dir / "scene.yaml").string()));
  EXPECT_NE(f1, transport_map_fingerprint(ts2, cam.model, *cam.camera_from_world, options, 1));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace glasspiv
