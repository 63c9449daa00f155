#include "render/transport_map_file.h"

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <variant>

#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {

// The file is written and read by copying memory: it needs a little-endian host
// with IEEE 754 floats.
#if !defined(__BYTE_ORDER__) || !defined(__ORDER_LITTLE_ENDIAN__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
static_assert(false,
              "render/transport_map_file.cpp: the transport map file is little-endian and is read by copying "
              "memory; this host is not (known) little-endian");
#endif
static_assert(std::numeric_limits<float>::is_iec559 && sizeof(float) == 4, "IEEE 754 binary32 floats required");
static_assert(std::numeric_limits<double>::is_iec559 && sizeof(double) == 8, "IEEE 754 binary64 doubles required");

namespace {

// ---------------------------------------------------------------- fingerprint

// FNV-1a 64 over a canonical little-endian byte stream.
class Fnv1a64 {
 public:
  void bytes(const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
      h_ ^= p[i];
      h_ *= 1099511628211ull;
    }
  }
  void u64(std::uint64_t v) {
    unsigned char b[8];
    for (int i = 0; i < 8; ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
    bytes(b, 8);
  }
  void u32(std::uint32_t v) {
    unsigned char b[4];
    for (int i = 0; i < 4; ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
    bytes(b, 4);
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void boolean(bool v) { u32(v ? 1u : 0u); }
  // By bit pattern; -0.0 == 0.0 as inputs, so it hashes as 0.0.
  void f64(double v) {
    if (v == 0) v = 0;
    std::uint64_t bits;
    std::memcpy(&bits, &v, 8);
    u64(bits);
  }
  void vec3(const Eigen::Vector3d& v) {
    for (int i = 0; i < 3; ++i) f64(v[i]);
  }
  void mat3(const Eigen::Matrix3d& m) {  // row-major
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) f64(m(r, c));
  }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 14695981039346656037ull;
};

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

// ---------------------------------------------------------------- checksum

// XXH64 (xxHash, 64-bit, by Yann Collet; specification in xxHash's
// doc/xxhash_spec.md), streaming, seed 0.
class Xxh64 {
 public:
  void update(const void* data, std::size_t size) {
    if (size == 0) return;  // data may be null (an empty vector's)
    const auto* p = static_cast<const unsigned char*>(data);
    total_ += size;
    if (buffered_ + size < 32) {
      std::memcpy(buffer_ + buffered_, p, size);
      buffered_ += size;
      return;
    }
    if (buffered_ > 0) {
      const std::size_t fill = 32 - buffered_;
      std::memcpy(buffer_ + buffered_, p, fill);
      stripe(buffer_);
      p += fill;
      size -= fill;
      buffered_ = 0;
    }
    // Four independent lanes per 32-byte stripe.
    std::uint64_t v0 = v_[0], v1 = v_[1], v2 = v_[2], v3 = v_[3];
    while (size >= 32) {
      v0 = round(v0, read64(p));
      v1 = round(v1, read64(p + 8));
      v2 = round(v2, read64(p + 16));
      v3 = round(v3, read64(p + 24));
      p += 32;
      size -= 32;
    }
    v_[0] = v0, v_[1] = v1, v_[2] = v2, v_[3] = v3;
    std::memcpy(buffer_, p, size);
    buffered_ = size;
  }

  std::uint64_t digest() const {
    std::uint64_t h;
    if (total_ >= 32) {
      h = rotl(v_[0], 1) + rotl(v_[1], 7) + rotl(v_[2], 12) + rotl(v_[3], 18);
      for (std::uint64_t v : v_) h = merge(h, v);
    } else {
      h = kP5;
    }
    h += total_;
    const unsigned char* p = buffer_;
    const unsigned char* end = buffer_ + buffered_;
    for (; p + 8 <= end; p += 8) h = rotl(h ^ round(0, read64(p)), 27) * kP1 + kP4;
    if (p + 4 <= end) {
      std::uint32_t w;
      std::memcpy(&w, p, 4);
      h = rotl(h ^ (std::uint64_t{w} * kP1), 23) * kP2 + kP3;
      p += 4;
    }
    for (; p < end; ++p) h = rotl(h ^ (std::uint64_t{*p} * kP5), 11) * kP1;
    h ^= h >> 33;
    h *= kP2;
    h ^= h >> 29;
    h *= kP3;
    h ^= h >> 32;
    return h;
  }

 private:
  static constexpr std::uint64_t kP1 = 0x9E3779B185EBCA87ull, kP2 = 0xC2B2AE3D27D4EB4Full,
                                 kP3 = 0x165667B19E3779F9ull, kP4 = 0x85EBCA77C2B2AE63ull,
                                 kP5 = 0x27D4EB2F165667C5ull;
  static std::uint64_t rotl(std::uint64_t x, int r) { return (x << r) | (x >> (64 - r)); }
  static std::uint64_t read64(const unsigned char* p) {
    std::uint64_t v;
    std::memcpy(&v, p, 8);
    return v;
  }
  static std::uint64_t round(std::uint64_t acc, std::uint64_t input) { return rotl(acc + input * kP2, 31) * kP1; }
  static std::uint64_t merge(std::uint64_t h, std::uint64_t v) { return (h ^ round(0, v)) * kP1 + kP4; }
  void stripe(const unsigned char* p) {
    for (int i = 0; i < 4; ++i) v_[i] = round(v_[i], read64(p + 8 * i));
  }

  std::uint64_t v_[4] = {kP1 + kP2, kP2, 0, 0 - kP1};
  unsigned char buffer_[32] = {};
  std::size_t buffered_ = 0;
  std::uint64_t total_ = 0;
};

// ---------------------------------------------------------------- layout

constexpr char kMagic[8] = {'G', 'P', 'I', 'V', 'T', 'M', 'A', 'P'};
constexpr std::uint32_t kHeaderSize = 144;
constexpr std::uint32_t kFlagFootprint = 1u;  // the four footprint Jacobian arrays are present
constexpr int kCrossingTagCount = 3;
static_assert(static_cast<int>(CrossingTag::direct) == 0 && static_cast<int>(CrossingTag::refracted_only) == 1 &&
                  static_cast<int>(CrossingTag::with_reflections) == kCrossingTagCount - 1,
              "CrossingTag changed: update the tag check and docs/transport_map_file.md");

constexpr unsigned char kZeros[8] = {};  // padding

constexpr std::size_t padded8(std::size_t bytes) { return (bytes + 7) & ~std::size_t{7}; }

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
template <typename T>
void put(unsigned char* b, std::size_t at, T v) {
  std::memcpy(b + at, &v, sizeof v);
}
template <typename T>
T get(const unsigned char* b, std::size_t at) {
  T v;
  std::memcpy(&v, b + at, sizeof v);
  return v;
}

std::array<unsigned char, kHeaderSize> encode(const Header& h) {
  std::array<unsigned char, kHeaderSize> b{};
  std::memcpy(b.data(), kMagic, 8);
  put(b.data(), 8, h.version);
  put(b.data(), 12, h.header_size);
  put(b.data(), 16, h.fingerprint);
  put(b.data(), 24, h.width);
  put(b.data(), 28, h.height);
  put(b.data(), 32, h.samples_per_axis);
  put(b.data(), 36, h.flags);
  put(b.data(), 40, h.crossing_count);
  put(b.data(), 48, h.camera_rays);
  put(b.data(), 56, h.branches_traced);
  put(b.data(), 64, h.crossings);
  put(b.data(), 72, h.pixels_without_solid_hit);
  put(b.data(), 80, h.unproject_failures);
  put(b.data(), 88, h.closed_form_rays);
  put(b.data(), 96, h.branches_cut_by_weight);
  put(b.data(), 104, h.branches_cut_by_depth);
  put(b.data(), 112, h.reflections_skipped);
  put(b.data(), 120, h.cut_weight);
  put(b.data(), 128, h.threads);
  put(b.data(), 132, h.reserved);
  put(b.data(), 136, h.checksum);
  return b;
}

Header decode(const unsigned char* b) {
  Header h;
  h.version = get<std::uint32_t>(b, 8);
  h.header_size = get<std::uint32_t>(b, 12);
  h.fingerprint = get<std::uint64_t>(b, 16);
  h.width = get<std::int32_t>(b, 24);
  h.height = get<std::int32_t>(b, 28);
  h.samples_per_axis = get<std::int32_t>(b, 32);
  h.flags = get<std::uint32_t>(b, 36);
  h.crossing_count = get<std::uint64_t>(b, 40);
  h.camera_rays = get<std::int64_t>(b, 48);
  h.branches_traced = get<std::int64_t>(b, 56);
  h.crossings = get<std::int64_t>(b, 64);
  h.pixels_without_solid_hit = get<std::int64_t>(b, 72);
  h.unproject_failures = get<std::int64_t>(b, 80);
  h.closed_form_rays = get<std::int64_t>(b, 88);
  h.branches_cut_by_weight = get<std::int64_t>(b, 96);
  h.branches_cut_by_depth = get<std::int64_t>(b, 104);
  h.reflections_skipped = get<std::int64_t>(b, 112);
  h.cut_weight = get<double>(b, 120);
  h.threads = get<std::int32_t>(b, 128);
  h.reserved = get<std::uint32_t>(b, 132);
  h.checksum = get<std::uint64_t>(b, 136);
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

// The first problem of pixel_offsets / tag, or "" (shared by writer and reader).
std::string offsets_problem(const std::vector<std::uint32_t>& offsets, std::uint64_t crossings) {
  if (offsets.front() != 0) return "pixel_offsets[0] is " + std::to_string(offsets.front()) + ", expected 0";
  for (std::size_t i = 1; i < offsets.size(); ++i)
    if (offsets[i] < offsets[i - 1])
      return "pixel_offsets[" + std::to_string(i) + "] = " + std::to_string(offsets[i]) + " is less than pixel_offsets[" +
             std::to_string(i - 1) + "] = " + std::to_string(offsets[i - 1]) + " (must not decrease)";
  if (offsets.back() != crossings)
    return "the last entry is " + std::to_string(offsets.back()) + ", expected the crossing count " +
           std::to_string(crossings);
  return "";
}

std::string tag_problem(const std::vector<std::uint8_t>& tag) {
  for (std::size_t i = 0; i < tag.size(); ++i)
    if (tag[i] >= kCrossingTagCount)
      return "tag[" + std::to_string(i) + "] is " + std::to_string(tag[i]) +
             ", expected 0 (direct), 1 (refracted_only) or 2 (with_reflections)";
  return "";
}

std::string hex(std::uint64_t v) { return fingerprint_hex(v); }

// ---------------------------------------------------------------- reading

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

struct OpenFile {
  File file;
  std::uint64_t size = 0;
};

OpenFile open_for_reading(const std::string& path) {
  OpenFile of;
  of.file.reset(std::fopen(path.c_str(), "rb"));
  if (!of.file) {
    if (errno == ENOENT) throw InputError(path, "", "file does not exist");
    throw InputError(path, "", std::string("cannot open: ") + std::strerror(errno));
  }
  struct stat st {};
  if (::fstat(::fileno(of.file.get()), &st) != 0)
    throw InputError(path, "", std::string("cannot read: ") + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw InputError(path, "", "is not a regular file");
  of.size = static_cast<std::uint64_t>(st.st_size);
  return of;
}

Header read_header(const OpenFile& of, const std::string& path) {
  unsigned char b[kHeaderSize];
  const std::size_t got = std::fread(b, 1, kHeaderSize, of.file.get());
  if (got < 8 || std::memcmp(b, kMagic, 8) != 0)
    throw InputError(path, "magic", "not a transport map file (it does not start with \"GPIVTMAP\")");
  if (got < 16) throw InputError(path, "header", "file ends inside the header (" + std::to_string(got) + " bytes)");
  const std::uint32_t version = get<std::uint32_t>(b, 8);
  if (version != kTransportMapFormatVersion)
    throw InputError(path, "header.version",
                     "format version " + std::to_string(version) + ", this build reads version " +
                         std::to_string(kTransportMapFormatVersion));
  const std::uint32_t header_size = get<std::uint32_t>(b, 12);
  if (header_size != kHeaderSize)
    throw InputError(path, "header.header_size",
                     "is " + std::to_string(header_size) + ", version 1 has " + std::to_string(kHeaderSize));
  if (got < kHeaderSize)
    throw InputError(path, "header", "file ends inside the header (" + std::to_string(got) + " of " +
                                         std::to_string(kHeaderSize) + " bytes)");
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
  const std::uint64_t expected = h.pixels() > of.size / 12
                                     ? std::numeric_limits<std::uint64_t>::max()
                                     : kHeaderSize + payload_bytes(h.pixels(), h.crossing_count, h.footprint());
  if (of.size != expected)
    throw InputError(path, "payload",
                     "file is " + std::to_string(of.size) + " bytes, the header (" + std::to_string(h.width) + "x" +
                         std::to_string(h.height) + " pixels, " + std::to_string(h.crossing_count) +
                         " crossings) needs " +
                         (expected == std::numeric_limits<std::uint64_t>::max() ? std::string("far more")
                                                                                : std::to_string(expected)) +
                         (of.size < expected ? ": truncated" : ": trailing bytes"));
  return h;
}

TransportMap read_body(const OpenFile& of, const std::string& path, const Header& h) {
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

  Xxh64 checksum;
  // Large blocks straight into the vectors, each hashed while still in cache.
  constexpr std::size_t kChunk = std::size_t{4} << 20;
  for_each_array(map, h.pixels(), h.crossing_count, h.footprint(), [&](const char* name, auto& v, std::uint64_t n) {
    v.resize(static_cast<std::size_t>(n));
    const std::size_t bytes = v.size() * sizeof(v[0]);
    auto* p = reinterpret_cast<unsigned char*>(v.data());
    for (std::size_t done = 0; done < bytes;) {
      const std::size_t want = std::min(kChunk, bytes - done);
      if (std::fread(p + done, 1, want, of.file.get()) != want)
        throw InputError(path, name, "file ended early (changed while being read?)");
      checksum.update(p + done, want);
      done += want;
    }
    unsigned char pad[8] = {};
    const std::size_t pad_bytes = padded8(bytes) - bytes;
    if (std::fread(pad, 1, pad_bytes, of.file.get()) != pad_bytes)
      throw InputError(path, name, "file ended early (changed while being read?)");
    checksum.update(pad, pad_bytes);
  });
  const std::uint64_t actual = checksum.digest();
  if (actual != h.checksum)
    throw InputError(path, "header.checksum",
                     "the payload's checksum is " + hex(actual) + ", the header says " + hex(h.checksum) +
                         ": the file is damaged");
  if (const std::string p = offsets_problem(map.pixel_offsets, h.crossing_count); !p.empty())
    throw InputError(path, "pixel_offsets", p);
  if (const std::string p = tag_problem(map.tag); !p.empty()) throw InputError(path, "tag", p);
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
  h.i32(options.max_depth);
  h.i32(samples_per_axis);
  return h.value();
}

std::string fingerprint_hex(std::uint64_t fingerprint) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(fingerprint));
  return s;
}

std::uint64_t transport_map_checksum(const void* data, std::size_t size) {
  Xxh64 x;
  x.update(data, size);
  return x.digest();
}

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
  if (std::string p = offsets_problem(map.pixel_offsets, crossings); !p.empty()) bad("pixel_offsets: " + p);
  if (std::string p = tag_problem(map.tag); !p.empty()) bad("tag: " + p);

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
  for_each_array(map, pixels, crossings, footprint, [&](const char*, const auto& v, std::uint64_t) {
    const std::size_t bytes = v.size() * sizeof(v[0]);
    checksum.update(v.data(), bytes);
    checksum.update(kZeros, padded8(bytes) - bytes);
  });
  h.checksum = checksum.digest();
  const auto header = encode(h);

  // Straight from the vectors into the temporary file, renamed over `path` when complete.
  write_file_atomically_with(path, [&](const std::string& temporary) {
    File f(std::fopen(temporary.c_str(), "wb"));
    if (!f) throw InputError(path, "", std::string("cannot open for writing: ") + std::strerror(errno));
    auto write = [&](const void* data, std::size_t bytes) {
      if (bytes > 0 && std::fwrite(data, 1, bytes, f.get()) != bytes)
        throw InputError(path, "", std::string("write failed: ") + std::strerror(errno));
    };
    write(header.data(), header.size());
    for_each_array(map, pixels, crossings, footprint, [&](const char*, const auto& v, std::uint64_t) {
      const std::size_t bytes = v.size() * sizeof(v[0]);
      write(v.data(), bytes);
      write(kZeros, padded8(bytes) - bytes);
    });
    if (std::fflush(f.get()) != 0) throw InputError(path, "", std::string("write failed: ") + std::strerror(errno));
    if (std::fclose(f.release()) != 0)
      throw InputError(path, "", std::string("write failed: ") + std::strerror(errno));
  });
}

TransportMap read_transport_map(const std::string& path, std::uint64_t* fingerprint) {
  const OpenFile of = open_for_reading(path);
  const Header h = read_header(of, path);
  TransportMap map = read_body(of, path, h);
  if (fingerprint) *fingerprint = h.fingerprint;
  return map;
}

std::optional<TransportMap> load_cached_transport_map(const std::string& path, std::uint64_t fingerprint,
                                                      std::string* why) {
  auto fail = [&](std::string reason) -> std::optional<TransportMap> {
    if (why) *why = std::move(reason);
    return std::nullopt;
  };
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return fail("no file");
  try {
    const OpenFile of = open_for_reading(path);
    const Header h = read_header(of, path);
    if (h.fingerprint != fingerprint)
      return fail("made for another setup (fingerprint " + hex(h.fingerprint) + ", wanted " + hex(fingerprint) + ")");
    TransportMap map = read_body(of, path, h);
    if (why) why->clear();
    return map;
  } catch (const InputError& e) {
    return fail(std::string("unreadable: ") + e.what());
  }
}

}  // namespace glasspiv
