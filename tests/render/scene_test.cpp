// The scene description: packing geometry, the reader on every shipped scene,
// look-at poses, each validation error, and the JSON Schema against the reader.
#include <chrono>
#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "render/mesh_file.h"
#include "render/packing.h"
#include "render/scene.h"
#include "render/scene_yaml.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

namespace fs = std::filesystem;
const std::string kSource = GLASSPIV_SOURCE_DIR;
const std::string kCamera = kSource + "/data/cameras/example.yaml";

double min_distance(const std::vector<SphereSolid>& s) {
  double best = INFINITY;
  for (std::size_t a = 0; a < s.size(); ++a)
    for (std::size_t b = a + 1; b < s.size(); ++b) best = std::min(best, (s[a].centre_mm - s[b].centre_mm).norm());
  return best;
}

// Neighbours of sphere k at exactly `distance` (to 1e-9 mm).
int neighbours_at(const std::vector<SphereSolid>& s, std::size_t k, double distance) {
  int n = 0;
  for (std::size_t b = 0; b < s.size(); ++b)
    if (b != k && std::fabs((s[k].centre_mm - s[b].centre_mm).norm() - distance) < 1e-9) ++n;
  return n;
}

Packing packing(Lattice lattice, int layers, int nx, int ny, double d = 40) {
  Packing p;
  p.lattice = lattice;
  p.diameter_mm = d;
  p.layers = layers;
  p.layer_size = {nx, ny};
  p.origin_mm = Eigen::Vector3d(1, 2, 3);
  p.material = "N-BK7";
  p.field = "packings[0]";
  return p;
}

TEST(Packing, BccCellTouchingAndLayerOffsets) {
  const double d = 40, a = 2 * d / std::sqrt(3.0);
  const LatticeGeometry g = lattice_geometry(Lattice::bcc, d);
  EXPECT_NEAR(g.cubic_cell_mm, a, 1e-12);
  EXPECT_NEAR(g.pitch_mm, a, 1e-12);
  EXPECT_NEAR(g.layer_spacing_mm, a / 2, 1e-12);
  const Packing p = packing(Lattice::bcc, 5, 3, 3, d);
  EXPECT_EQ(spheres_in_layer(p, 0), 9);
  EXPECT_EQ(spheres_in_layer(p, 1), 4);
  EXPECT_EQ(spheres_in_layer(p, 4), 9);
  const auto s = expand_packing(p);
  ASSERT_EQ(s.size(), 9u + 4 + 9 + 4 + 9);
  EXPECT_NEAR(min_distance(s), d, 1e-9);  // nearest neighbours touch, none overlap
  // The body centre of the cell: (a/2, a/2, a/2) from the first sphere.
  EXPECT_TRUE(packing_sphere_centre(p, 1, 0, 0).isApprox(p.origin_mm + Eigen::Vector3d(a / 2, a / 2, a / 2), 1e-12));
  EXPECT_TRUE(packing_sphere_centre(p, 2, 1, 2).isApprox(p.origin_mm + Eigen::Vector3d(a, 2 * a, a), 1e-12));
  // The middle sphere of layer 2 touches its 8 body-centre neighbours (4 below, 4
  // above); its in-layer neighbours sit at a > D, its next layer-but-one at a.
  const std::size_t middle = 9 + 4 + 4;  // layer 2, i 1, j 1
  EXPECT_TRUE(s[middle].centre_mm.isApprox(packing_sphere_centre(p, 2, 1, 1)));
  EXPECT_EQ(neighbours_at(s, middle, d), 8);
  EXPECT_EQ(neighbours_at(s, middle, a), 6);
  EXPECT_EQ(s[middle].field, "packings[0].spheres[2,1,1]");
  Scene scene;
  scene.packings.push_back(p);
  EXPECT_NO_THROW(validate(scene));
}

TEST(Packing, FccAndSc) {
  const double d = 40;
  const LatticeGeometry f = lattice_geometry(Lattice::fcc, d);
  EXPECT_NEAR(f.cubic_cell_mm, d * std::sqrt(2.0), 1e-12);
  const Packing p = packing(Lattice::fcc, 5, 4, 4, d);
  EXPECT_EQ(spheres_in_layer(p, 0), 16);
  EXPECT_EQ(spheres_in_layer(p, 1), 9);
  const auto s = expand_packing(p);
  EXPECT_NEAR(min_distance(s), d, 1e-9);
  // Layer 2, i 1, j 1 is fully surrounded: fcc has 12 touching neighbours.
  const std::size_t inner = 16 + 9 + 4 + 1;
  EXPECT_TRUE(s[inner].centre_mm.isApprox(packing_sphere_centre(p, 2, 1, 1)));
  EXPECT_EQ(neighbours_at(s, inner, d), 12);
  // Layers k and k+2 are one cubic cell apart.
  EXPECT_NEAR((packing_sphere_centre(p, 2, 0, 0) - packing_sphere_centre(p, 0, 0, 0)).norm(), d * std::sqrt(2.0), 1e-12);

  const Packing c = packing(Lattice::sc, 3, 3, 3, d);
  EXPECT_EQ(spheres_in_layer(c, 1), 9);
  const auto sc = expand_packing(c);
  ASSERT_EQ(sc.size(), 27u);
  EXPECT_NEAR(min_distance(sc), d, 1e-9);
  EXPECT_EQ(neighbours_at(sc, 13, d), 6);  // the centre of the 3x3x3 cube
}

TEST(Packing, Overrides) {
  Packing p = packing(Lattice::bcc, 3, 3, 3);
  PackingOverride by_index;
  by_index.sphere = std::array<int, 3>{1, 0, 1};
  by_index.material = "black";
  PackingOverride by_region;
  by_region.region_mm = std::array<Eigen::Vector3d, 2>{Eigen::Vector3d(-1e9, -1e9, 30), Eigen::Vector3d(1e9, 1e9, 1e9)};
  by_region.material = "PMMA";
  p.overrides = {by_index, by_region};
  const auto s = expand_packing(p);
  int black = 0, pmma = 0;
  for (const auto& sphere : s) {
    black += sphere.material == "black";
    pmma += sphere.material == "PMMA";
  }
  EXPECT_EQ(black, 1);
  EXPECT_EQ(pmma, 9);  // layer 2 at z = 3 + 46.19
  EXPECT_EQ(s[9 + 2].material, "black");  // layer 1, i 0, j 1
}

TEST(LookAt, AxisPointsAtTargetAndUpIsMinusY) {
  const Eigen::Vector3d position(120, -40, -500), target(10, 20, 30), up(0.1, 1, 0.2);
  const RigidTransform t = camera_from_world_look_at(position, target, up);
  EXPECT_TRUE((t.rotation.transpose() * t.rotation).isIdentity(1e-12));
  EXPECT_NEAR(t.rotation.determinant(), 1, 1e-12);
  EXPECT_TRUE(t.apply(position).isZero(1e-9));
  const Eigen::Vector3d seen = t.apply(target);
  EXPECT_NEAR(seen.x(), 0, 1e-9);
  EXPECT_NEAR(seen.y(), 0, 1e-9);
  EXPECT_NEAR(seen.z(), (target - position).norm(), 1e-9);
  const Eigen::Vector3d up_camera = t.rotation * up;
  EXPECT_NEAR(up_camera.x(), 0, 1e-12);
  EXPECT_LT(up_camera.y(), 0);
  // A point above the target appears above the image centre.
  const Eigen::Vector3d above = t.apply(target + 10 * up);
  EXPECT_LT(above.y() / above.z(), 0);
  EXPECT_THROW(camera_from_world_look_at(position, position, up), InputError);
  EXPECT_THROW(camera_from_world_look_at(position, target, target - position), InputError);
}

void expect_camera_looks_at(const SceneCamera& cam, const Eigen::Vector3d& target) {
  const RigidTransform& t = *cam.camera.camera_from_world;
  const Eigen::Vector3d seen = t.apply(target);
  EXPECT_GT(seen.z(), 0) << cam.name;
  EXPECT_NEAR(seen.x() / seen.z(), 0, 1e-12) << cam.name;
  EXPECT_NEAR(seen.y() / seen.z(), 0, 1e-12) << cam.name;
  EXPECT_LT((t.rotation * Eigen::Vector3d::UnitY()).y(), 0) << cam.name;  // world up is image up
  EXPECT_NEAR((t.rotation * Eigen::Vector3d::UnitY()).x(), 0, 1e-12) << cam.name;
  // The target projects onto the principal point (distortion vanishes on the axis).
  const auto pixel = cam.camera.model.project(seen);
  ASSERT_TRUE(pixel.has_value());
  EXPECT_NEAR(pixel->x(), cam.camera.model.cx_px(), 1e-6);
  EXPECT_NEAR(pixel->y(), cam.camera.model.cy_px(), 1e-6);
}

TEST(SceneFiles, EveryShippedSceneLoadsAndValidates) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator(kSource + "/data/scenes")) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    const Scene scene = read_scene(entry.path().string());
    EXPECT_NO_THROW(validate(scene));
    ASSERT_TRUE(scene.sheet.has_value());
    EXPECT_FALSE(scene.cameras.empty());
    for (const SceneCamera& cam : scene.cameras) {
      expect_camera_looks_at(cam, scene.sheet->origin_mm);
      // Every camera is outside every sphere and on the camera side of the sheet.
      for (const SphereSolid& s : scene.all_spheres())
        EXPECT_GT((cam.camera.camera_from_world->inverse().translation_mm - s.centre_mm).norm(), s.diameter_mm / 2);
    }
    ++count;
  }
  EXPECT_EQ(count, 6);  // reactor, reactor_5cams, reactor_markers, ball_lens, flat_window, ball_layer
}

TEST(SceneFiles, Reactor) {
  const Scene scene = read_scene(kSource + "/data/scenes/reactor.yaml");
  EXPECT_EQ(scene.wavelength_nm, 532);
  EXPECT_EQ(scene.fluid, "air");
  ASSERT_EQ(scene.packings.size(), 1u);
  const Packing& p = scene.packings[0];
  EXPECT_EQ(p.lattice, Lattice::bcc);
  EXPECT_EQ(p.layer_size, (std::array<int, 2>{3, 3}));
  const auto spheres = scene.all_spheres();
  EXPECT_EQ(spheres.size(), 39u);  // 9 + 4 + 9 + 4 + 9 + 4
  EXPECT_NEAR(min_distance(spheres), 40, 1e-9);
  // The first layer is centred on the axis.
  EXPECT_TRUE(packing_sphere_centre(p, 0, 1, 1).isZero(1e-12));
  // The sheet lies behind two layers of the 3 x 3 layout: halfway between the
  // centres of layers 2 and 4, through the centres of layer 3.
  const double z2 = packing_sphere_centre(p, 2, 0, 0).z(), z4 = packing_sphere_centre(p, 4, 0, 0).z();
  EXPECT_NEAR(scene.sheet->origin_mm.z(), (z2 + z4) / 2, 1e-9);
  EXPECT_NEAR(scene.sheet->origin_mm.z(), packing_sphere_centre(p, 3, 0, 0).z(), 1e-9);
  EXPECT_NEAR(scene.sheet->normal().z(), -1, 1e-12);  // facing the camera
  EXPECT_NEAR(scene.sheet->sigma_mm(), 0.25, 1e-12);
  ASSERT_EQ(scene.cameras.size(), 1u);
  EXPECT_EQ(scene.cameras[0].name, "cam0");
  EXPECT_EQ(scene.cameras[0].camera.model.width_px(), 2560);
  EXPECT_TRUE(fs::equivalent(scene.cameras[0].file, kCamera));
  EXPECT_TRUE(scene.cameras[0].camera.camera_from_world->inverse().translation_mm.isApprox(Eigen::Vector3d(0, 0, -600)));
  EXPECT_EQ(scene.material("N-BK7").name, "N-BK7");
}

TEST(SceneFiles, FiveCamerasThreeAtSheetHeightTwoElevated) {
  const Scene scene = read_scene(kSource + "/data/scenes/reactor_5cams.yaml");
  ASSERT_EQ(scene.cameras.size(), 5u);
  int level = 0, elevated = 0;
  for (const SceneCamera& cam : scene.cameras) {
    const Eigen::Vector3d c = cam.camera.camera_from_world->inverse().translation_mm;
    EXPECT_NEAR((c - scene.sheet->origin_mm).norm(), 640, 1e-2) << cam.name;
    if (std::fabs(c.y() - scene.sheet->origin_mm.y()) < 1e-9) ++level;
    if (c.y() > 100) ++elevated;
  }
  EXPECT_EQ(level, 3);
  EXPECT_EQ(elevated, 2);
}

TEST(SceneFiles, BallLensAndFlatWindow) {
  const Scene ball = read_scene(kSource + "/data/scenes/ball_lens.yaml");
  ASSERT_EQ(ball.spheres.size(), 1u);
  EXPECT_EQ(ball.spheres[0].diameter_mm, 40);
  EXPECT_EQ(ball.spheres[0].field, "solids[0]");
  const Scene window = read_scene(kSource + "/data/scenes/flat_window.yaml");
  ASSERT_EQ(window.slabs.size(), 1u);
  const BoxSolid box = window.slabs[0].to_box();
  EXPECT_TRUE(box.centre_mm.isApprox(Eigen::Vector3d(0, 0, -55)));
  EXPECT_TRUE(box.size_mm.isApprox(Eigen::Vector3d(300, 300, 10)));
  EXPECT_TRUE(box.world_from_box.isApprox(Eigen::Matrix3d::Identity()));
}

// Writes a scene into a temporary folder and reads it.
class SceneText : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("glasspiv_scene_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& text, const std::string& name = "scene.yaml") {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    return path;
  }
  Scene load(const std::string& body) { return read_scene(write(header() + body)); }
  std::string header() const {
    return "glasspiv_scene: 1\n";
  }
  // Expects the body to be rejected naming `field`, with a line and `words` in the message.
  void expect_error(const std::string& body, const std::string& field, const std::string& words) {
    const std::string path = write(header() + body);
    try {
      (void)read_scene(path);
      ADD_FAILURE() << "accepted; expected an error at " << field;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.field(), field) << e.what();
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
      EXPECT_NE(e.problem().find("line "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
  std::string camera_line() const { return "    file: " + kCamera + "\n"; }
  fs::path dir_;
};

const char* kSphere = "solids:\n  - {type: sphere, centre_mm: [0, 0, 0], diameter_mm: 40, material: N-BK7}\n";
const char* kSheet = "sheet: {origin_mm: [0, 0, 40], s_axis: [1, 0, 0], t_axis: [0, 1, 0], extent_mm: [10, 10], thickness_mm: 1}\n";

TEST_F(SceneText, EverySolidKindMaterialsAndOverrides) {
  fs::copy_file(kCamera, dir_ / "cam.yaml");
  std::ofstream(dir_ / "dots.png") << "not really a png";
  const Scene s = load(
      "fluid: water\n"
      "materials:\n  glass: BK7\n  mine: {index: 1.49, absorption_per_mm: 0.01}\n  black: {opaque: 0.05}\n"
      "solids:\n"
      "  - {type: box, centre_mm: [0, 0, 300], size_mm: [10, 20, 30], rotation: {euler_deg: [0, 0, 90]}, material: black}\n"
      "  - {type: box, centre_mm: [0, 0, 400], size_mm: [10, 20, 30], rotation: {rvec_deg: [0, 90, 0]}, material: mine}\n"
      "  - {type: slab, point_mm: [0, 0, -60], normal: [0, 0, 1.0004], thickness_mm: 5, extent_mm: [50, 60], material: glass}\n"
      "  - {type: cylinder, base_centre_mm: [200, 0, 0], axis: [0, 1, 0], radius_mm: 5, length_mm: 100, material: PMMA}\n"
      "  - {type: rectangle, centre_mm: [0, 0, 500], size_mm: [100, 80], normal: [0, 0, -1], up: [0, 1, 0], texture: dots.png}\n"
      "packings:\n"
      "  - lattice: fcc\n    diameter_mm: 10\n    layers: 2\n    layer_size: [2, 2]\n    origin_mm: [100, 100, 100]\n"
      "    material: glass\n    overrides:\n      - {sphere: [0, 1, 1], material: black}\n"
      "      - {region: {min_mm: [0, 0, 104], max_mm: [200, 200, 200]}, material: mine}\n"
      "sheet: {origin_mm: [0, 0, 40], s_axis: [0.6, 0.8, 0], t_axis: [-0.8, 0.6, 0.00001], extent_mm: [10, 20], thickness_mm: 2}\n"
      "background: {radiance: 0.5}\n"
      "cameras:\n  - name: side\n    file: cam.yaml\n"
      "  - name: inline\n    model: {image_size_px: [640, 480], lens_model: pinhole, focal_length_px: [800, 800], principal_point_px: [319.5, 239.5]}\n"
      "    pose: {rvec: [0, 0, 0], tvec_mm: [0, 0, 100]}\n");
  EXPECT_EQ(s.fluid, "water");
  EXPECT_EQ(s.material("glass").name, "N-BK7");
  EXPECT_EQ(s.material("black").kind, MaterialKind::opaque);
  EXPECT_EQ(*s.material("mine").absorption_per_mm, 0.01);
  ASSERT_EQ(s.boxes.size(), 2u);
  EXPECT_TRUE((s.boxes[0].world_from_box * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_TRUE((s.boxes[1].world_from_box * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX()));
  ASSERT_EQ(s.slabs.size(), 1u);
  EXPECT_EQ(s.slabs[0].normal, Eigen::Vector3d::UnitZ()) << "normals are normalised";
  ASSERT_EQ(s.cylinders.size(), 1u);
  ASSERT_EQ(s.rectangles.size(), 1u);
  EXPECT_TRUE(fs::equivalent(s.rectangles[0].texture, dir_ / "dots.png"));
  const auto spheres = s.all_spheres();
  ASSERT_EQ(spheres.size(), 5u);
  EXPECT_EQ(spheres[3].material, "black");
  EXPECT_EQ(spheres[4].material, "mine");
  EXPECT_NEAR(s.sheet->s_axis.dot(s.sheet->t_axis), 0, 1e-15) << "t is made exactly orthogonal";
  EXPECT_NEAR(s.sheet->t_axis.norm(), 1, 1e-15);
  EXPECT_EQ(s.background.radiance, 0.5);
  ASSERT_EQ(s.cameras.size(), 2u);
  EXPECT_EQ(s.cameras[0].name, "side");
  EXPECT_TRUE(s.cameras[0].camera.camera_from_world.has_value()) << "the file's own pose";
  EXPECT_EQ(s.cameras[1].name, "inline");
  EXPECT_EQ(s.cameras[1].file, "");
  EXPECT_EQ(s.cameras[1].camera.model.width_px(), 640);
}

TEST_F(SceneText, ValidationErrorsNameFileFieldAndLine) {
  expect_error("solids:\n  - {type: sphere, centre_mm: [0, 0, 0], diameter_mm: -4, material: N-BK7}\n",
               "solids[0].diameter_mm", "must be positive");
  expect_error("solids:\n  - {type: sphere, centre_mm: [0, 0, 0], diameter_mm: 4, material: unobtainium}\n",
               "solids[0].material", "unknown material");
  expect_error("solids:\n  - {type: sphere, centre_mm: [0, 0, 0], material: N-BK7}\n", "solids[0].diameter_mm",
               "missing");
  expect_error("solids:\n  - {type: sphere, centre_mm: [0, 0, 0], diameter_mm: 4, colour: red, material: N-BK7}\n",
               "solids[0].colour", "unknown key 'colour'");
  expect_error("colour: red\n", "colour", "unknown key 'colour'");
  expect_error("sheet: {origin_mm: [0, 0, 0], s_axis: [1, 0, 0], t_axis: [0, 1, 0], extent_mm: [1, 1], thickness_mm: 1, tilt: 3}\n",
               "sheet.tilt", "unknown key");
  expect_error("solids:\n  - {type: mesh, file: bunny.stl, material: N-BK7}\n", "solids[0].file", "does not exist");
  expect_error("meshes: {file: bunny.stl}\n", "meshes", "must be a list");
  expect_error("solids:\n  - {type: torus}\n", "solids[0].type", "unknown solid type");
  expect_error(std::string(kSphere) + "  - {type: sphere, centre_mm: [30, 0, 0], diameter_mm: 40, material: N-BK7}\n",
               "solids[1]", "overlaps solids[0]");
  expect_error("solids:\n  - {type: cylinder, base_centre_mm: [0, 0, 0], axis: [0, 0, 0], radius_mm: 1, length_mm: 2, material: PMMA}\n",
               "solids[0].axis", "zero-length");
  expect_error("sheet: {origin_mm: [0, 0, 0], s_axis: [1.1, 0, 0], t_axis: [0, 1, 0], extent_mm: [1, 1], thickness_mm: 1}\n",
               "sheet.s_axis", "unit vector");
  expect_error("sheet: {origin_mm: [0, 0, 0], s_axis: [1, 0, 0], t_axis: [0.1, 0.995, 0], extent_mm: [1, 1], thickness_mm: 1}\n",
               "sheet.t_axis", "orthogonal");
  expect_error("sheet: {origin_mm: [0, 0, 0], s_axis: [1, 0, 0], t_axis: [0, 1, 0], extent_mm: [1, 1], thickness_mm: 0}\n",
               "sheet.thickness_mm", "must be positive");
  expect_error("cameras:\n  - name: a\n    file: no_such_camera.yaml\n", "cameras[0].file", "does not exist");
  expect_error("cameras:\n  - name: a\n" + camera_line() + "  - name: a\n" + camera_line(), "cameras[1].name",
               "appears twice");
  expect_error("cameras:\n  - name: a\n" + camera_line() + "    pose: {position_mm: [0, 0, 0], look_at_mm: [0, 0, 0], up: [0, 1, 0]}\n",
               "cameras[0].pose.look_at_mm", "must differ");
  expect_error("packings:\n  - {lattice: hcp, diameter_mm: 40, layers: 2, layer_size: [3, 3], origin_mm: [0, 0, 0], material: N-BK7}\n",
               "packings[0].lattice", "unknown lattice");
  expect_error("packings:\n  - {lattice: bcc, diameter_mm: 40, layers: 2, layer_size: [3, 3], origin_mm: [0, 0, 0], material: N-BK7,\n"
               "     overrides: [{sphere: [1, 2, 2], material: PMMA}]}\n",
               "packings[0].overrides[0].sphere", "no sphere [1, 2, 2]");
  expect_error(std::string(kSphere) + "packings:\n  - {lattice: sc, diameter_mm: 40, layers: 1, layer_size: [1, 1], origin_mm: [0, 0, 39], material: N-BK7}\n",
               "packings[0].spheres[0,0,0]", "overlaps solids[0]");
  expect_error("fluid: {opaque: 0.5}\n", "fluid", "must be a text");
  expect_error("materials:\n  black: {opaque: 0.1}\nfluid: black\n", "fluid", "opaque");
  expect_error("materials:\n  glass: {index: 1.5, opaque: 0.2}\n", "materials.glass", "needs a catalogue name");
  expect_error("solids:\n  - {type: box, centre_mm: [0, 0, 0], size_mm: [1, 1, 1], rotation: {rvec: [0, 0, 1]}, material: PMMA}\n",
               "solids[0].rotation.rvec", "unknown key");
  expect_error("solids:\n  - {type: rectangle, centre_mm: [0, 0, 0], size_mm: [1, 1], normal: [0, 0, 1], up: [0, 0, 1]}\n",
               "solids[0].up", "parallel");
  expect_error("solids:\n  - {type: rectangle, centre_mm: [0, 0, 0], size_mm: [1, 1], normal: [0, 0, 1], up: [0, 1, 0], texture: gone.png}\n",
               "solids[0].texture", "does not exist");
  expect_error("wavelength_nm: 250\n" + std::string(kSphere), "solids[0].material", "wavelength");
}

TEST_F(SceneText, VersionAndMissingPose) {
  const std::string path = write("glasspiv_scene: 2\n");
  try {
    (void)read_scene(path);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "glasspiv_scene");
  }
  EXPECT_THROW((void)read_scene(write("wavelength_nm: 532\n", "noversion.yaml")), InputError);
  // A camera file without a pose needs one in the scene.
  std::ofstream(dir_ / "nopose.yaml") << "glasspiv_camera: 1\nimage_size_px: [64, 48]\nlens_model: pinhole\nfocal_length_px: [80, 80]\n"
                                         "principal_point_px: [31.5, 23.5]\n";
  expect_error("cameras:\n  - file: nopose.yaml\n", "cameras[0].pose", "no pose");
  EXPECT_NO_THROW(load(std::string(kSphere) + kSheet));
}

TEST(SceneSchema, ValidJsonListingTheReadersTopLevelKeys) {
  std::ifstream in(kSource + "/docs/scene.schema.json");
  ASSERT_TRUE(in.good());
  const nlohmann::json schema = nlohmann::json::parse(in);
  EXPECT_EQ(schema.at("$schema"), "https://json-schema.org/draft/2020-12/schema");
  EXPECT_EQ(schema.at("type"), "object");
  EXPECT_EQ(schema.at("additionalProperties"), false);
  std::set<std::string> in_schema;
  for (const auto& item : schema.at("properties").items()) in_schema.insert(item.key());
  const auto keys = scene_top_level_keys();
  EXPECT_EQ(in_schema, std::set<std::string>(keys.begin(), keys.end()));
  EXPECT_NE(std::find(schema.at("required").begin(), schema.at("required").end(), "glasspiv_scene"),
            schema.at("required").end());
  // Every solid type the reader accepts has a branch in the schema.
  const std::string text = schema.dump();
  for (const char* type : {"sphere", "box", "slab", "cylinder", "rectangle", "mesh"})
    EXPECT_NE(text.find(std::string("\"") + type + "\""), std::string::npos) << type;
}

}  // namespace
}  // namespace glasspiv

namespace glasspiv {
namespace {

void expect_same(const Scene& a, const Scene& b) {
  EXPECT_EQ(a.wavelength_nm, b.wavelength_nm);
  EXPECT_EQ(a.fluid, b.fluid);
  EXPECT_EQ(a.materials.size(), b.materials.size());
  for (const auto& [name, m] : a.materials) {
    EXPECT_EQ(m.kind, b.material(name).kind) << name;
    if (m.kind != MaterialKind::opaque) {
      EXPECT_EQ(m.refractive_index(532), b.material(name).refractive_index(532)) << name;
    }
  }
  const auto sa = a.all_spheres(), sb = b.all_spheres();
  ASSERT_EQ(sa.size(), sb.size());
  for (std::size_t k = 0; k < sa.size(); ++k) {
    EXPECT_EQ(sa[k].centre_mm, sb[k].centre_mm);
    EXPECT_EQ(sa[k].material, sb[k].material);
  }
  ASSERT_EQ(a.boxes.size(), b.boxes.size());
  for (std::size_t k = 0; k < a.boxes.size(); ++k)
    EXPECT_TRUE(a.boxes[k].world_from_box.isApprox(b.boxes[k].world_from_box, 1e-14));
  ASSERT_EQ(a.slabs.size(), b.slabs.size());
  ASSERT_EQ(a.cylinders.size(), b.cylinders.size());
  ASSERT_EQ(a.rectangles.size(), b.rectangles.size());
  ASSERT_EQ(a.meshes.size(), b.meshes.size());
  for (std::size_t k = 0; k < a.meshes.size(); ++k) {
    EXPECT_TRUE(fs::equivalent(a.meshes[k].file, b.meshes[k].file));
    EXPECT_EQ(a.meshes[k].placement.scale, b.meshes[k].placement.scale);
    EXPECT_EQ(a.meshes[k].placement.position_mm, b.meshes[k].placement.position_mm);
    EXPECT_TRUE(a.meshes[k].placement.world_from_mesh.isApprox(b.meshes[k].placement.world_from_mesh, 1e-14));
    EXPECT_EQ(a.meshes[k].options.normals, b.meshes[k].options.normals);
    EXPECT_EQ(a.meshes[k].options.crease_angle_deg, b.meshes[k].options.crease_angle_deg);
    EXPECT_EQ(a.meshes[k].material, b.meshes[k].material);
  }
  ASSERT_EQ(a.sheet.has_value(), b.sheet.has_value());
  if (a.sheet) {
    EXPECT_EQ(a.sheet->origin_mm, b.sheet->origin_mm);
    EXPECT_EQ(a.sheet->t_axis, b.sheet->t_axis);
  }
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (std::size_t k = 0; k < a.cameras.size(); ++k) {
    EXPECT_EQ(a.cameras[k].name, b.cameras[k].name);
    EXPECT_TRUE(a.cameras[k].camera.camera_from_world->rotation.isApprox(b.cameras[k].camera.camera_from_world->rotation, 1e-14));
    EXPECT_TRUE(a.cameras[k].camera.camera_from_world->translation_mm.isApprox(
        b.cameras[k].camera.camera_from_world->translation_mm, 1e-12));
    EXPECT_EQ(a.cameras[k].camera.model.intrinsics(), b.cameras[k].camera.model.intrinsics());
  }
}

TEST(SceneWriter, ShippedScenesRoundTrip) {
  const fs::path dir = fs::temp_directory_path() / "glasspiv_scene_writer_test" / "sub";
  fs::create_directories(dir);
  for (const char* name : {"reactor.yaml", "reactor_5cams.yaml", "ball_lens.yaml", "flat_window.yaml"}) {
    SCOPED_TRACE(name);
    const Scene scene = read_scene(kSource + "/data/scenes/" + name);
    const std::string out = (dir / name).string();
    write_scene(out, scene);
    const Scene back = read_scene(out);
    expect_same(scene, back);
    EXPECT_TRUE(fs::equivalent(back.cameras[0].file, kCamera));
  }
  fs::remove_all(dir.parent_path());
}

TEST_F(SceneText, EverySolidKindRoundTrips) {
  std::ofstream(dir_ / "dots.png") << "x";
  const Scene s = load(
      "materials:\n  mine: {index: 1.49, absorption_per_mm: 0.01}\n  black: {opaque: 0.05}\n  glass: BK7\n"
      "solids:\n"
      "  - {type: box, centre_mm: [0, 0, 300], size_mm: [10, 20, 30], rotation: {euler_deg: [10, 20, 30]}, material: black}\n"
      "  - {type: slab, point_mm: [0, 0, -60], normal: [0, 0, 1], thickness_mm: 5, extent_mm: [50, 60], material: glass}\n"
      "  - {type: cylinder, base_centre_mm: [200, 0, 0], axis: [0, 1, 0], radius_mm: 5, length_mm: 100, material: mine}\n"
      "  - {type: rectangle, centre_mm: [0, 0, 500], size_mm: [100, 80], normal: [0, 0, -1], up: [0, 1, 0], texture: dots.png}\n"
      "packings:\n  - {lattice: sc, diameter_mm: 10, layers: 2, layer_size: [2, 2], origin_mm: [100, 100, 100], material: glass,\n"
      "     overrides: [{sphere: [0, 1, 1], material: black}, {region: {min_mm: [0, 0, 105], max_mm: [999, 999, 999]}, material: mine}]}\n"
      "cameras:\n  - name: inline\n    model: {image_size_px: [640, 480], lens_model: opencv4, focal_length_px: [800, 810],\n"
      "            principal_point_px: [319.5, 239.5], distortion_coefficients: [0.1, -0.01, 0.001, 0.002]}\n"
      "    pose: {position_mm: [10, 20, -300], look_at_mm: [0, 0, 0], up: [0, 1, 0]}\n");
  const std::string out = (dir_ / "copy.yaml").string();
  write_scene(out, s);
  const Scene back = read_scene(out);
  expect_same(s, back);
  EXPECT_TRUE(fs::equivalent(back.rectangles[0].texture, dir_ / "dots.png"));
  EXPECT_EQ(back.cameras[0].file, "");
}

// A closed tetrahedron in ASCII STL (file units).
const char* kTetrahedronStl =
    "solid t\n"
    "facet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 1 0\nvertex 1 0 0\nendloop\nendfacet\n"
    "facet normal 0 -1 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 0 1\nendloop\nendfacet\n"
    "facet normal -1 0 0\nouter loop\nvertex 0 0 0\nvertex 0 0 1\nvertex 0 1 0\nendloop\nendfacet\n"
    "facet normal 1 1 1\nouter loop\nvertex 1 0 0\nvertex 0 1 0\nvertex 0 0 1\nendloop\nendfacet\n"
    "endsolid t\n";

TEST_F(SceneText, MeshesFromTheListAndAsSolids) {
  fs::create_directories(dir_ / "parts");
  std::ofstream(dir_ / "parts" / "tet.stl") << kTetrahedronStl;
  const Scene s = load(
      "materials:\n  glass: BK7\n"
      "solids:\n"
      "  - {type: mesh, file: parts/tet.stl, material: glass}\n"
      "meshes:\n"
      "  - file: parts/tet.stl\n"
      "    material: PMMA\n"
      "    scale: 1000\n"
      "    position_mm: [10, 20, 30]\n"
      "    rotation_deg: [0, 0, 90]\n"
      "    normals: file\n"
      "    crease_angle_deg: 30\n");
  ASSERT_EQ(s.meshes.size(), 2u);
  const MeshSolid& a = s.meshes[0];
  EXPECT_EQ(a.field, "solids[0]");
  EXPECT_TRUE(fs::equivalent(a.file, dir_ / "parts" / "tet.stl")) << "relative to the scene file";
  EXPECT_EQ(a.placement.scale, 1);
  EXPECT_EQ(a.placement.position_mm, Eigen::Vector3d::Zero());
  EXPECT_EQ(a.placement.world_from_mesh, Eigen::Matrix3d::Identity());
  EXPECT_EQ(a.options.normals, MeshNormals::smooth) << "the default";
  EXPECT_EQ(a.options.crease_angle_deg, 60);
  EXPECT_EQ(a.material, "glass");
  const MeshSolid& b = s.meshes[1];
  EXPECT_EQ(b.field, "meshes[0]");
  EXPECT_EQ(b.placement.scale, 1000);
  EXPECT_EQ(b.placement.position_mm, Eigen::Vector3d(10, 20, 30));
  EXPECT_TRUE((b.placement.world_from_mesh * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_EQ(b.options.normals, MeshNormals::file);
  EXPECT_EQ(b.options.crease_angle_deg, 30);
  EXPECT_EQ(b.material, "PMMA");
  // The scene describes; load_scene_mesh reads: 1000^3 / 6 mm^3, placed.
  const TriangleMesh m = load_scene_mesh(s, b);
  EXPECT_NEAR(m.volume_mm3(), 1e9 / 6, 1e-3);
  EXPECT_TRUE(bounds_mm(m).min().isApprox(Eigen::Vector3d(-990, 20, 30)));
  // Round trip through the writer (file relative to the new file's folder).
  fs::create_directories(dir_ / "out");
  const std::string out = (dir_ / "out" / "copy.yaml").string();
  write_scene(out, s);
  const Scene back = read_scene(out);
  ASSERT_EQ(back.meshes.size(), 2u);
  EXPECT_EQ(back.meshes[0].field, "meshes[0]");
  expect_same(s, back);
}

TEST_F(SceneText, MeshErrorsNameTheFieldPath) {
  std::ofstream(dir_ / "tet.stl") << kTetrahedronStl;
  std::ofstream(dir_ / "open.stl") << "solid t\nfacet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 1 0\n"
                                      "vertex 1 0 0\nendloop\nendfacet\nendsolid t\n";
  expect_error("meshes:\n  - {file: gone.stl, material: N-BK7}\n", "meshes[0].file", "does not exist");
  expect_error("meshes:\n  - {file: tet.stl}\n", "meshes[0].material", "missing");
  expect_error("meshes:\n  - {material: N-BK7}\n", "meshes[0].file", "missing");
  expect_error("meshes:\n  - {file: tet.stl, material: N-BK7, scale: -2}\n", "meshes[0].scale", "must be positive");
  expect_error("meshes:\n  - {file: tet.stl, material: N-BK7, scale: 0}\n", "meshes[0].scale", "must be positive");
  expect_error("meshes:\n  - {file: tet.stl, material: N-BK7, normals: phong}\n", "meshes[0].normals", "unknown normals");
  expect_error("meshes:\n  - {file: tet.stl, material: N-BK7, crease_angle_deg: 200}\n", "meshes[0].crease_angle_deg",
               "(0, 180]");
  expect_error("meshes:\n  - {file: tet.stl, material: unobtainium}\n", "meshes[0].material", "unknown material");
  expect_error("meshes:\n  - {file: tet.stl, material: N-BK7, position_mm: [1, 2]}\n", "meshes[0].position_mm", "");
  expect_error("meshes:\n  - {file: tet.stl, material: N-BK7, rotation: {rvec_deg: [0, 0, 1]}}\n", "meshes[0].rotation",
               "unknown key 'rotation'");
  expect_error("meshes:\n  - {type: mesh, file: tet.stl, material: N-BK7}\n", "meshes[0].type", "unknown key 'type'");
  expect_error("solids:\n  - {type: mesh, file: tet.stl, material: N-BK7, colour: red}\n", "solids[0].colour",
               "unknown key");
  // A bad file is found when the mesh is loaded, named by the scene and the field.
  const Scene s = load("meshes:\n  - {file: tet.stl, material: N-BK7}\n  - {file: open.stl, material: N-BK7}\n");
  EXPECT_NO_THROW((void)load_scene_mesh(s, s.meshes[0]));
  try {
    (void)load_scene_mesh(s, s.meshes[1]);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), s.source);
    EXPECT_EQ(e.field(), "meshes[1].file");
    EXPECT_NE(e.problem().find("open.stl"), std::string::npos) << e.what();
    EXPECT_NE(e.problem().find("open meshes are refused"), std::string::npos) << e.what();
  }
}


// ------------------------------------------------------------------ limits

std::string sphere_with(const std::string& centre, const std::string& diameter) {
  return "solids:\n  - {type: sphere, centre_mm: " + centre + ", diameter_mm: " + diameter + ", material: N-BK7}\n";
}
std::string sheet_with(const std::string& extent, const std::string& thickness, const std::string& origin = "[0, 0, 0]") {
  return "sheet: {origin_mm: " + origin + ", s_axis: [1, 0, 0], t_axis: [0, 1, 0], extent_mm: " + extent +
         ", thickness_mm: " + thickness + "}\n";
}
std::string packing_with(const std::string& layers, const std::string& layer_size, const std::string& diameter = "40",
                         const std::string& extra = "") {
  return "packings:\n  - {lattice: bcc, diameter_mm: " + diameter + ", layers: " + layers + ", layer_size: " +
         layer_size + ", origin_mm: [0, 0, 0], material: N-BK7" + extra + "}\n";
}

// One limit on every length and coordinate in mm, whatever the element (a
// sphere of 1e160 mm used to abort the tracer on an assertion).
TEST_F(SceneText, EveryLengthAndCoordinateIsWithinTheSceneLimits) {
  expect_error(sphere_with("[0, 0, 0]", "1e160"), "solids[0].diameter_mm", "larger than the 1000000 mm");
  expect_error(sphere_with("[0, 0, 0]", "1e-4"), "solids[0].diameter_mm", "smaller than the 0.001 mm");
  expect_error(sphere_with("[0, 2e6, 0]", "4"), "solids[0].centre_mm", "+-1000000 mm");
  expect_error(sheet_with("[1e308, 10]", "1"), "sheet.extent_mm[0]", "larger than the 1000000 mm");
  expect_error(sheet_with("[10, 10]", "1e-9"), "sheet.thickness_mm", "smaller than");
  expect_error(sheet_with("[10, 10]", "1", "[0, 0, -1e300]"), "sheet.origin_mm", "+-1000000 mm");
  expect_error("solids:\n  - {type: box, centre_mm: [0, 0, 0], size_mm: [1, 1e7, 1], material: PMMA}\n",
               "solids[0].size_mm[1]", "1000000 mm");
  expect_error("solids:\n  - {type: box, centre_mm: [1e9, 0, 0], size_mm: [1, 1, 1], material: PMMA}\n",
               "solids[0].centre_mm", "+-1000000 mm");
  expect_error("solids:\n  - {type: slab, point_mm: [0, 0, 0], normal: [0, 0, 1], thickness_mm: 1e300, extent_mm: [1, 1], "
               "material: PMMA}\n",
               "solids[0].thickness_mm", "1000000 mm");
  expect_error("solids:\n  - {type: slab, point_mm: [0, 0, 0], normal: [0, 0, 1], thickness_mm: 1, extent_mm: [1, 1e308], "
               "material: PMMA}\n",
               "solids[0].extent_mm[1]", "1000000 mm");
  expect_error("solids:\n  - {type: cylinder, base_centre_mm: [0, 0, 0], axis: [0, 0, 1], radius_mm: 1e-300, length_mm: 2, "
               "material: PMMA}\n",
               "solids[0].radius_mm", "smaller than");
  expect_error("solids:\n  - {type: cylinder, base_centre_mm: [0, 0, 5e6], axis: [0, 0, 1], radius_mm: 1, length_mm: 2, "
               "material: PMMA}\n",
               "solids[0].base_centre_mm", "+-1000000 mm");
  expect_error("solids:\n  - {type: rectangle, centre_mm: [0, 0, 0], size_mm: [2e6, 1], normal: [0, 0, 1], up: [0, 1, 0]}\n",
               "solids[0].size_mm[0]", "1000000 mm");
  expect_error(packing_with("1", "[2, 2]", "1e200"), "packings[0].diameter_mm", "1000000 mm");
  // A packing whose sites run past the limit, though each number alone is fine.
  expect_error(packing_with("1", "[30000, 1]", "100"), "packings[0]", "+-1000000 mm");
  expect_error(packing_with("2", "[3, 3]", "40", ", overrides: [{region: {min_mm: [0, 0, 0], max_mm: [1e9, 1, 1]}, "
                                                   "material: PMMA}]"),
               "packings[0].overrides[0].region.max_mm", "+-1000000 mm");
  expect_error("cameras:\n  - name: a\n" + camera_line() + "    pose: {rvec: [0, 0, 0], tvec_mm: [0, 0, 1e300]}\n",
               "cameras[0].pose", "+-1000000 mm");
  // At the limits: accepted.
  EXPECT_NO_THROW((void)load(sphere_with("[0, 0, 1e6]", "1e6")));
  EXPECT_NO_THROW((void)load(sphere_with("[0, 0, -1e6]", "0.001")));
}

// A packing is counted before it is expanded: layer_size [1000, 1000] or
// layers 1e6 used to take minutes and gigabytes before any output.
TEST_F(SceneText, SolidCountIsLimitedBeforeAnythingIsExpanded) {
  const auto start = std::chrono::steady_clock::now();
  expect_error(packing_with("1", "[1000, 1000]"), "packings[0]", "more than the 100000 solids a scene may hold");
  expect_error(packing_with("1e6", "[1, 1]"), "packings[0]", "100000 solids");
  expect_error(packing_with("2147483647", "[2147483647, 2147483647]"), "packings[0]", "100000 solids");
  // Each packing within the limit, together over it.
  expect_error(packing_with("1", "[300, 300]") + "  - {lattice: sc, diameter_mm: 1, layers: 1, layer_size: [200, 100], "
                                                  "origin_mm: [0, 0, -100], material: N-BK7}\n",
               "packings[1]", "with the 90000 solids before it");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  std::string overrides = ", overrides: [";
  for (int k = 0; k <= static_cast<int>(kMaxPackingOverrides); ++k) overrides += "{sphere: [0, 0, 0], material: PMMA},";
  overrides.back() = ']';
  expect_error(packing_with("1", "[2, 2]", "40", overrides), "packings[0].overrides", "more than the 1000");

  // The count itself, without overflow, and expand_packing refusing on its own.
  EXPECT_EQ(packing_sphere_count(packing(Lattice::bcc, 3, 4, 5)), 2u * 20 + 12);
  EXPECT_EQ(packing_sphere_count(packing(Lattice::sc, 3, 4, 5)), 60u);
  EXPECT_EQ(packing_sphere_count(packing(Lattice::sc, INT_MAX, INT_MAX, INT_MAX)), UINT64_MAX);
  EXPECT_EQ(packing_sphere_count(packing(Lattice::sc, 0, 4, 5)), 0u);
  EXPECT_EQ(expand_packing(packing(Lattice::bcc, 3, 4, 5)).size(), 52u);
  EXPECT_THROW((void)expand_packing(packing(Lattice::sc, 1000, 1000, 1000)), InputError);
  Scene scene;
  scene.source = "code";
  scene.packings.push_back(packing(Lattice::sc, 1, 1000, 1000));
  try {
    (void)scene.all_spheres();
    ADD_FAILURE() << "expanded";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "code");
    EXPECT_EQ(e.field(), "packings[0]");
  }
}

// At the limit, validation (the overlap check included) stays quick.
TEST(SceneLimits, AFullScaleScenesValidationIsQuick) {
  Scene scene;
  scene.packings.push_back(packing(Lattice::bcc, 64, 40, 40, 1));  // 32 * 1600 + 32 * 1521 spheres
  ASSERT_LE(packing_sphere_count(scene.packings[0]), kMaxSceneSolids);
  ASSERT_GT(packing_sphere_count(scene.packings[0]), kMaxSceneSolids - 1000);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_NO_THROW(validate(scene));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  // As many spheres all in one place: the first overlap ends the search.
  Scene pile;
  pile.spheres.resize(kMaxSceneSolids);
  for (std::size_t k = 0; k < pile.spheres.size(); ++k) {
    pile.spheres[k].diameter_mm = 1 + 1e-3 * double(k % 7);
    pile.spheres[k].material = "N-BK7";
    pile.spheres[k].field = "solids[" + std::to_string(k) + "]";
  }
  const auto pile_start = std::chrono::steady_clock::now();
  try {
    validate(pile);
    ADD_FAILURE() << "overlap not found";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "solids[1]");
    EXPECT_NE(e.problem().find("overlaps solids[0]"), std::string::npos) << e.what();
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - pile_start).count(), 5.0);
  // And an overlap is still found, naming the later of the two.
  SphereSolid extra;
  extra.centre_mm = packing_sphere_centre(scene.packings[0], 30, 20, 20) + Eigen::Vector3d(0.1, 0, 0);
  extra.diameter_mm = 1;
  extra.material = "N-BK7";
  extra.field = "solids[0]";
  scene.spheres.push_back(extra);
  try {
    validate(scene);
    ADD_FAILURE() << "overlap not found";
  } catch (const InputError& e) {
    EXPECT_NE(e.field().find("packings[0].spheres["), std::string::npos) << e.what();
    EXPECT_NE(e.problem().find("overlaps solids[0]"), std::string::npos) << e.what();
  }
}

// Non-finite or absurd numbers the reader used to take silently.
TEST_F(SceneText, AbsurdNumbersAreRefusedNamingTheLimit) {
  expect_error("wavelength_nm: 1e300\n", "wavelength_nm", "[100, 20000] nm");
  expect_error("wavelength_nm: 1e-300\n", "wavelength_nm", "[100, 20000] nm");
  expect_error("wavelength_nm: .nan\n", "wavelength_nm", "finite");
  expect_error("materials:\n  glass: {index: 1e300}\n", "materials.glass.index", "[0.5, 10]");
  expect_error("materials:\n  glass: {index: 1.5, absorption_per_mm: 1e300}\n", "materials.glass.absorption_per_mm",
               "[0, 1000000]");
  expect_error("materials:\n  glass: {index: .inf}\n", "materials.glass.index", "finite");
  expect_error("background: {radiance: 1e300}\n", "background.radiance", "[0, 1000000]");
  expect_error("background: {radiance: -.inf}\n", "background.radiance", "finite");
  std::ofstream(dir_ / "tet.stl") << "solid t\nendsolid t\n";
  expect_error("meshes:\n  - {file: tet.stl, material: N-BK7, scale: 1e300}\n", "meshes[0].scale",
               "[1e-06, 1000000]");
  // A scene built in code is held to the same limits.
  Scene scene;
  scene.source = "code";
  scene.materials["glass"] = material_with_index("glass", 1e300);
  scene.fluid = "glass";
  EXPECT_THROW(validate(scene), InputError);
}

// Any problem with a file the scene names is the scene's, at that field: a
// name over the system's limit used to escape as an internal error.
TEST_F(SceneText, FileNamesTheSystemRefusesAreInputErrors) {
  const std::string long_name(300, 'c');
  expect_error("cameras:\n  - name: a\n    file: " + long_name + ".yaml\n", "cameras[0].file", "(305 characters)");
  expect_error("meshes:\n  - {file: " + long_name + ".stl, material: N-BK7}\n", "meshes[0].file", "cannot be used");
  expect_error("solids:\n  - {type: rectangle, centre_mm: [0, 0, 0], size_mm: [1, 1], normal: [0, 0, 1], up: [0, 1, 0], "
               "texture: " + long_name + ".png}\n",
               "solids[0].texture", "cannot be used");
  fs::create_directories(dir_ / "folder.yaml");
  expect_error("cameras:\n  - name: a\n    file: folder.yaml\n", "cameras[0].file", "is a folder");
  expect_error("meshes:\n  - {file: ., material: N-BK7}\n", "meshes[0].file", "is a folder");
  expect_error("cameras:\n  - name: a\n    file: \"\"\n", "cameras[0].file", "must name a camera file");
  // A path through a file, not a folder.
  std::ofstream(dir_ / "plain") << "x";
  expect_error("cameras:\n  - name: a\n    file: plain/cam.yaml\n", "cameras[0].file", "cam.yaml");
}

}  // namespace
}  // namespace glasspiv
