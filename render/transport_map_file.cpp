#include "render/transport_map_file.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

#include "util/binary_file.h"
#include "util/fnv1a64.h"
#include "util/input_error.h"

namespace glasspiv {

namespace {

// ---------------------------------------------------------------- fingerprint

// One overload per Shape alternative and no catch-all: a new alternative does
// not compile until it is hashed here.
struct ShapeHasher {
  Fnv1a64& h;
  void operator()(const Sphere& s) const {
    h.vec3(s.centre_mm);
    h.f64(s.radius_mm);
  }
  void operator()(const Box& b) const {
    h.vec3(b.centre_mm);
    h.mat3(b.world_from_box);
    h.vec3(b.half_extent_mm);
  }
  void operator()(const Cylinder& c) const {
    h.vec3(c.centre_mm);
    h.vec3(c.axis);
    h.f64(c.radius_mm);
    h.f64(c.half_length_mm);
  }
  void operator()(const Rectangle& r) const {
    h.vec3(r.centre_mm);
    h.vec3(r.right);
    h.vec3(r.up);
    h.f64(r.half_width_mm);
    h.f64(r.half_height_mm);
  }
  void operator()(const TriangleMesh& m) const {
    h.u64(m.vertices_mm().size());
    for (const Eigen::Vector3d& v : m.vertices_mm()) h.vec3(v);
    h.u64(m.triangle_count());
    for (std::size_t k = 0; k < m.triangle_count(); ++k) {
      for (std::uint32_t i : m.triangles()[k]) h.u64(i);
      if (m.shading() == MeshShading::smooth)
        for (const Eigen::Vector3d& n : m.corner_normals(k)) h.vec3(n);
    }
    h.u64(static_cast<std::uint64_t>(m.shading()));
  }
};

// ---------------------------------------------------------------- layout

constexpr char kMagic[8] = {'G', 'P', 'I', 'V', 'T', 'M', 'A', 'P'};
constexpr std::uint32_t kHeaderSize = 144;
constexpr std::uint32_t kFlagFootprint = 1u;  // the four footprint Jacobian arrays are present
constexpr int kCrossingTagCount = 3;
static_assert(static_cast<int>(CrossingTag::direct) == 0 && static_cast<int>(CrossingTag::refracted_only) == 1 &&
                  static_cast<int>(CrossingTag::with_reflections) == kCrossingTagCount - 1,
              "CrossingTag changed: update the tag check and docs/transport_map_file.md");

struct Header {
  std::uint32_t version = 0, header_size = 0;
  std::uint64_t fingerprint = 0;
  std::int32_t width = 0, height = 0, samples_per_axis = 0;
  std::uint32_t flags = 0;
  std::uint64_t crossing_count = 0;
  std::int64_t camera_rays = 0, branches_traced = 0, crossings = 0, pixels_without_solid_hit = 0,
               unproject_failures = 0, closed_form_rays = 0, branches_cut_by_weight = 0, branches_cut_by_depth = 0,
               reflections_skipped = 0;
  double cut_weight = 0;
  std::int32_t threads = 0;
  std::uint32_t reserved = 0;
  std::uint64_t checksum = 0;

  std::uint64_t pixels() const { return std::uint64_t(width) * std::uint64_t(height); }
  bool footprint() const { return (flags & kFlagFootprint) != 0; }
};

// Byte offsets of the header fields (docs/transport_map_file.md).
std::array<unsigned char, kHeaderSize> encode(const Header& h) {
  std::array<unsigned char, kHeaderSize> b{};
  std::memcpy(b.data(), kMagic, 8);
  put_field(b.data(), 8, h.version);
  put_field(b.data(), 12, h.header_size);
  put_field(b.data(), 16, h.fingerprint);
  put_field(b.data(), 24, h.width);
  put_field(b.data(), 28, h.height);
  put_field(b.data(), 32, h.samples_per_axis);
  put_field(b.data(), 36, h.flags);
  put_field(b.data(), 40, h.crossing_count);
  put_field(b.data(), 48, h.camera_rays);
  put_field(b.data(), 56, h.branches_traced);
  put_field(b.data(), 64, h.crossings);
  put_field(b.data(), 72, h.pixels_without_solid_hit);
  put_field(b.data(), 80, h.unproject_failures);
  put_field(b.data(), 88, h.closed_form_rays);
  put_field(b.data(), 96, h.branches_cut_by_weight);
  put_field(b.data(), 104, h.branches_cut_by_depth);
  put_field(b.data(), 112, h.reflections_skipped);
  put_field(b.data(), 120, h.cut_weight);
  put_field(b.data(), 128, h.threads);
  put_field(b.data(), 132, h.reserved);
  put_field(b.data(), 136, h.checksum);
  return b;
}

Header decode(const unsigned char* b) {
  Header h;
  h.version = get_field<std::uint32_t>(b, 8);
  h.header_size = get_field<std::uint32_t>(b, 12);
  h.fingerprint = get_field<std::uint64_t>(b, 16);
  h.width = get_field<std::int32_t>(b, 24);
  h.height = get_field<std::int32_t>(b, 28);
  h.samples_per_axis = get_field<std::int32_t>(b, 32);
  h.flags = get_field<std::uint32_t>(b, 36);
  h.crossing_count = get_field<std::uint64_t>(b, 40);
  h.camera_rays = get_field<std::int64_t>(b, 48);
  h.branches_traced = get_field<std::int64_t>(b, 56);
  h.crossings = get_field<std::int64_t>(b, 64);
  h.pixels_without_solid_hit = get_field<std::int64_t>(b, 72);
  h.unproject_failures = get_field<std::int64_t>(b, 80);
  h.closed_form_rays = get_field<std::int64_t>(b, 88);
  h.branches_cut_by_weight = get_field<std::int64_t>(b, 96);
  h.branches_cut_by_depth = get_field<std::int64_t>(b, 104);
  h.reflections_skipped = get_field<std::int64_t>(b, 112);
  h.cut_weight = get_field<double>(b, 120);
  h.threads = get_field<std::int32_t>(b, 128);
  h.reserved = get_field<std::uint32_t>(b, 132);
  h.checksum = get_field<std::uint64_t>(b, 136);
  return h;
}

// Calls f(name, vector, element count) for every array in file order. Map is
// TransportMap or const TransportMap.
template <typename Map, typename F>
void for_each_array(Map& m, std::uint64_t pixels, std::uint64_t crossings, bool footprint, F&& f) {
  f("pixel_offsets", m.pixel_offsets, pixels + 1);
  f("s_mm", m.s_mm, crossings);
  f("t_mm", m.t_mm, crossings);
  f("weight", m.weight, crossings);
  f("tag", m.tag, crossings);
  if (footprint) {
    f("ds_dcol", m.ds_dcol, crossings);
    f("ds_drow", m.ds_drow, crossings);
    f("dt_dcol", m.dt_dcol, crossings);
    f("dt_drow", m.dt_drow, crossings);
  }
  f("background_weight", m.background_weight, pixels);
  f("opaque_weight", m.opaque_weight, pixels);
}

std::uint64_t payload_bytes(std::uint64_t pixels, std::uint64_t crossings, bool footprint) {
  const std::uint64_t per_crossing_f32 = padded8(4 * crossings) * (footprint ? 7 : 3);
  return padded8(4 * (pixels + 1)) + per_crossing_f32 + padded8(crossings) + 2 * padded8(4 * pixels);
}

std::string number(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%.9g", v);
  return s;
}

// The first problem of tag, or "" (shared by writer and reader; pixel_offsets:
// offsets_problem, util/binary_file.h).
std::string tag_problem(const std::vector<std::uint8_t>& tag) {
  for (std::size_t i = 0; i < tag.size(); ++i)
    if (tag[i] >= kCrossingTagCount)
      return "tag[" + std::to_string(i) + "] is " + std::to_string(tag[i]) +
             ", expected 0 (direct), 1 (refracted_only) or 2 (with_reflections)";
  return "";
}

// The first value that no traced map holds, as (field, problem), or {"", ""}
// (shared by writer and reader): s, t and the footprint Jacobians must be
// finite; every weight finite and not negative.
std::pair<std::string, std::string> values_problem(const TransportMap& m) {
  const std::pair<const char*, const std::vector<float>*> finite[] = {
      {"s_mm", &m.s_mm}, {"t_mm", &m.t_mm}, {"ds_dcol", &m.ds_dcol},
      {"ds_drow", &m.ds_drow}, {"dt_dcol", &m.dt_dcol}, {"dt_drow", &m.dt_drow}};
  for (const auto& [name, v] : finite)
    for (std::size_t i = 0; i < v->size(); ++i)
      if (!std::isfinite((*v)[i]))
        return {name, std::string(name) + "[" + std::to_string(i) + "] is " + number((*v)[i]) + ", must be finite"};
  const std::pair<const char*, const std::vector<float>*> weights[] = {
      {"weight", &m.weight}, {"background_weight", &m.background_weight}, {"opaque_weight", &m.opaque_weight}};
  for (const auto& [name, v] : weights)
    for (std::size_t i = 0; i < v->size(); ++i)
      if (!(std::isfinite((*v)[i]) && (*v)[i] >= 0))
        return {name, std::string(name) + "[" + std::to_string(i) + "] is " + number((*v)[i]) +
                          ", must be finite and not negative"};
  return {};
}

// ---------------------------------------------------------------- reading

Header read_header(BinaryFileReader& in) {
  unsigned char b[kHeaderSize];
  in.read_header(kMagic, "transport map", kTransportMapFormatVersion, b, kHeaderSize);
  const std::string& path = in.path();
  const Header h = decode(b);
  if (h.width <= 0) throw InputError(path, "header.width", "is " + std::to_string(h.width) + ", must be positive");
  if (h.height <= 0) throw InputError(path, "header.height", "is " + std::to_string(h.height) + ", must be positive");
  if (h.samples_per_axis < 1)
    throw InputError(path, "header.samples_per_axis", "is " + std::to_string(h.samples_per_axis) + ", must be >= 1");
  if (h.flags & ~kFlagFootprint)
    throw InputError(path, "header.flags", "unknown bits set (flags " + std::to_string(h.flags) + ")");
  if (h.crossing_count > std::numeric_limits<std::uint32_t>::max())
    throw InputError(path, "header.crossing_count",
                     "is " + std::to_string(h.crossing_count) + ", more than pixel_offsets (u32) can index");
  const std::pair<const char*, std::int64_t> counts[] = {
      {"header.stats.camera_rays", h.camera_rays},
      {"header.stats.branches_traced", h.branches_traced},
      {"header.stats.crossings", h.crossings},
      {"header.stats.pixels_without_solid_hit", h.pixels_without_solid_hit},
      {"header.stats.unproject_failures", h.unproject_failures},
      {"header.stats.closed_form_rays", h.closed_form_rays},
      {"header.stats.branches_cut_by_weight", h.branches_cut_by_weight},
      {"header.stats.branches_cut_by_depth", h.branches_cut_by_depth},
      {"header.stats.reflections_skipped", h.reflections_skipped},
      {"header.stats.threads", h.threads}};
  for (const auto& [field, value] : counts)
    if (value < 0) throw InputError(path, field, "is " + std::to_string(value) + ", must not be negative");
  if (!(h.cut_weight >= 0 && h.cut_weight <= std::numeric_limits<double>::max()))
    throw InputError(path, "header.stats.cut_weight",
                     "is " + std::to_string(h.cut_weight) + ", must be finite and not negative");
  if (h.reserved != 0) throw InputError(path, "header.reserved", "is " + std::to_string(h.reserved) + ", must be 0");
  // Every pixel takes at least 12 bytes, so this bound keeps the sums below from overflowing.
  in.expect_size(h.pixels() > in.size() / 12
                     ? std::numeric_limits<std::uint64_t>::max()
                     : kHeaderSize + payload_bytes(h.pixels(), h.crossing_count, h.footprint()),
                 std::to_string(h.width) + "x" + std::to_string(h.height) + " pixels, " +
                     std::to_string(h.crossing_count) + " crossings");
  return h;
}

TransportMap read_body(BinaryFileReader& in, const Header& h) {
  TransportMap map;
  map.width = h.width;
  map.height = h.height;
  map.samples_per_axis = h.samples_per_axis;
  map.stats.camera_rays = static_cast<long>(h.camera_rays);
  map.stats.branches_traced = static_cast<long>(h.branches_traced);
  map.stats.crossings = static_cast<long>(h.crossings);
  map.stats.pixels_without_solid_hit = static_cast<long>(h.pixels_without_solid_hit);
  map.stats.unproject_failures = static_cast<long>(h.unproject_failures);
  map.stats.closed_form_rays = static_cast<long>(h.closed_form_rays);
  map.stats.branches_cut_by_weight = static_cast<long>(h.branches_cut_by_weight);
  map.stats.branches_cut_by_depth = static_cast<long>(h.branches_cut_by_depth);
  map.stats.reflections_skipped = static_cast<long>(h.reflections_skipped);
  map.stats.cut_weight = h.cut_weight;
  map.stats.threads = h.threads;

  for_each_array(map, h.pixels(), h.crossing_count, h.footprint(),
                 [&](const char* name, auto& v, std::uint64_t n) { in.read_array(name, v, n); });
  in.expect_checksum(h.checksum);
  const std::string& path = in.path();
  if (const std::string p = offsets_problem(map.pixel_offsets, h.crossing_count, "pixel_offsets", "crossing count");
      !p.empty())
    throw InputError(path, "pixel_offsets", p);
  if (const std::string p = tag_problem(map.tag); !p.empty()) throw InputError(path, "tag", p);
  if (const auto [field, p] = values_problem(map); !field.empty()) throw InputError(path, field, p);
  return map;
}

}  // namespace

// ---------------------------------------------------------------- public API

std::uint64_t transport_map_fingerprint(const TraceScene& scene, const CameraModel& camera,
                                        const RigidTransform& camera_from_world, const TraceOptions& options,
                                        int samples_per_axis) {
  Fnv1a64 h;
  h.u32(kTransportMapTracerVersion);
  // Scene.
  h.f64(scene.fluid_index);
  h.vec3(scene.sheet.origin_mm);
  h.vec3(scene.sheet.s_axis);
  h.vec3(scene.sheet.t_axis);
  h.f64(scene.sheet.extent_s_mm);
  h.f64(scene.sheet.extent_t_mm);
  h.u64(scene.solids.size());
  for (const TraceSolid& solid : scene.solids) {
    h.u32(static_cast<std::uint32_t>(solid.shape.index()));
    std::visit(ShapeHasher{h}, solid.shape);
    h.u32(static_cast<std::uint32_t>(solid.material.kind));
    h.f64(solid.material.refractive_index);
    h.f64(solid.material.absorption_per_mm);
    h.f64(solid.material.albedo);
  }
  // Camera model: lens model, size, fx fy cx cy and all 14 distortion slots.
  h.i32(static_cast<std::int32_t>(camera.lens_model()));
  h.i32(camera.width_px());
  h.i32(camera.height_px());
  for (double v : camera.intrinsics()) h.f64(v);
  // Pose.
  h.mat3(camera_from_world.rotation);
  h.vec3(camera_from_world.translation_mm);
  // Options.
  h.boolean(options.reflections);
  h.f64(options.min_weight);
  // Only where it changes what is traced: maps made before the option existed
  // keep their fingerprint.
  if (options.min_weight_reflected > options.min_weight) h.f64(options.min_weight_reflected);
  if (reflection_grid_in_effect(options)) {
    h.i32(options.reflection_grid);
    h.f64(options.reflection_grid_tolerance);
    if (options.grid_whole_samples) h.boolean(true);
    if (options.reflection_grid_levels > 1) h.i32(options.reflection_grid_levels);
  }
  h.i32(options.max_depth);
  h.i32(samples_per_axis);
  return h.value();
}

std::string fingerprint_hex(std::uint64_t fingerprint) { return hex_u64(fingerprint); }

std::uint64_t transport_map_checksum(const void* data, std::size_t size) { return xxh64(data, size); }

void write_transport_map(const std::string& path, const TransportMap& map, std::uint64_t fingerprint) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("write_transport_map: " + what); };
  if (map.width <= 0 || map.height <= 0)
    bad("size " + std::to_string(map.width) + "x" + std::to_string(map.height) + " is not positive");
  if (map.samples_per_axis < 1) bad("samples_per_axis " + std::to_string(map.samples_per_axis) + " < 1");
  const std::uint64_t pixels = map.pixel_count();
  const std::uint64_t crossings = map.crossing_count();
  if (crossings > std::numeric_limits<std::uint32_t>::max()) bad("more crossings than pixel_offsets can index");
  const std::size_t jacobian_sizes[] = {map.ds_dcol.size(), map.ds_drow.size(), map.dt_dcol.size(),
                                        map.dt_drow.size()};
  bool footprint = true, no_footprint = true;
  for (std::size_t n : jacobian_sizes) {
    footprint = footprint && n == crossings;
    no_footprint = no_footprint && n == 0;
  }
  if (!footprint && !no_footprint) bad("the footprint Jacobian arrays must all hold one value per crossing, or all be empty");
  for_each_array(map, pixels, crossings, footprint, [&](const char* name, const auto& v, std::uint64_t n) {
    if (v.size() != n) bad(std::string(name) + " has " + std::to_string(v.size()) + " values, expected " + std::to_string(n));
  });
  if (std::string p = offsets_problem(map.pixel_offsets, crossings, "pixel_offsets", "crossing count"); !p.empty())
    bad("pixel_offsets: " + p);
  if (std::string p = tag_problem(map.tag); !p.empty()) bad("tag: " + p);
  if (const auto [field, p] = values_problem(map); !field.empty()) bad(field + ": " + p);

  Header h;
  h.version = kTransportMapFormatVersion;
  h.header_size = kHeaderSize;
  h.fingerprint = fingerprint;
  h.width = map.width;
  h.height = map.height;
  h.samples_per_axis = map.samples_per_axis;
  h.flags = footprint ? kFlagFootprint : 0;
  h.crossing_count = crossings;
  h.camera_rays = map.stats.camera_rays;
  h.branches_traced = map.stats.branches_traced;
  h.crossings = map.stats.crossings;
  h.pixels_without_solid_hit = map.stats.pixels_without_solid_hit;
  h.unproject_failures = map.stats.unproject_failures;
  h.closed_form_rays = map.stats.closed_form_rays;
  h.branches_cut_by_weight = map.stats.branches_cut_by_weight;
  h.branches_cut_by_depth = map.stats.branches_cut_by_depth;
  h.reflections_skipped = map.stats.reflections_skipped;
  h.cut_weight = map.stats.cut_weight;
  h.threads = map.stats.threads;
  Xxh64 checksum;
  for_each_array(map, pixels, crossings, footprint,
                 [&](const char*, const auto& v, std::uint64_t) { hash_array(checksum, v); });
  h.checksum = checksum.digest();
  const auto header = encode(h);

  write_binary_file_atomically(path, [&](BinaryFileWriter& out) {
    out.write(header.data(), header.size());
    for_each_array(map, pixels, crossings, footprint,
                   [&](const char*, const auto& v, std::uint64_t) { out.write_array(v); });
  });
}

TransportMap read_transport_map(const std::string& path, std::uint64_t* fingerprint) {
  BinaryFileReader in(path);
  const Header h = read_header(in);
  TransportMap map = read_body(in, h);
  if (fingerprint) *fingerprint = h.fingerprint;
  return map;
}

std::optional<TransportMap> load_cached_transport_map(const std::string& path, std::uint64_t fingerprint,
                                                      std::string* why) {
  return load_cached_binary_file(path, fingerprint, why, read_header, read_body);
}

}  // namespace glasspiv
