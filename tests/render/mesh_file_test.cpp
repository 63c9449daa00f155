// Tests of render/mesh_file.h: small STL (ASCII and binary), OBJ and PLY files
// written here load into the same closed mesh as their source arrays (same
// volume by the divergence theorem, welded vertices), placement and file
// normals are applied, bad files are InputErrors naming the path, and assimp
// prints nothing.
#include "render/mesh_file.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "render/scene.h"
#include "tests/render/test_meshes.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

// A sheared box: the cube [0, 2]^3 (2 x 2 squares per face) mapped by
// (x, y, z) -> (x + z, 2 y, z): integer coordinates (exact in a file's float),
// volume 2 * 8 = 16, outward winding (the map keeps orientation: det 2).
MeshArrays source() {
  MeshArrays a = grid_cube(2);
  for (Vector3d& v : a.vertices_mm) v = Vector3d(v.x() + v.z(), 2 * v.y(), v.z());
  return a;
}

Vector3d face_normal(const MeshArrays& a, const MeshTriangle& t) {
  return (a.vertices_mm[t[1]] - a.vertices_mm[t[0]]).cross(a.vertices_mm[t[2]] - a.vertices_mm[t[0]]).normalized();
}

std::string ascii_stl(const MeshArrays& a, std::size_t skip = SIZE_MAX) {
  std::string s = "solid sheared_box\n";
  for (std::size_t k = 0; k < a.triangles.size(); ++k) {
    if (k == skip) continue;
    const Vector3d n = face_normal(a, a.triangles[k]);
    s += "  facet normal " + std::to_string(n.x()) + " " + std::to_string(n.y()) + " " + std::to_string(n.z()) +
         "\n    outer loop\n";
    for (std::uint32_t i : a.triangles[k]) {
      const Vector3d& p = a.vertices_mm[i];
      s += "      vertex " + std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
    }
    s += "    endloop\n  endfacet\n";
  }
  return s + "endsolid sheared_box\n";
}

std::string binary_stl(const MeshArrays& a) {
  std::string s(80, ' ');
  const auto put32 = [&](std::uint32_t x) {
    for (int b = 0; b < 4; ++b) s.push_back(static_cast<char>((x >> (8 * b)) & 0xff));  // little-endian
  };
  const auto putf = [&](double x) {
    const float f = static_cast<float>(x);
    std::uint32_t bits;
    std::memcpy(&bits, &f, 4);
    put32(bits);
  };
  put32(static_cast<std::uint32_t>(a.triangles.size()));
  for (const MeshTriangle& t : a.triangles) {
    const Vector3d n = face_normal(a, t);
    for (int c = 0; c < 3; ++c) putf(n[c]);
    for (std::uint32_t i : t)
      for (int c = 0; c < 3; ++c) putf(a.vertices_mm[i][c]);
    s.push_back(0);
    s.push_back(0);
  }
  return s;
}

std::string obj(const MeshArrays& a) {
  std::string s = "# sheared box\no box\n";
  for (const Vector3d& p : a.vertices_mm) s += "v " + std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  for (const MeshTriangle& t : a.triangles)
    s += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " + std::to_string(t[2] + 1) + "\n";
  return s;
}

std::string ply(const MeshArrays& a) {
  std::string s = "ply\nformat ascii 1.0\ncomment sheared box\nelement vertex " + std::to_string(a.vertices_mm.size()) +
                  "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                  std::to_string(a.triangles.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const Vector3d& p : a.vertices_mm) s += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  for (const MeshTriangle& t : a.triangles)
    s += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
  return s;
}

// The cube [0, 2]^3 as six quads (the OBJ and PLY readers triangulate them),
// with per-face normals in the OBJ; the top face's normal is tilted by
// atan(0.1) towards +x so that file normals can be told from computed ones.
const char* kQuadCubeObj =
    "v 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nv 0 0 2\nv 2 0 2\nv 2 2 2\nv 0 2 2\n"
    "vn 0 0 -1\nvn 0 0 1\nvn 0 -1 0\nvn 0 1 0\nvn -1 0 0\nvn 1 0 0\nvn 0.1 0 1\n"
    "f 1//1 4//1 3//1 2//1\nf 5//7 6//7 7//7 8//7\nf 1//3 2//3 6//3 5//3\n"
    "f 4//4 8//4 7//4 3//4\nf 1//5 5//5 8//5 4//5\nf 2//6 3//6 7//6 6//6\n";
const char* kQuadCubePly =
    "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 6\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n2 0 0\n2 2 0\n0 2 0\n0 0 2\n2 0 2\n2 2 2\n0 2 2\n"
    "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 3 7 6 2\n4 0 4 7 3\n4 1 2 6 5\n";

class MeshFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("glasspiv_mesh_file_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  // Expects InputError naming `path` (as the file) with `words` in the problem.
  void expect_error(const std::string& path, const std::string& words) {
    try {
      (void)load_mesh(path);
      ADD_FAILURE() << "accepted " << path;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.field(), "");
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(e.problem().find(words), std::string::npos) << e.what();
      EXPECT_EQ(e.problem().find('\n'), std::string::npos) << "one line: " << e.what();
    }
  }
  fs::path dir_;
};

TEST_F(MeshFile, StlObjPlyLoadAsTheSourceArrays) {
  const MeshArrays a = source();
  const double v = signed_volume(a);
  ASSERT_NEAR(v, 16, 1e-12);
  for (const auto& [name, text] : std::map<std::string, std::string>{{"box.stl", ascii_stl(a)},
                                                                      {"binary.STL", binary_stl(a)},
                                                                      {"box.obj", obj(a)},
                                                                      {"box.ply", ply(a)}}) {
    SCOPED_TRACE(name);
    const std::string path = write(name, text);
    const TriangleMesh m = load_mesh(path);
    // Integer coordinates are exact in a file's float: same volume to rounding.
    EXPECT_NEAR(m.volume_mm3(), v, 1e-12 * v);
    EXPECT_EQ(m.triangle_count(), a.triangles.size());
    // STL stores each triangle's corners on their own: welded back to the source's vertices.
    EXPECT_EQ(m.vertices_mm().size(), a.vertices_mm.size());
    EXPECT_EQ(m.part_count(), 1);
    EXPECT_TRUE(bounds_mm(m).min().isApprox(Vector3d(0, 0, 0)));
    EXPECT_TRUE(bounds_mm(m).max().isApprox(Vector3d(4, 4, 2)));
    const MeshArrays raw = read_mesh_arrays(path);
    EXPECT_NEAR(std::fabs(signed_volume(raw)), v, 1e-12 * v);
  }
  // Quads are triangulated.
  for (const auto& [name, text] : std::map<std::string, std::string>{{"quads.obj", kQuadCubeObj}, {"quads.ply", kQuadCubePly}}) {
    SCOPED_TRACE(name);
    const TriangleMesh m = load_mesh(write(name, text));
    EXPECT_EQ(m.triangle_count(), 12u);
    EXPECT_NEAR(m.volume_mm3(), 8, 1e-12);
  }
}

TEST_F(MeshFile, ScaleRotationAndPositionAreApplied) {
  const MeshArrays a = source();
  const std::string path = write("box_in_metres.stl", ascii_stl(a));
  MeshPlacement placement;
  placement.scale = 1000;  // metres -> mm
  placement.world_from_mesh = rotation_from_rvec_deg(Vector3d(0, 0, 90));  // x -> y, y -> -x
  placement.position_mm = Vector3d(10, 20, 30);
  const TriangleMesh m = load_mesh(path, placement);
  EXPECT_NEAR(m.volume_mm3(), 16e9, 1e-9 * 16e9);
  // The file's (4, 4, 2) corner -> 1000 (-4, 4, 2) + (10, 20, 30).
  const Eigen::AlignedBox3d b = bounds_mm(m);
  EXPECT_NEAR(b.min().x(), -4000 + 10, 1e-9);
  EXPECT_NEAR(b.max().x(), 0 + 10, 1e-9);
  EXPECT_NEAR(b.max().y(), 4000 + 20, 1e-9);
  EXPECT_NEAR(b.max().z(), 2000 + 30, 1e-9);
  // A ray along -z from above hits the top face z = 2030 and leaves at z = 30.
  const Vector3d o(-1000 + 10, 3000 + 20, 5000);  // above the file's (3, 1) on its top face
  const auto in = intersect(m, o, -Vector3d::UnitZ(), 0);
  ASSERT_TRUE(in);
  EXPECT_NEAR(in->point.z(), 2030, 1e-9);
  EXPECT_NEAR(in->normal.z(), 1, 1e-12);
}

TEST_F(MeshFile, NormalsFlatSmoothOrFromTheFile) {
  const std::string path = write("quads.obj", kQuadCubeObj);
  MeshPlacement placement;
  placement.world_from_mesh = rotation_from_rvec_deg(Vector3d(0, 0, 90));
  const Vector3d o(-1.5, 0.5, 10), d = -Vector3d::UnitZ();  // onto the top face
  // file: the tilted top normal (0.1, 0, 1) of the file, rotated like the mesh: (0, 0.1, 1).
  MeshLoadOptions file{MeshNormals::file, 60};
  const auto h = intersect(load_mesh(path, placement, file), o, d, 0);
  ASSERT_TRUE(h && h->shading_normal);
  EXPECT_TRUE(h->shading_normal->isApprox(Vector3d(0, 0.1, 1).normalized(), 1e-7)) << h->shading_normal->transpose();
  EXPECT_NEAR(h->normal.z(), 1, 1e-15) << "the geometric normal is the face's";
  // smooth: computed; the cube's 90 degree edges stay sharp at the 60 degree crease.
  const auto s = intersect(load_mesh(path, placement, {MeshNormals::smooth, 60}), o, d, 0);
  ASSERT_TRUE(s && s->shading_normal);
  EXPECT_NEAR(s->shading_normal->z(), 1, 1e-15);
  // flat: none.
  const auto f = intersect(load_mesh(path, placement, {MeshNormals::flat, 60}), o, d, 0);
  ASSERT_TRUE(f);
  EXPECT_FALSE(f->shading_normal);
  // file, from a file without normals (PLY here): computed ones.
  const auto p = intersect(load_mesh(write("quads.ply", kQuadCubePly), placement, file), o, d, 0);
  ASSERT_TRUE(p && p->shading_normal);
  EXPECT_NEAR(p->shading_normal->z(), 1, 1e-15);
  // STL facet normals ("file"): the faces' own.
  const auto stl = intersect(load_mesh(write("box.stl", ascii_stl(source())), {}, file), Vector3d(3, 1, 10), d, 0);
  ASSERT_TRUE(stl && stl->shading_normal);
  EXPECT_NEAR(stl->shading_normal->z(), 1, 1e-6);
}

TEST_F(MeshFile, BadFilesAreInputErrorsNamingThePath) {
  expect_error((dir_ / "missing.stl").string(), "does not exist");
  expect_error(write("garbage.stl", "this is not a mesh\n\x01\x02\x03"), "cannot be read as stl");
  expect_error(write("garbage.ply", "ply\nformat nonsense\n"), "cannot be read as ply");
  expect_error(write("garbage.obj", "v 0 0\nf 1 2 3 4 5\n"), "");
  expect_error(write("part.step", "ISO-10303-21;\n"), "unsupported mesh file type '.step'");
  expect_error(write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "");
  expect_error(write("open.stl", ascii_stl(source(), 3)), "the mesh is open");
  MeshArrays inconsistent = source();
  std::swap(inconsistent.triangles[0][1], inconsistent.triangles[0][2]);
  expect_error(write("inconsistent.obj", obj(inconsistent)), "inconsistent orientation");
  fs::create_directories(dir_ / "folder.stl");
  expect_error((dir_ / "folder.stl").string(), "folder");
}

TEST_F(MeshFile, AssimpPrintsNothing) {
  const std::string good = write("box.stl", ascii_stl(source()));
  // (Not a truncated ASCII facet: assimp 5.2's STL reader leaks ~2.5 kB on one,
  // which would fail the sanitizer build; an empty solid fails its validation.)
  const std::string bad = write("bad.stl", "solid x\nendsolid x\n");
  const std::string bad_obj = write("bad.obj", "v 1 2 3\nf 1 7 9\nusemtl nothing\nmtllib missing.mtl\n");
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  (void)load_mesh(good);
  for (const std::string& path : {bad, bad_obj}) {
    try {
      (void)load_mesh(path);
    } catch (const InputError&) {
    }
  }
  const std::string out = ::testing::internal::GetCapturedStdout();
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(out, "");
  EXPECT_EQ(err, "");
}

TEST_F(MeshFile, SceneMeshErrorsNameTheSceneAndTheField) {
  Scene scene;
  scene.source = (dir_ / "setup.yaml").string();
  MeshSolid mesh;
  mesh.field = "meshes[2]";
  mesh.material = "N-BK7";
  mesh.file = write("open.stl", ascii_stl(source(), 0));
  try {
    (void)load_scene_mesh(scene, mesh);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), scene.source);
    EXPECT_EQ(e.field(), "meshes[2].file");
    EXPECT_NE(e.problem().find(mesh.file), std::string::npos) << e.what();
    EXPECT_NE(e.problem().find("open"), std::string::npos) << e.what();
  }
  mesh.file = write("box.obj", obj(source()));
  mesh.placement.scale = 2;
  EXPECT_NEAR(load_scene_mesh(scene, mesh).volume_mm3(), 16 * 8, 1e-9);
}

TEST(MeshNormalsNames, RoundTrip) {
  for (MeshNormals n : {MeshNormals::flat, MeshNormals::smooth, MeshNormals::file})
    EXPECT_EQ(mesh_normals_from_name(mesh_normals_name(n)), n);
  EXPECT_FALSE(mesh_normals_from_name("Smooth"));
}

}  // namespace
}  // namespace glasspiv
