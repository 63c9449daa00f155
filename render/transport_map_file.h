#pragma once
// The transport map on disk (docs/transport_map_file.md): a versioned,
// little-endian binary file that loads in large blocks straight into the
// TransportMap's vectors, guarded by a payload checksum, and the 64-bit
// fingerprint of the inputs a map was traced from, so that a cached map is only
// reused for exactly the same setup.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "render/path_tracer.h"
#include "render/transport_map.h"

namespace glasspiv {

// Version of the tracer's results, hashed into every fingerprint. Bump it
// whenever build_transport_map (or trace_ray, the shapes, the optics under it)
// changes what it produces for the same inputs, so that maps cached by an
// older build are traced again instead of reused.
inline constexpr std::uint32_t kTransportMapTracerVersion = 2;

// Version of the file layout (header.version); bump it when the layout changes.
inline constexpr std::uint32_t kTransportMapFormatVersion = 1;

// 64-bit fingerprint of everything a map depends on: kTransportMapTracerVersion,
// the scene (fluid index, sheet, every solid's shape and material), the camera
// model (lens model, size, every intrinsic), the pose, every TraceOptions field
// and samples_per_axis. FNV-1a 64 over a canonical little-endian byte stream;
// doubles enter by their bit pattern (-0.0 as 0.0), so a change in the last bit
// of any input changes it. The thread count is not an input: the map is
// bit-identical for any thread count.
std::uint64_t transport_map_fingerprint(const TraceScene& scene, const CameraModel& camera,
                                        const RigidTransform& camera_from_world, const TraceOptions& options,
                                        int samples_per_axis);

// 16 lowercase hex digits.
std::string fingerprint_hex(std::uint64_t fingerprint);

// Writes `map` with `fingerprint` to `path` atomically (util/atomic_file.h): an
// existing file is only replaced by a complete one. Throws std::invalid_argument
// for an inconsistent map (array sizes, pixel_offsets, tag values) and InputError
// naming `path` when the file cannot be written.
void write_transport_map(const std::string& path, const TransportMap& map, std::uint64_t fingerprint);

// Reads a map written by write_transport_map; its fingerprint into *fingerprint
// if given. Validates everything (magic, version, header, sizes against the file
// length, checksum, pixel_offsets, tags) and throws a one-line
// InputError(path, field, problem) naming the first problem found.
TransportMap read_transport_map(const std::string& path, std::uint64_t* fingerprint = nullptr);

// The map in `path` if the file exists, reads cleanly and carries `fingerprint`;
// std::nullopt otherwise, with *why (if given) set to a one-line reason:
// "no file", "made for another setup (fingerprint <file's>, wanted <fingerprint>)"
// or "unreadable: <the read error>". A file made for another setup is rejected
// after reading its header only.
std::optional<TransportMap> load_cached_transport_map(const std::string& path, std::uint64_t fingerprint,
                                                      std::string* why = nullptr);

// The payload checksum of the file format: XXH64 (seed 0) of `size` bytes, the
// same value as `xxhsum -H64` prints. Exposed for tests and tools.
std::uint64_t transport_map_checksum(const void* data, std::size_t size);

}  // namespace glasspiv
