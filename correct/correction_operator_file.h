#pragma once
// The correction operator on disk (docs/correction_operator_file.md): the cache
// of build_correction_operator's result, modelled on the transport map file
// (render/transport_map_file.h) and sharing its machinery (util/binary_file.h):
// a versioned little-endian binary file of the operator's pixel-major arrays,
// loaded in large blocks straight into the vectors, guarded by an XXH64 payload
// checksum, and the 64-bit fingerprint of what the operator was built from (the
// transport map's fingerprint, the grid, the options), so that a cached
// operator is only reused for exactly the same setup. The arrays by cell are
// not stored: read_correction_operator derives them (finish_correction_operator).
#include <cstdint>
#include <optional>
#include <string>

#include "correct/correction_operator.h"
#include "correct/sheet_grid.h"

namespace glasspiv {

// Version of build_correction_operator's results, hashed into every
// fingerprint (and written into the header, for information). Bump it whenever
// build_correction_operator (the footprint taps, the splats, the order of the
// entries) changes what it produces for the same map, grid and options, so
// that operators cached by an older build are built again instead of reused.
inline constexpr std::uint32_t kCorrectionOperatorVersion = 2;  // 2: cell pixel counts per sample 1/k^2

// Version of the file layout (header.version); bump it when the layout changes.
inline constexpr std::uint32_t kCorrectionOperatorFormatVersion = 1;

// 64-bit fingerprint of everything an operator depends on:
// kCorrectionOperatorVersion, the fingerprint of the transport map it is built
// from (transport_map_fingerprint, which covers the scene, camera, pose and
// tracing), every SheetGrid field and every OperatorOptions field. FNV-1a 64
// (util/fnv1a64.h) over a canonical little-endian byte stream; doubles by their
// bit pattern (-0.0 as 0.0). The thread count is not an input.
std::uint64_t correction_operator_fingerprint(std::uint64_t transport_map_fingerprint, const SheetGrid& grid,
                                              const OperatorOptions& options);

// Writes the arrays of `op` that are not derived (pixel_offsets, cell, value,
// background_weight, cell_pixels, cell_direct_pixels) with `fingerprint` to
// `path` atomically
// (util/atomic_file.h): an existing file is only replaced by a complete one.
// Throws std::invalid_argument for an operator the reader would refuse (size or
// grid not positive or out of range, array sizes, pixel_offsets not starting at
// 0, decreasing or not ending at the entry count, a cell index outside the grid,
// a value, background weight or per-cell count not finite or negative) and
// InputError naming `path` when the file cannot be written.
void write_correction_operator(const std::string& path, const CorrectionOperator& op, std::uint64_t fingerprint);

// Reads an operator written by write_correction_operator, its fingerprint into
// *fingerprint if given, and derives the arrays by cell
// (finish_correction_operator). Validates everything (magic, versions, header,
// sizes against the file length before allocating, checksum, pixel_offsets,
// cell indices, finite non-negative values) and throws a one-line
// InputError(path, field, problem) naming the first problem found.
CorrectionOperator read_correction_operator(const std::string& path, std::uint64_t* fingerprint = nullptr);

// The operator in `path` if the file exists, reads cleanly and carries
// `fingerprint`; std::nullopt otherwise, with *why (if given) set to a one-line
// reason: "no file", "made for another setup (fingerprint <file's>, wanted
// <fingerprint>)" or "unreadable: <the read error>". A file made for another
// setup is rejected after reading its header only.
std::optional<CorrectionOperator> load_cached_correction_operator(const std::string& path, std::uint64_t fingerprint,
                                                                  std::string* why = nullptr);

}  // namespace glasspiv
