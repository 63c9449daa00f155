// Overlapping solids: exact pairs (sphere-sphere, sphere-box, box-box,
// sphere-cylinder) decided to the tolerance, touching allowed; sampled pairs
// (meshes, cylinder-box) find real overlaps; the scene builder refuses them
// naming both fields; touching packings pass.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "render/overlap.h"
#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"
#include "tests/render/test_meshes.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

Box box(const Eigen::Vector3d& centre, const Eigen::Vector3d& half, const Eigen::Matrix3d& r = Eigen::Matrix3d::Identity()) {
  Box b;
  b.centre_mm = centre;
  b.half_extent_mm = half;
  b.world_from_box = r;
  return b;
}

TEST(Overlap, SphereAndBoxExactToTheTolerance) {
  const Sphere s{Eigen::Vector3d(0, 0, 0), 10};
  // Box face at x = 10: touching; at x = 9.99: overlapping by 0.01 mm.
  EXPECT_FALSE(overlap(s, box(Eigen::Vector3d(15, 0, 0), Eigen::Vector3d(5, 5, 5))));
  EXPECT_TRUE(overlap(s, box(Eigen::Vector3d(14.99, 0, 0), Eigen::Vector3d(5, 5, 5))));
  // Near a box corner: the corner at distance 10 - 1e-3 from the centre.
  const double c = (10 - 1e-3) / std::sqrt(3.0);
  EXPECT_TRUE(overlap(s, box(Eigen::Vector3d(c + 1, c + 1, c + 1), Eigen::Vector3d(1, 1, 1))));
  const double c2 = (10 + 1e-3) / std::sqrt(3.0);
  EXPECT_FALSE(overlap(s, box(Eigen::Vector3d(c2 + 1, c2 + 1, c2 + 1), Eigen::Vector3d(1, 1, 1))));
}

TEST(Overlap, RotatedBoxesBySeparatingAxes) {
  const Eigen::Matrix3d r45 = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Box a = box(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 1, 1));
  // A diamond whose corner points at a's face x = 1: its corner at x = 3 - sqrt(2).
  EXPECT_TRUE(overlap(a, box(Eigen::Vector3d(2.4, 0, 0), Eigen::Vector3d(1, 1, 1), r45)));   // corner at 0.986
  EXPECT_FALSE(overlap(a, box(Eigen::Vector3d(2.42, 0, 0), Eigen::Vector3d(1, 1, 1), r45)));  // corner at 1.006
  // Two unit cubes sharing a face touch.
  EXPECT_FALSE(overlap(a, box(Eigen::Vector3d(2, 0.5, 0), Eigen::Vector3d(1, 1, 1))));
  // An edge-to-edge crossing that no face axis separates.
  const Eigen::Matrix3d tilt = (Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitX()) *
                                Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY())).toRotationMatrix();
  EXPECT_FALSE(overlap(a, box(Eigen::Vector3d(3, 3, 0), Eigen::Vector3d(1, 1, 1), tilt)));
}

TEST(Overlap, SphereAndCylinder) {
  Cylinder c;
  c.centre_mm = Eigen::Vector3d::Zero();
  c.axis = Eigen::Vector3d::UnitZ();
  c.radius_mm = 5;
  c.half_length_mm = 10;
  EXPECT_FALSE(overlap(Sphere{Eigen::Vector3d(8, 0, 0), 3}, c));         // touches the side
  EXPECT_TRUE(overlap(Sphere{Eigen::Vector3d(8, 0, 0), 3.01}, c));
  EXPECT_FALSE(overlap(Sphere{Eigen::Vector3d(0, 0, 13), 3}, c));        // touches the cap
  EXPECT_TRUE(overlap(Sphere{Eigen::Vector3d(0, 0, 12.99), 3}, c));
  const double d = 3 / std::sqrt(2.0);                                    // the rim: distance 3 at 45 deg
  EXPECT_FALSE(overlap(Sphere{Eigen::Vector3d(5 + d + 1e-4, 0, 10 + d + 1e-4), 3}, c));
  EXPECT_TRUE(overlap(Sphere{Eigen::Vector3d(5 + d - 1e-2, 0, 10 + d - 1e-2), 3}, c));
}

TEST(Overlap, MeshesBySampling) {
  const TriangleMesh ball = build_triangle_mesh(icosphere(3, 20));
  EXPECT_TRUE(overlap(ball, box(Eigen::Vector3d(25, 0, 0), Eigen::Vector3d(10, 10, 10))));   // 5 mm deep
  EXPECT_FALSE(overlap(ball, box(Eigen::Vector3d(31, 0, 0), Eigen::Vector3d(10, 10, 10))));  // 1 mm apart
  EXPECT_TRUE(overlap(ball, Sphere{Eigen::Vector3d(0, 0, 0), 5}));                           // inside it
}

TEST(Overlap, FindsThePairAndSkipsTouchingPackings) {
  const Scene scene = read_scene(std::string(GLASSPIV_SOURCE_DIR) + "/data/scenes/reactor.yaml");
  const TraceScene ts = build_trace_scene(scene);  // 39 touching spheres: fine
  std::vector<Shape> shapes;
  for (const auto& s : ts.solids) shapes.push_back(s.shape);
  EXPECT_FALSE(find_overlap(shapes));
  // A plate through the first layer's centre sphere (index 4: layer 0, i = 1, j = 1).
  shapes.push_back(box(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(100, 100, 1)));
  const auto pair = find_overlap(shapes);
  ASSERT_TRUE(pair);
  EXPECT_EQ(pair->second, 39);
  EXPECT_TRUE(overlap(shapes[static_cast<std::size_t>(pair->first)], shapes[39]));
}

TEST(Overlap, SceneBuilderNamesBothFields) {
  Scene scene = read_scene(std::string(GLASSPIV_SOURCE_DIR) + "/data/scenes/ball_lens.yaml");
  BoxSolid b;
  b.centre_mm = Eigen::Vector3d(0, 0, 25);
  b.size_mm = Eigen::Vector3d(10, 10, 20);  // reaches z = 15 < 20: into the lens
  b.material = "N-BK7";
  b.field = "solids[1]";
  scene.boxes.push_back(b);
  try {
    build_trace_scene(scene);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "solids[0]");
    EXPECT_NE(e.problem().find("overlaps solids[1]"), std::string::npos) << e.problem();
  }
}

}  // namespace
}  // namespace glasspiv
