// Transport map file and cache key: bit-exact round trip of a real map, the
// fingerprint's sensitivity to every input, the cache lookup's reasons, one-line
// errors naming the path and the field, atomic writes, the checksum's XXH64
// known answers.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include <unistd.h>

#include "tests/temp_dir.h"
#include "render/transport_map_file.h"
#include "tests/render/test_maps.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

constexpr std::size_t kHeaderBytes = 144;

std::size_t padded8(std::size_t bytes) { return (bytes + 7) / 8 * 8; }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void spill(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}


// After patching the payload: a valid checksum again, so that the later checks are reached.
void reseal(std::string& bytes) {
  poke(bytes, 136, transport_map_checksum(bytes.data() + kHeaderBytes, bytes.size() - kHeaderBytes));
}

// ------------------------------------------------------------------ inputs

// The camera's constructor arguments, so that each can be changed alone.
struct CameraParams {
  int width = 32, height = 24;
  double fx = 40, fy = 41, cx = 15.5, cy = 11.5;
  std::vector<double> distortion = {-0.05, 0.01, 0.001, -0.002, 0.003};
  CameraModel make() const { return CameraModel(width, height, fx, fy, cx, cy, distortion); }
};

struct Inputs {
  TraceScene scene;
  CameraParams camera;
  RigidTransform pose;
  TraceOptions options;
  int samples = 2;

  std::uint64_t fingerprint() const {
    return transport_map_fingerprint(scene, camera.make(), pose, options, samples);
  }
};

// A glass sphere in front of the small camera (camera at the origin looking down +z),
// the sheet behind it: direct, refracted and reflected crossings.
Inputs sphere_inputs() {
  Inputs in;
  in.scene.fluid_index = 1.333;
  in.scene.sheet.origin_mm = Eigen::Vector3d(0, 0, 150);
  in.scene.sheet.extent_s_mm = 200;
  in.scene.sheet.extent_t_mm = 180;
  in.scene.solids.push_back({Sphere{Eigen::Vector3d(2, -1, 100), 20}, TraceMaterial::glass(1.52, 0.002)});
  in.pose.translation_mm = Eigen::Vector3d(0.5, -0.25, 0.125);
  return in;
}

// Every shape kind, for the fingerprint only (not traced).
Inputs all_shapes_inputs() {
  Inputs in = sphere_inputs();
  in.scene.solids.push_back({make_slab(Eigen::Vector3d(0, 0, 60), Eigen::Vector3d(0.1, 0, 1).normalized(), 5, 80),
                             TraceMaterial::glass(1.47)});
  in.scene.solids.push_back(
      {Cylinder{Eigen::Vector3d(30, 0, 120), Eigen::Vector3d::UnitY(), 8, 40}, TraceMaterial::glass(1.6, 0.01)});
  in.scene.solids.push_back({Rectangle{Eigen::Vector3d(0, 0, 300), Eigen::Vector3d::UnitX(),
                                       Eigen::Vector3d::UnitY(), 90, 70},
                             TraceMaterial::opaque(0.5)});
  in.pose = RigidTransform::from_rvec_tvec(Eigen::Vector3d(0.01, -0.02, 0.03), Eigen::Vector3d(0.5, -0.25, 3));
  return in;
}

TransportMap small_map(const Inputs& in) {
  return build_transport_map(in.scene, in.camera.make(), in.pose, in.options, in.samples, 2);
}

// A real map with the footprint Jacobian filled (by the tracer if it fills
// it, else with seeded values) and a -0.0 and the smallest denormal to check
// bit-exactness (a NaN is refused: no traced map holds one).
TransportMap map_with_footprint(const Inputs& in) {
  TransportMap map = small_map(in);
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<float> u(-2, 2);
  for (auto* v : {&map.ds_dcol, &map.ds_drow, &map.dt_dcol, &map.dt_drow}) {
    if (v->size() != map.crossing_count()) {
      v->resize(map.crossing_count());
      for (float& x : *v) x = u(rng);
    }
  }
  map.ds_dcol[0] = -0.0f;
  map.dt_drow[1] = std::numeric_limits<float>::denorm_min();
  // Every statistic distinct and non-zero, so that a swapped or dropped field shows.
  long next = 1000;
  for (long* v : {&map.stats.camera_rays, &map.stats.branches_traced, &map.stats.crossings,
                  &map.stats.pixels_without_solid_hit, &map.stats.unproject_failures, &map.stats.closed_form_rays,
                  &map.stats.branches_cut_by_weight, &map.stats.branches_cut_by_depth, &map.stats.reflections_skipped})
    if (*v == 0) *v = ++next;
  if (map.stats.cut_weight == 0) map.stats.cut_weight = 0.1234567890123;
  return map;
}

void expect_identical(const TransportMap& a, const TransportMap& b) {
  expect_same_map_arrays(a, b);
  EXPECT_EQ(a.stats.camera_rays, b.stats.camera_rays);
  EXPECT_EQ(a.stats.branches_traced, b.stats.branches_traced);
  EXPECT_EQ(a.stats.crossings, b.stats.crossings);
  EXPECT_EQ(a.stats.pixels_without_solid_hit, b.stats.pixels_without_solid_hit);
  EXPECT_EQ(a.stats.unproject_failures, b.stats.unproject_failures);
  EXPECT_EQ(a.stats.closed_form_rays, b.stats.closed_form_rays);
  EXPECT_EQ(a.stats.branches_cut_by_weight, b.stats.branches_cut_by_weight);
  EXPECT_EQ(a.stats.branches_cut_by_depth, b.stats.branches_cut_by_depth);
  EXPECT_EQ(a.stats.reflections_skipped, b.stats.reflections_skipped);
  EXPECT_EQ(std::memcmp(&a.stats.cut_weight, &b.stats.cut_weight, sizeof(double)), 0);
  EXPECT_EQ(a.stats.threads, b.stats.threads);
}

// ------------------------------------------------------------------ round trip

TEST(TransportMapFile, RoundTripIsBitExact) {
  TempDir dir("glasspiv_tmf");
  const Inputs in = sphere_inputs();
  const TransportMap map = map_with_footprint(in);
  // The map is a real one: refracted and reflected crossings, pixels with and without the sphere.
  std::set<int> tags(map.tag.begin(), map.tag.end());
  ASSERT_EQ(tags, (std::set<int>{0, 1, 2}));
  ASSERT_GT(map.stats.pixels_without_solid_hit, 0);
  ASSERT_LT(map.stats.pixels_without_solid_hit, 32 * 24);
  ASSERT_GT(map.crossing_count(), map.pixel_count());

  const std::string path = dir.file("sphere.tmap");
  const std::uint64_t fp = in.fingerprint();
  write_transport_map(path, map, fp);
  std::uint64_t read_fp = 0;
  const TransportMap back = read_transport_map(path, &read_fp);
  EXPECT_EQ(read_fp, fp);
  expect_identical(map, back);
  EXPECT_TRUE(std::signbit(back.ds_dcol[0]));
  EXPECT_EQ(back.dt_drow[1], std::numeric_limits<float>::denorm_min());

  // The size is exactly the documented layout's.
  const std::size_t p = map.pixel_count(), c = map.crossing_count();
  EXPECT_EQ(fs::file_size(path), kHeaderBytes + padded8(4 * (p + 1)) + 7 * padded8(4 * c) + padded8(c) +
                                     2 * padded8(4 * p));
  // The header's checksum (hashed array by array) is XXH64 of the whole payload.
  const std::string first = slurp(path);
  std::uint64_t stored = 0;
  std::memcpy(&stored, first.data() + 136, 8);
  EXPECT_EQ(stored, transport_map_checksum(first.data() + kHeaderBytes, first.size() - kHeaderBytes));
  EXPECT_EQ(first.compare(0, 8, "GPIVTMAP"), 0);
  // Writing the same map again gives the same bytes.
  write_transport_map(path, map, fp);
  EXPECT_EQ(slurp(path), first);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"sphere.tmap"});  // no temporary left behind
}

TEST(TransportMapFile, RoundTripWithoutFootprintAndWithOnePixel) {
  TempDir dir("glasspiv_tmf");
  const Inputs in = sphere_inputs();
  TransportMap map = small_map(in);
  for (auto* v : {&map.ds_dcol, &map.ds_drow, &map.dt_dcol, &map.dt_drow}) v->clear();
  write_transport_map(dir.file("a.tmap"), map, 7);
  const TransportMap back = read_transport_map(dir.file("a.tmap"));
  expect_identical(map, back);
  EXPECT_TRUE(back.ds_dcol.empty());
  EXPECT_EQ(fs::file_size(dir.file("a.tmap")), kHeaderBytes + padded8(4 * (map.pixel_count() + 1)) +
                                                   3 * padded8(4 * map.crossing_count()) +
                                                   padded8(map.crossing_count()) + 2 * padded8(4 * map.pixel_count()));

  // One pixel, no crossings: sections of odd sizes, all padded.
  TransportMap tiny;
  tiny.width = tiny.height = 1;
  tiny.pixel_offsets = {0, 0};
  tiny.background_weight = {0.75f};
  tiny.opaque_weight = {0.25f};
  tiny.stats.threads = 3;
  write_transport_map(dir.file("tiny.tmap"), tiny, 0);
  expect_identical(tiny, read_transport_map(dir.file("tiny.tmap")));
}

TEST(TransportMapFile, WriterRefusesAnInconsistentMap) {
  TempDir dir("glasspiv_tmf");
  const TransportMap good = small_map(sphere_inputs());
  const std::map<std::string, std::function<void(TransportMap&)>> breakages = {
      {"short s_mm", [](TransportMap& m) { m.s_mm.pop_back(); }},
      {"short background", [](TransportMap& m) { m.background_weight.pop_back(); }},
      {"one Jacobian array", [](TransportMap& m) { m.ds_dcol.assign(m.crossing_count(), 0.f); }},
      {"decreasing offsets", [](TransportMap& m) { std::swap(m.pixel_offsets[10], m.pixel_offsets[500]); }},
      {"last offset", [](TransportMap& m) { m.pixel_offsets.back() -= 1; }},
      {"tag", [](TransportMap& m) { m.tag[3] = 3; }},
      {"samples", [](TransportMap& m) { m.samples_per_axis = 0; }},
      {"width", [](TransportMap& m) { m.width = 0; }},
      {"NaN s", [](TransportMap& m) { m.s_mm[4] = std::numeric_limits<float>::quiet_NaN(); }},
      {"infinite t", [](TransportMap& m) { m.t_mm[4] = -std::numeric_limits<float>::infinity(); }},
      {"negative weight", [](TransportMap& m) { m.weight[2] = -1e-30f; }},
      {"NaN weight", [](TransportMap& m) { m.weight[2] = std::numeric_limits<float>::quiet_NaN(); }},
      {"infinite background", [](TransportMap& m) { m.background_weight[7] = std::numeric_limits<float>::infinity(); }},
      {"negative opaque", [](TransportMap& m) { m.opaque_weight[7] = -0.5f; }},
      {"NaN Jacobian",
       [](TransportMap& m) {
         for (auto* v : {&m.ds_dcol, &m.ds_drow, &m.dt_dcol, &m.dt_drow}) v->assign(m.crossing_count(), 0.f);
         m.dt_drow.back() = std::numeric_limits<float>::quiet_NaN();
       }},
  };
  for (const auto& [name, breakage] : breakages) {
    TransportMap bad = good;
    for (auto* v : {&bad.ds_dcol, &bad.ds_drow, &bad.dt_dcol, &bad.dt_drow}) v->clear();
    breakage(bad);
    EXPECT_THROW(write_transport_map(dir.file("bad.tmap"), bad, 1), std::invalid_argument) << name;
  }
  EXPECT_TRUE(dir.entries().empty());
}

// ------------------------------------------------------------------ fingerprint

TEST(TransportMapFingerprint, SameInputsBuiltTwiceGiveTheSameFingerprint) {
  const Inputs a = all_shapes_inputs(), b = all_shapes_inputs();
  EXPECT_EQ(a.fingerprint(), b.fingerprint());
  EXPECT_EQ(fingerprint_hex(a.fingerprint()).size(), 16u);
  EXPECT_EQ(fingerprint_hex(0x0123456789abcdefull), "0123456789abcdef");
  EXPECT_EQ(fingerprint_hex(0xfedcba9876543210ull), "fedcba9876543210");
  // -0.0 and 0.0 are the same input.
  Inputs c = all_shapes_inputs();
  ASSERT_EQ(c.scene.sheet.origin_mm.x(), 0.0);
  c.scene.sheet.origin_mm.x() = -0.0;
  EXPECT_EQ(c.fingerprint(), a.fingerprint());
  // A reflected cut-off at or below min_weight traces the same map: the same
  // fingerprint as without one (maps made before the option keep theirs).
  Inputs d = a;
  d.options.min_weight_reflected = d.options.min_weight;
  EXPECT_EQ(d.fingerprint(), a.fingerprint());
  // The thread count is not an input.
  EXPECT_NE(a.fingerprint(), 0u);
}

TEST(TransportMapFingerprint, ChangesWithEverySingleInput) {
  using Change = std::function<void(Inputs&)>;
  auto sphere = [](Inputs& in) -> Sphere& { return std::get<Sphere>(in.scene.solids[0].shape); };
  auto box = [](Inputs& in) -> Box& { return std::get<Box>(in.scene.solids[1].shape); };
  auto cylinder = [](Inputs& in) -> Cylinder& { return std::get<Cylinder>(in.scene.solids[2].shape); };
  auto rectangle = [](Inputs& in) -> Rectangle& { return std::get<Rectangle>(in.scene.solids[3].shape); };
  const std::vector<std::pair<std::string, Change>> changes = {
      {"sphere centre x + 1e-9", [&](Inputs& in) { sphere(in).centre_mm.x() += 1e-9; }},
      {"sphere centre z + 1e-9", [&](Inputs& in) { sphere(in).centre_mm.z() += 1e-9; }},
      {"sphere radius", [&](Inputs& in) { sphere(in).radius_mm += 1e-9; }},
      {"sphere becomes a cylinder of the same numbers",
       [&](Inputs& in) { in.scene.solids[0].shape = Cylinder{Eigen::Vector3d(2, -1, 100), Eigen::Vector3d::UnitZ(), 20, 20}; }},
      {"box centre", [&](Inputs& in) { box(in).centre_mm.y() += 1e-9; }},
      {"box rotation", [&](Inputs& in) { box(in).world_from_box(0, 1) += 1e-12; }},
      {"box half extent", [&](Inputs& in) { box(in).half_extent_mm.z() += 1e-9; }},
      {"cylinder centre", [&](Inputs& in) { cylinder(in).centre_mm.x() += 1e-9; }},
      {"cylinder axis", [&](Inputs& in) { cylinder(in).axis.x() += 1e-12; }},
      {"cylinder radius", [&](Inputs& in) { cylinder(in).radius_mm += 1e-9; }},
      {"cylinder half length", [&](Inputs& in) { cylinder(in).half_length_mm += 1e-9; }},
      {"rectangle centre", [&](Inputs& in) { rectangle(in).centre_mm.z() += 1e-9; }},
      {"rectangle right", [&](Inputs& in) { rectangle(in).right.y() += 1e-12; }},
      {"rectangle up", [&](Inputs& in) { rectangle(in).up.x() += 1e-12; }},
      {"rectangle half width", [&](Inputs& in) { rectangle(in).half_width_mm += 1e-9; }},
      {"rectangle half height", [&](Inputs& in) { rectangle(in).half_height_mm += 1e-9; }},
      {"solid order", [&](Inputs& in) { std::swap(in.scene.solids[1], in.scene.solids[2]); }},
      {"one solid fewer", [&](Inputs& in) { in.scene.solids.pop_back(); }},
      {"material index", [&](Inputs& in) { in.scene.solids[0].material.refractive_index += 1e-12; }},
      {"material absorption", [&](Inputs& in) { in.scene.solids[0].material.absorption_per_mm += 1e-12; }},
      {"material kind", [&](Inputs& in) { in.scene.solids[0].material.kind = TraceMaterial::Kind::opaque; }},
      {"material albedo", [&](Inputs& in) { in.scene.solids[3].material.albedo += 1e-12; }},
      {"fluid index", [&](Inputs& in) { in.scene.fluid_index += 1e-12; }},
      {"sheet origin", [&](Inputs& in) { in.scene.sheet.origin_mm.z() += 1e-9; }},
      {"sheet s axis", [&](Inputs& in) { in.scene.sheet.s_axis.z() += 1e-12; }},
      {"sheet t axis", [&](Inputs& in) { in.scene.sheet.t_axis.z() += 1e-12; }},
      {"sheet extent s", [&](Inputs& in) { in.scene.sheet.extent_s_mm += 1e-9; }},
      {"sheet extent t", [&](Inputs& in) { in.scene.sheet.extent_t_mm += 1e-9; }},
      {"camera width", [&](Inputs& in) { in.camera.width += 1; }},
      {"camera height", [&](Inputs& in) { in.camera.height += 1; }},
      {"camera fx + 1e-9", [&](Inputs& in) { in.camera.fx += 1e-9; }},
      {"camera fy", [&](Inputs& in) { in.camera.fy += 1e-9; }},
      {"camera cx", [&](Inputs& in) { in.camera.cx += 1e-9; }},
      {"camera cy", [&](Inputs& in) { in.camera.cy += 1e-9; }},
      {"distortion k1", [&](Inputs& in) { in.camera.distortion[0] += 1e-12; }},
      {"distortion k3", [&](Inputs& in) { in.camera.distortion[4] += 1e-12; }},
      {"distortion model 5 -> 8 (zeros)", [&](Inputs& in) { in.camera.distortion.resize(8, 0.0); }},
      {"pose translation + 1e-9", [&](Inputs& in) { in.pose.translation_mm.x() += 1e-9; }},
      {"pose rotation", [&](Inputs& in) { in.pose.rotation(2, 0) += 1e-12; }},
      {"options.reflections", [&](Inputs& in) { in.options.reflections = !in.options.reflections; }},
      {"options.min_weight", [&](Inputs& in) { in.options.min_weight *= 1.0000001; }},
      {"options.min_weight_reflected above min_weight",
       [&](Inputs& in) { in.options.min_weight_reflected = 3 * in.options.min_weight; }},
      {"options.reflection_grid", [&](Inputs& in) { in.options.reflection_grid = 2; }},
      {"options.reflection_grid_tolerance with a grid",
       [&](Inputs& in) {
         in.options.reflection_grid = 2;
         in.options.reflection_grid_tolerance *= 2;
       }},
      {"options.grid_whole_samples with a grid",
       [&](Inputs& in) {
         in.options.reflection_grid = 2;
         in.options.grid_whole_samples = true;
       }},
      {"options.grid_whole_samples with a grid, no reflections",
       [&](Inputs& in) {
         in.options.reflections = false;
         in.options.reflection_grid = 2;
         in.options.grid_whole_samples = true;
       }},
      {"options.reflection_grid_levels with a grid",
       [&](Inputs& in) {
         in.options.reflection_grid = 2;
         in.options.reflection_grid_levels = 2;
       }},
      {"options.max_depth", [&](Inputs& in) { in.options.max_depth += 1; }},
      {"samples_per_axis", [&](Inputs& in) { in.samples += 1; }},
  };
  const std::uint64_t base = all_shapes_inputs().fingerprint();
  std::map<std::uint64_t, std::string> seen = {{base, "base"}};
  for (const auto& [name, change] : changes) {
    Inputs in = all_shapes_inputs();
    change(in);
    const std::uint64_t fp = in.fingerprint();
    EXPECT_NE(fp, base) << name;
    const auto [it, fresh] = seen.emplace(fp, name);
    EXPECT_TRUE(fresh) << name << " gives the fingerprint of " << it->second;
  }
}

// The fingerprint hashes every field of these structs. A struct that grows
// (a new option, a new shape field) fails here until transport_map_fingerprint
// hashes the new field; then update the size below. LP64 layouts (Linux x86-64, arm64).
TEST(TransportMapFingerprint, HashesEveryFieldOfTheInputStructs) {
#if defined(__LP64__)
  // record_solids_met (the last field) changes no crossing of a map: not hashed.
  EXPECT_EQ(sizeof(TraceOptions), 56u) << "TraceOptions changed: hash the new field in transport_map_fingerprint";
  EXPECT_EQ(sizeof(TraceMaterial), 32u) << "TraceMaterial changed: hash the new field";
  EXPECT_EQ(sizeof(SheetPlane), 88u) << "SheetPlane changed: hash the new field";
  EXPECT_EQ(sizeof(TraceScene), 24u + 8u + sizeof(SheetPlane)) << "TraceScene changed: hash the new field";
  EXPECT_EQ(sizeof(TraceSolid), sizeof(Shape) + sizeof(TraceMaterial)) << "TraceSolid changed: hash the new field";
  EXPECT_EQ(sizeof(Sphere), 32u) << "Sphere changed: hash the new field";
  EXPECT_EQ(sizeof(Box), 120u) << "Box changed: hash the new field";
  EXPECT_EQ(sizeof(Cylinder), 64u) << "Cylinder changed: hash the new field";
  EXPECT_EQ(sizeof(Rectangle), 88u) << "Rectangle changed: hash the new field";
  // subtrees_interpolated and samples_interpolated (8 bytes each) count work saved and are not stored.
  EXPECT_EQ(sizeof(TransportStats), 104u) << "TransportStats changed: store the new field in the file header";
  EXPECT_EQ(sizeof(RigidTransform), 96u) << "RigidTransform changed: hash the new field";
  EXPECT_EQ(std::variant_size_v<Shape>, 5u) << "new Shape alternative: hash it (the visitor will not compile)";
#else
  GTEST_SKIP() << "struct sizes are checked on LP64 hosts";
#endif
}

// ------------------------------------------------------------------ cache lookup

TEST(TransportMapCache, LoadsOnlyAnIntactMapOfTheSameSetup) {
  TempDir dir("glasspiv_tmf");
  const Inputs in = sphere_inputs();
  const TransportMap map = map_with_footprint(in);
  const std::uint64_t fp = in.fingerprint();
  const std::string path = dir.file("cache.tmap");
  std::string why = "stale";

  EXPECT_FALSE(load_cached_transport_map(path, fp, &why));
  EXPECT_EQ(why, "no file");

  write_transport_map(path, map, fp);
  const auto hit = load_cached_transport_map(path, fp, &why);
  ASSERT_TRUE(hit);
  EXPECT_EQ(why, "");
  expect_identical(map, *hit);

  Inputs other = in;
  other.options.min_weight = 1e-3;
  const std::uint64_t other_fp = other.fingerprint();
  EXPECT_FALSE(load_cached_transport_map(path, other_fp, &why));
  EXPECT_EQ(why, "made for another setup (fingerprint " + fingerprint_hex(fp) + ", wanted " +
                     fingerprint_hex(other_fp) + ")");
  EXPECT_FALSE(load_cached_transport_map(path, other_fp));  // why is optional

  const std::string good = slurp(path);
  auto expect_unreadable = [&](const std::string& bytes, const std::string& field, const std::string& what) {
    spill(path, bytes);
    std::string reason;
    EXPECT_FALSE(load_cached_transport_map(path, fp, &reason)) << what;
    EXPECT_EQ(reason.rfind("unreadable: " + path + ": field '" + field + "'", 0), 0u) << what << ": " << reason;
    EXPECT_EQ(reason.find('\n'), std::string::npos) << reason;
  };
  expect_unreadable(good.substr(0, good.size() - 9), "payload", "truncated");
  expect_unreadable(good.substr(0, 50), "header", "truncated header");
  std::string flipped = good;
  flipped[good.size() / 2] ^= 0x10;
  expect_unreadable(flipped, "header.checksum", "flipped payload byte");
  std::string magic = good;
  magic[3] = 'X';
  expect_unreadable(magic, "magic", "wrong magic");
  expect_unreadable("", "magic", "empty file");

  // The intact file is found again.
  spill(path, good);
  EXPECT_TRUE(load_cached_transport_map(path, fp));
}

// ------------------------------------------------------------------ read errors

TEST(TransportMapFile, ReadErrorsNameThePathAndTheField) {
  TempDir dir("glasspiv_tmf");
  const TransportMap map = map_with_footprint(sphere_inputs());
  const std::string path = dir.file("m.tmap");
  write_transport_map(path, map, 42);
  const std::string good = slurp(path);
  const std::size_t p = map.pixel_count(), c = map.crossing_count();
  const std::size_t tag_at = kHeaderBytes + padded8(4 * (p + 1)) + 3 * padded8(4 * c);
  const std::size_t offsets_at = kHeaderBytes;
  const std::size_t s_at = kHeaderBytes + padded8(4 * (p + 1)), t_at = s_at + padded8(4 * c),
                    weight_at = t_at + padded8(4 * c), jacobian_at = tag_at + padded8(c),
                    background_at = jacobian_at + 4 * padded8(4 * c), opaque_at = background_at + padded8(4 * p);
  ASSERT_EQ(opaque_at + padded8(4 * p), good.size());
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  auto forge = [](std::string& b, std::size_t at, float v) {
    poke(b, at, v);
    reseal(b);
  };

  struct Case {
    std::string name, field;
    std::function<void(std::string&)> damage;
  };
  const std::vector<Case> cases = {
      {"magic", "magic", [](std::string& b) { b[0] = 'g'; }},
      {"version", "header.version", [](std::string& b) { poke<std::uint32_t>(b, 8, 2); }},
      {"header size", "header.header_size", [](std::string& b) { poke<std::uint32_t>(b, 12, 112); }},
      {"width", "header.width", [](std::string& b) { poke<std::int32_t>(b, 24, 0); }},
      {"height", "header.height", [](std::string& b) { poke<std::int32_t>(b, 28, -3); }},
      {"samples", "header.samples_per_axis", [](std::string& b) { poke<std::int32_t>(b, 32, 0); }},
      {"flags", "header.flags", [](std::string& b) { poke<std::uint32_t>(b, 36, 3); }},
      {"crossing count too big", "header.crossing_count", [](std::string& b) { poke<std::uint64_t>(b, 40, 1ull << 32); }},
      {"crossing count", "payload", [c](std::string& b) { poke<std::uint64_t>(b, 40, c + 8); }},
      {"pixel count", "payload", [](std::string& b) { poke<std::int32_t>(b, 24, 1 << 30); }},
      {"flags off", "payload", [](std::string& b) { poke<std::uint32_t>(b, 36, 0); }},
      {"negative stat", "header.stats.branches_traced", [](std::string& b) { poke<std::int64_t>(b, 56, -1); }},
      {"negative cut weight", "header.stats.cut_weight", [](std::string& b) { poke<double>(b, 120, -0.5); }},
      {"NaN cut weight", "header.stats.cut_weight",
       [](std::string& b) { poke<double>(b, 120, std::numeric_limits<double>::quiet_NaN()); }},
      {"reserved", "header.reserved", [](std::string& b) { poke<std::uint32_t>(b, 132, 1); }},
      {"trailing bytes", "payload", [](std::string& b) { b += std::string(8, '\0'); }},
      {"truncated", "payload", [](std::string& b) { b.resize(b.size() - 1); }},
      {"checksum in the header", "header.checksum", [](std::string& b) { b[136] ^= 1; }},
      {"flipped bit in the last section", "header.checksum", [](std::string& b) { b[b.size() - 5] ^= 0x80; }},
      {"offsets start", "pixel_offsets",
       [&](std::string& b) {
         poke<std::uint32_t>(b, offsets_at, 1);
         reseal(b);
       }},
      {"offsets decrease", "pixel_offsets",
       [&](std::string& b) {
         poke<std::uint32_t>(b, offsets_at + 4 * 300, std::numeric_limits<std::uint32_t>::max() - 1);
         reseal(b);
       }},
      {"offsets end", "pixel_offsets",
       [&](std::string& b) {
         poke<std::uint32_t>(b, offsets_at + 4 * p, static_cast<std::uint32_t>(c - 1));
         reseal(b);
       }},
      {"tag out of range", "tag",
       [&](std::string& b) {
         b[tag_at + c - 1] = 3;
         reseal(b);
       }},
      // Forged payloads, their checksum recomputed: values no traced map holds.
      {"NaN s", "s_mm", [&](std::string& b) { forge(b, s_at + 4 * 5, nan); }},
      {"infinite t", "t_mm", [&](std::string& b) { forge(b, t_at, -inf); }},
      {"negative weight", "weight", [&](std::string& b) { forge(b, weight_at + 4 * (c - 1), -0.25f); }},
      {"infinite weight", "weight", [&](std::string& b) { forge(b, weight_at, inf); }},
      {"NaN ds_dcol", "ds_dcol", [&](std::string& b) { forge(b, jacobian_at, nan); }},
      {"infinite ds_drow", "ds_drow", [&](std::string& b) { forge(b, jacobian_at + padded8(4 * c), inf); }},
      {"NaN dt_dcol", "dt_dcol", [&](std::string& b) { forge(b, jacobian_at + 2 * padded8(4 * c) + 8, nan); }},
      {"infinite dt_drow", "dt_drow", [&](std::string& b) { forge(b, jacobian_at + 3 * padded8(4 * c) + 4, -inf); }},
      {"NaN background", "background_weight", [&](std::string& b) { forge(b, background_at + 4 * (p - 1), nan); }},
      {"negative background", "background_weight", [&](std::string& b) { forge(b, background_at, -1.0f); }},
      {"infinite opaque", "opaque_weight", [&](std::string& b) { forge(b, opaque_at + 4 * 3, inf); }},
      {"negative opaque", "opaque_weight", [&](std::string& b) { forge(b, opaque_at, -1e-30f); }},
  };
  for (const Case& k : cases) {
    std::string bytes = good;
    k.damage(bytes);
    spill(path, bytes);
    try {
      read_transport_map(path);
      ADD_FAILURE() << k.name << ": no error";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path) << k.name;
      EXPECT_EQ(e.field(), k.field) << k.name << ": " << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  }
  // The undamaged bytes read back (the cases above damaged copies only).
  spill(path, good);
  std::uint64_t fp = 0;
  expect_identical(map, read_transport_map(path, &fp));
  EXPECT_EQ(fp, 42u);

  try {
    read_transport_map(dir.file("missing.tmap"));
    ADD_FAILURE() << "missing file read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), dir.file("missing.tmap"));
  }
  EXPECT_THROW(read_transport_map(dir.file("")), InputError);  // the folder itself
}

// ------------------------------------------------------------------ atomic write

// A write that fails half way (file size limit: the write gets EFBIG) throws,
// leaves the existing file as it was and no temporary behind.
TEST(TransportMapFile, FailedWriteLeavesTheExistingFileUntouched) {
  TempDir dir("glasspiv_tmf");
  const std::string path = dir.file("keep.tmap");
  TransportMap tiny;
  tiny.width = tiny.height = 1;
  tiny.pixel_offsets = {0, 0};
  tiny.background_weight = {1.0f};
  tiny.opaque_weight = {0.0f};
  write_transport_map(path, tiny, 5);
  const std::string before = slurp(path);
  ASSERT_LT(before.size(), 4096u);

  const TransportMap big = small_map(sphere_inputs());
  rlimit old{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
  auto* old_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit low = old;
  low.rlim_cur = 4096;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &low), 0);
  bool threw = false;
  try {
    write_transport_map(path, big, 6);
  } catch (const InputError& e) {
    threw = true;
    EXPECT_EQ(e.file(), path);
  }
  ::setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_TRUE(threw);
  EXPECT_EQ(slurp(path), before);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"keep.tmap"});
  std::uint64_t fp = 0;
  expect_identical(tiny, read_transport_map(path, &fp));
  EXPECT_EQ(fp, 5u);

  // And without the limit the same write replaces it.
  write_transport_map(path, big, 6);
  expect_identical(big, read_transport_map(path, &fp));
  EXPECT_EQ(fp, 6u);
}

// ------------------------------------------------------------------ checksum

// XXH64 known answers (seed 0), as `xxhsum -H64` prints them; the last input
// is longer than one 32-byte stripe and ends in 8-, 4- and 1-byte tails.
TEST(TransportMapFile, ChecksumIsXxh64) {
  auto h = [](const std::string& s) { return transport_map_checksum(s.data(), s.size()); };
  EXPECT_EQ(h(""), 0xef46db3751d8e999ull);
  EXPECT_EQ(h("a"), 0xd24ec4f1a98c6e5bull);
  EXPECT_EQ(h("abc"), 0x44bc2cf5ad770999ull);
  EXPECT_EQ(h("Nobody inspects the spammish repetition"), 0xfbcea83c8a378bf1ull);
}

}  // namespace
}  // namespace glasspiv
