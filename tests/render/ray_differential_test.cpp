// Ray differentials and the Embree scene index: footprint Jacobians against
// the pinhole closed form and against finite differences of traced rays
// through spheres, a cylinder and a slab (refraction, reflection, TIR); the
// BVH gives bit-identical paths to the linear-search reference.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "render/path_tracer.h"
#include "render/scene_index.h"
#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"

namespace glasspiv {
namespace {

CameraModel camera() { return CameraModel(64, 48, 90.0, 88.0, 31.7, 23.2); }

TEST(RayDifferentials, EmptySceneFootprintIsThePinholeJacobian) {
  TraceScene scene;
  scene.sheet.origin_mm = Eigen::Vector3d(0, 0, 250);
  scene.sheet.extent_s_mm = scene.sheet.extent_t_mm = 1e4;
  const auto index = make_scene_index(scene);
  TraceResult r;
  for (double u : {0.0, 17.3, 63.0}) {
    for (double v : {0.0, 30.1, 47.0}) {
      const auto ray = pixel_camera_ray(camera(), RigidTransform{}, Eigen::Vector2d(u, v));
      ASSERT_TRUE(ray);
      trace_ray(scene, *index, *ray, TraceOptions{}, &r);
      ASSERT_EQ(r.crossings.size(), 1u);
      // s = (u - cx) / fx * D, t = (v - cy) / fy * D (sheet axes x, y): exact
      // up to round-off.
      EXPECT_NEAR(r.crossings[0].dst_dpixel(0, 0), 250.0 / 90.0, 1e-12);
      EXPECT_NEAR(r.crossings[0].dst_dpixel(1, 1), 250.0 / 88.0, 1e-12);
      EXPECT_NEAR(r.crossings[0].dst_dpixel(0, 1), 0.0, 1e-12);
      EXPECT_NEAR(r.crossings[0].dst_dpixel(1, 0), 0.0, 1e-12);
      EXPECT_EQ(r.counts.closed_form, 1);  // no solid: no BVH query
    }
  }
}

// The camera ray's differential through a strongly distorted lens (rational
// model) against central differences of the unprojected directions.
TEST(RayDifferentials, CameraRayDifferentialThroughLensDistortion) {
  const CameraModel lens(640, 480, 500, 510, 321.3, 238.9, {-0.25, 0.08, 1e-3, -2e-3, -0.01, 0.02, 0.005, 0.001});
  const RigidTransform pose{Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix(),
                            Eigen::Vector3d(10, -20, 300)};
  const double h = 1e-3;
  double worst = 0;
  for (double u : {0.0, 101.7, 320.0, 639.0})
    for (double v : {0.0, 240.2, 479.0}) {
      const Eigen::Vector2d px(u, v);
      const auto ray = pixel_camera_ray(lens, pose, px);
      ASSERT_TRUE(ray);
      for (int axis = 0; axis < 2; ++axis) {
        const Eigen::Vector2d step = axis == 0 ? Eigen::Vector2d(h, 0) : Eigen::Vector2d(0, h);
        const auto p = pixel_camera_ray(lens, pose, px + step), m = pixel_camera_ray(lens, pose, px - step);
        ASSERT_TRUE(p && m);
        const Eigen::Vector3d fd = (p->direction - m->direction) / (2 * h);
        worst = std::max(worst, (fd - ray->ddirection_dpixel.col(axis)).norm() / fd.norm());
      }
    }
  // Central differences of a 1e-10 px accurate unprojection: truncation ~h^2,
  // round-off ~1e-10 px / h relative to ~1 px.
  EXPECT_LT(worst, 1e-6);
}

// Spheres (one in front of the sheet, one cut by it), a cylinder and a slab.
TraceScene glass_scene() {
  TraceScene scene;
  scene.fluid_index = 1.333;
  scene.sheet.origin_mm = Eigen::Vector3d(0, 0, 300);
  scene.sheet.s_axis = Eigen::Vector3d(-1, 0, 0);
  scene.sheet.extent_s_mm = scene.sheet.extent_t_mm = 2000;
  scene.solids.push_back({Sphere{Eigen::Vector3d(-30, 10, 200), 45}, TraceMaterial::glass(1.52)});
  scene.solids.push_back({Sphere{Eigen::Vector3d(40, -30, 300), 30}, TraceMaterial::glass(1.6)});
  Cylinder c;
  c.centre_mm = Eigen::Vector3d(60, 40, 180);
  c.axis = Eigen::Vector3d(0.2, 1, 0.1).normalized();
  c.radius_mm = 20;
  c.half_length_mm = 40;
  scene.solids.push_back({c, TraceMaterial::glass(1.47)});
  scene.solids.push_back({make_slab(Eigen::Vector3d(0, 0, 100), Eigen::Vector3d(0.1, 0, 1), 8, 500),
                          TraceMaterial::glass(1.5)});
  return scene;
}

// Central differences of every crossing's (s, t) over +-h pixels, matched by
// order (the branch order is deterministic); pixels whose neighbours take
// another path (different count or tags) are skipped: their footprint is cut by
// an edge, where no derivative exists.
TEST(RayDifferentials, FootprintsMatchFiniteDifferencesThroughGlass) {
  const TraceScene scene = glass_scene();
  const auto index = make_scene_index(scene);
  TraceOptions options;
  options.min_weight = 1e-4;
  const double h = 1e-4;  // px: truncation ~h^2 f''' , round-off ~1e-13 mm / h
  int compared = 0, refracted = 0, reflected = 0;
  double worst = 0;
  TraceResult r0, rp, rm, rp2, rm2;
  for (int v = 1; v < 48; v += 3) {
    for (int u = 1; u < 64; u += 3) {
      const Eigen::Vector2d px(u + 0.3, v + 0.2);
      const auto ray = pixel_camera_ray(camera(), RigidTransform{}, px);
      ASSERT_TRUE(ray);
      trace_ray(scene, *index, *ray, options, &r0);
      for (int axis = 0; axis < 2; ++axis) {
        const Eigen::Vector2d step = axis == 0 ? Eigen::Vector2d(h, 0) : Eigen::Vector2d(0, h);
        trace_ray(scene, *index, *pixel_camera_ray(camera(), RigidTransform{}, px + step), options, &rp);
        trace_ray(scene, *index, *pixel_camera_ray(camera(), RigidTransform{}, px - step), options, &rm);
        trace_ray(scene, *index, *pixel_camera_ray(camera(), RigidTransform{}, px + 2 * step), options, &rp2);
        trace_ray(scene, *index, *pixel_camera_ray(camera(), RigidTransform{}, px - 2 * step), options, &rm2);
        const std::size_t n = r0.crossings.size();
        if (rp.crossings.size() != n || rm.crossings.size() != n || rp2.crossings.size() != n ||
            rm2.crossings.size() != n)
          continue;
        for (std::size_t i = 0; i < n; ++i) {
          const SheetCrossing &c = r0.crossings[i], &p = rp.crossings[i], &m = rm.crossings[i];
          const SheetCrossing &p2 = rp2.crossings[i], &m2 = rm2.crossings[i];
          if (p.depth != c.depth || m.depth != c.depth || p.tag != c.tag || m.tag != c.tag || p2.tag != c.tag ||
              m2.tag != c.tag)
            continue;
          const Eigen::Vector2d fd((p.s_mm - m.s_mm) / (2 * h), (p.t_mm - m.t_mm) / (2 * h));
          const Eigen::Vector2d fd2((p2.s_mm - m2.s_mm) / (4 * h), (p2.t_mm - m2.t_mm) / (4 * h));
          const Eigen::Vector2d an = c.dst_dpixel.col(axis);
          // Central differences err by ~h^2 f'''/6, estimated by |fd(h) - fd(2h)| / 3
          // (large near caustics and grazing exits, where footprints reach
          // metres per pixel); a wrong formula errs by O(|J|).
          const double allowed = 1e-6 * std::max(1.0, an.norm()) + (fd - fd2).norm();
          const double err = (fd - an).norm();
          worst = std::max(worst, err / std::max(1.0, an.norm()));
          EXPECT_LT(err, allowed) << "pixel " << px.transpose() << " crossing " << i << " axis " << axis << "\n"
                                  << fd.transpose() << " vs " << an.transpose();
          ++compared;
          refracted += c.tag == CrossingTag::refracted_only;
          reflected += c.tag == CrossingTag::with_reflections;
        }
      }
    }
  }
  // The scene must exercise every kind of path.
  EXPECT_GT(compared, 1000);
  EXPECT_GT(refracted, 200);
  EXPECT_GT(reflected, 200);
  std::printf("footprint vs finite differences: %d crossings, worst relative error %.2e\n", compared, worst);
}

// The BVH changes the speed, never the answer: identical paths (bit for bit)
// to the linear search on random rays through the example reactor.
TEST(SceneIndex, EmbreeMatchesLinearSearchBitForBit) {
  const Scene scene = read_scene(std::string(GLASSPIV_SOURCE_DIR) + "/data/scenes/reactor.yaml");
  const TraceScene ts = build_trace_scene(scene);
  std::vector<Shape> shapes;
  for (const auto& s : ts.solids) shapes.push_back(s.shape);
  const LinearSceneIndex linear(shapes);
  const EmbreeSceneIndex embree(shapes);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-120, 160), dir(-1, 1);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d o(pos(rng), pos(rng), pos(rng) - 100);
    const Eigen::Vector3d d = Eigen::Vector3d(dir(rng), dir(rng), dir(rng)).normalized();
    const auto a = linear.first_hit(o, d, 0.0), b = embree.first_hit(o, d, 0.0);
    ASSERT_EQ(a.has_value(), b.has_value()) << i;
    if (!a) continue;
    ++hits;
    EXPECT_EQ(a->shape_index, b->shape_index);
    EXPECT_EQ(a->t, b->t);
    EXPECT_EQ(a->point, b->point);
    // With the nearest solid skipped, both find the same one behind it.
    const auto a2 = linear.first_hit(o, d, 0.0, a->shape_index), b2 = embree.first_hit(o, d, 0.0, a->shape_index);
    ASSERT_EQ(a2.has_value(), b2.has_value()) << i;
    if (!a2) continue;
    EXPECT_NE(a2->shape_index, a->shape_index);
    EXPECT_EQ(a2->shape_index, b2->shape_index);
    EXPECT_EQ(a2->t, b2->t);
    EXPECT_GE(a2->t, a->t);
  }
  EXPECT_GT(hits, 2000);
  // Whole paths through the packing, every branch.
  TraceOptions options;
  options.min_weight = 1e-5;
  TraceResult ra, rb;
  for (int i = 0; i < 300; ++i) {
    CameraRay ray;
    ray.origin_mm = Eigen::Vector3d(pos(rng) * 0.3, pos(rng) * 0.3, -600);
    ray.direction = Eigen::Vector3d(-ray.origin_mm.x(), -ray.origin_mm.y(), 600).normalized() +
                    Eigen::Vector3d(dir(rng), dir(rng), 0) * 0.05;
    trace_ray(ts, linear, ray, options, &ra);
    trace_ray(ts, embree, ray, options, &rb);
    ASSERT_EQ(ra.crossings.size(), rb.crossings.size());
    for (std::size_t k = 0; k < ra.crossings.size(); ++k) EXPECT_EQ(ra.crossings[k].point_mm, rb.crossings[k].point_mm);
    EXPECT_EQ(ra.counts.branches_traced, rb.counts.branches_traced);
    EXPECT_EQ(ra.background_weight, rb.background_weight);
  }
}

}  // namespace
}  // namespace glasspiv
