#include "correct/correction_operator_file.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "util/binary_file.h"
#include "util/fnv1a64.h"
#include "util/input_error.h"

namespace glasspiv {

namespace {

// ---------------------------------------------------------------- layout

constexpr char kMagic[8] = {'G', 'P', 'I', 'V', 'C', 'O', 'P', 'R'};
constexpr std::uint32_t kHeaderSize = 88;

struct Header {
  std::uint64_t fingerprint = 0;
  std::uint32_t operator_version = 0, reserved = 0;
  std::int32_t width = 0, height = 0;
  SheetGrid grid;
  std::uint64_t entry_count = 0;
  std::uint64_t checksum = 0;

  std::uint64_t pixels() const { return std::uint64_t(width) * std::uint64_t(height); }
};

// Byte offsets of the header fields (docs/correction_operator_file.md).
std::array<unsigned char, kHeaderSize> encode(const Header& h) {
  std::array<unsigned char, kHeaderSize> b{};
  std::memcpy(b.data(), kMagic, 8);
  put_field(b.data(), 8, kCorrectionOperatorFormatVersion);
  put_field(b.data(), 12, kHeaderSize);
  put_field(b.data(), 16, h.fingerprint);
  put_field(b.data(), 24, h.operator_version);
  put_field(b.data(), 28, h.reserved);
  put_field(b.data(), 32, h.width);
  put_field(b.data(), 36, h.height);
  put_field<std::int32_t>(b.data(), 40, h.grid.cols);
  put_field<std::int32_t>(b.data(), 44, h.grid.rows);
  put_field(b.data(), 48, h.grid.mm_per_px);
  put_field(b.data(), 56, h.grid.s0_mm);
  put_field(b.data(), 64, h.grid.t0_mm);
  put_field(b.data(), 72, h.entry_count);
  put_field(b.data(), 80, h.checksum);
  return b;
}

Header decode(const unsigned char* b) {
  Header h;
  h.fingerprint = get_field<std::uint64_t>(b, 16);
  h.operator_version = get_field<std::uint32_t>(b, 24);
  h.reserved = get_field<std::uint32_t>(b, 28);
  h.width = get_field<std::int32_t>(b, 32);
  h.height = get_field<std::int32_t>(b, 36);
  h.grid.cols = get_field<std::int32_t>(b, 40);
  h.grid.rows = get_field<std::int32_t>(b, 44);
  h.grid.mm_per_px = get_field<double>(b, 48);
  h.grid.s0_mm = get_field<double>(b, 56);
  h.grid.t0_mm = get_field<double>(b, 64);
  h.entry_count = get_field<std::uint64_t>(b, 72);
  h.checksum = get_field<std::uint64_t>(b, 80);
  return h;
}

// Calls f(name, vector, element count) for every stored array in file order.
// Op is CorrectionOperator or const CorrectionOperator.
template <typename Op, typename F>
void for_each_array(Op& op, std::uint64_t pixels, std::uint64_t entries, std::uint64_t cells, F&& f) {
  f("pixel_offsets", op.pixel_offsets, pixels + 1);
  f("cell", op.cell, entries);
  f("value", op.value, entries);
  f("background_weight", op.background_weight, pixels);
  f("cell_pixels", op.cell_pixels, cells);
  f("cell_direct_pixels", op.cell_direct_pixels, cells);
}

std::uint64_t payload_bytes(std::uint64_t pixels, std::uint64_t entries, std::uint64_t cells) {
  return padded8(4 * (pixels + 1)) + 2 * padded8(4 * entries) + padded8(4 * pixels) + 2 * padded8(4 * cells);
}

// ---------------------------------------------------------------- checks
// Shared by writer and reader, so that the writer never writes a file the
// reader refuses: the first problem as (field, problem), field "" for none.

struct Problem {
  std::string field, what;
  explicit operator bool() const { return !field.empty(); }
};

std::string number(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%.17g", v);
  return s;
}

bool finite(double v) { return std::isfinite(v); }

// Header fields (without the "header." the reader's field names carry).
Problem header_problem(const Header& h) {
  auto is = [](auto v) { return "is " + std::to_string(v); };
  if (h.operator_version < 1) return {"operator_version", is(h.operator_version) + ", must be >= 1"};
  if (h.reserved != 0) return {"reserved", is(h.reserved) + ", must be 0"};
  if (h.width <= 0) return {"width", is(h.width) + ", must be positive"};
  if (h.height <= 0) return {"height", is(h.height) + ", must be positive"};
  if (h.grid.cols <= 0) return {"grid.cols", is(h.grid.cols) + ", must be positive"};
  if (h.grid.rows <= 0) return {"grid.rows", is(h.grid.rows) + ", must be positive"};
  if (h.grid.cell_count() > kMaxSheetGridCells)
    return {"grid", "has " + std::to_string(h.grid.cols) + "x" + std::to_string(h.grid.rows) +
                        " cells, more than the " + std::to_string(kMaxSheetGridCells) + " a grid may have"};
  if (!(finite(h.grid.mm_per_px) && h.grid.mm_per_px > 0))
    return {"grid.mm_per_px", "is " + number(h.grid.mm_per_px) + ", must be finite and positive"};
  if (!finite(h.grid.s0_mm)) return {"grid.s0_mm", "is " + number(h.grid.s0_mm) + ", must be finite"};
  if (!finite(h.grid.t0_mm)) return {"grid.t0_mm", "is " + number(h.grid.t0_mm) + ", must be finite"};
  if (h.entry_count > std::numeric_limits<std::uint32_t>::max())
    return {"entry_count", is(h.entry_count) + ", more than pixel_offsets (u32) can index"};
  return {};
}

// The stored arrays, their sizes already right.
Problem arrays_problem(const CorrectionOperator& op) {
  if (std::string p = offsets_problem(op.pixel_offsets, op.value.size(), "pixel_offsets", "entry count");
      !p.empty())
    return {"pixel_offsets", p};
  const std::size_t cells = op.grid.cell_count();
  for (std::size_t i = 0; i < op.cell.size(); ++i)
    if (op.cell[i] >= cells)
      return {"cell", "cell[" + std::to_string(i) + "] is " + std::to_string(op.cell[i]) + ", the grid has " +
                          std::to_string(cells) + " cells (" + std::to_string(op.grid.cols) + "x" +
                          std::to_string(op.grid.rows) + ")"};
  const std::pair<const char*, const std::vector<float>*> weights[] = {
      {"value", &op.value},
      {"background_weight", &op.background_weight},
      {"cell_pixels", &op.cell_pixels},
      {"cell_direct_pixels", &op.cell_direct_pixels}};
  for (const auto& [name, v] : weights)
    for (std::size_t i = 0; i < v->size(); ++i)
      if (!(finite((*v)[i]) && (*v)[i] >= 0))
        return {name, std::string(name) + "[" + std::to_string(i) + "] is " + number((*v)[i]) +
                          ", must be finite and not negative"};
  return {};
}

Header header_of(const CorrectionOperator& op, std::uint64_t fingerprint) {
  Header h;
  h.fingerprint = fingerprint;
  h.operator_version = kCorrectionOperatorVersion;
  h.width = op.width;
  h.height = op.height;
  h.grid = op.grid;
  h.entry_count = op.value.size();
  return h;
}

// ---------------------------------------------------------------- reading

Header read_header(BinaryFileReader& in) {
  unsigned char b[kHeaderSize];
  in.read_header(kMagic, "correction operator", kCorrectionOperatorFormatVersion, b, kHeaderSize);
  const Header h = decode(b);
  if (const Problem p = header_problem(h)) throw InputError(in.path(), "header." + p.field, p.what);
  // Every pixel takes at least 8 bytes, so this bound keeps the sums below from overflowing.
  in.expect_size(h.pixels() > in.size() / 8
                     ? std::numeric_limits<std::uint64_t>::max()
                     : kHeaderSize + payload_bytes(h.pixels(), h.entry_count, h.grid.cell_count()),
                 std::to_string(h.width) + "x" + std::to_string(h.height) + " pixels, " +
                     std::to_string(h.entry_count) + " entries, " + std::to_string(h.grid.cols) + "x" +
                     std::to_string(h.grid.rows) + " cells");
  return h;
}

CorrectionOperator read_body(BinaryFileReader& in, const Header& h) {
  CorrectionOperator op;
  op.width = h.width;
  op.height = h.height;
  op.grid = h.grid;
  for_each_array(op, h.pixels(), h.entry_count, h.grid.cell_count(),
                 [&](const char* name, auto& v, std::uint64_t n) { in.read_array(name, v, n); });
  in.expect_checksum(h.checksum);
  if (const Problem p = arrays_problem(op)) throw InputError(in.path(), p.field, p.what);
  finish_correction_operator(op);
  return op;
}

}  // namespace

// ---------------------------------------------------------------- public API

std::uint64_t correction_operator_fingerprint(std::uint64_t transport_map_fingerprint, const SheetGrid& grid,
                                              const OperatorOptions& options) {
  Fnv1a64 h;
  h.u32(kCorrectionOperatorVersion);
  h.u64(transport_map_fingerprint);
  h.i32(grid.cols);
  h.i32(grid.rows);
  h.f64(grid.mm_per_px);
  h.f64(grid.s0_mm);
  h.f64(grid.t0_mm);
  h.boolean(options.footprint_filter);
  h.i32(options.max_taps_per_axis);
  h.boolean(options.taps_by_weight);
  return h.value();
}

void write_correction_operator(const std::string& path, const CorrectionOperator& op, std::uint64_t fingerprint) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("write_correction_operator: " + what); };
  Header h = header_of(op, fingerprint);
  if (const Problem p = header_problem(h)) bad(p.field + " " + p.what);
  const std::uint64_t pixels = h.pixels(), entries = h.entry_count, cells = h.grid.cell_count();
  for_each_array(op, pixels, entries, cells, [&](const char* name, const auto& v, std::uint64_t n) {
    if (v.size() != n)
      bad(std::string(name) + " has " + std::to_string(v.size()) + " values, expected " + std::to_string(n));
  });
  if (const Problem p = arrays_problem(op)) bad(p.field + ": " + p.what);

  Xxh64 checksum;
  for_each_array(op, pixels, entries, cells,
                 [&](const char*, const auto& v, std::uint64_t) { hash_array(checksum, v); });
  h.checksum = checksum.digest();
  const auto header = encode(h);
  write_binary_file_atomically(path, [&](BinaryFileWriter& out) {
    out.write(header.data(), header.size());
    for_each_array(op, pixels, entries, cells, [&](const char*, const auto& v, std::uint64_t) { out.write_array(v); });
  });
}

CorrectionOperator read_correction_operator(const std::string& path, std::uint64_t* fingerprint) {
  BinaryFileReader in(path);
  const Header h = read_header(in);
  CorrectionOperator op = read_body(in, h);
  if (fingerprint) *fingerprint = h.fingerprint;
  return op;
}

std::optional<CorrectionOperator> load_cached_correction_operator(const std::string& path, std::uint64_t fingerprint,
                                                                  std::string* why) {
  return load_cached_binary_file(path, fingerprint, why, read_header, read_body);
}

}  // namespace glasspiv
