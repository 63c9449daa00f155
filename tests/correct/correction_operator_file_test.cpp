// Correction operator file and cache key: bit-exact round trip of a hand-built
// operator (the arrays by cell derived again on reading), the documented
// layout, the fingerprint's byte stream and its sensitivity to every input, the
// writer's refusals, one-line read errors naming the path and the field
// (forged NaN / out-of-range files with a valid checksum included), the cache
// lookup's reasons, atomic writes.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <climits>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <unistd.h>

#include "tests/temp_dir.h"
#include "correct/correction_operator_file.h"
#include "render/transport_map_file.h"
#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

// The layout of docs/correction_operator_file.md, written out independently of the implementation.
constexpr std::size_t kHeaderBytes = 88;
std::size_t pad8(std::size_t bytes) { return (bytes + 7) / 8 * 8; }

struct Offsets {
  std::size_t pixel_offsets, cell, value, background_weight, cell_pixels, cell_direct_pixels, end;
};
Offsets offsets_of(std::size_t pixels, std::size_t entries, std::size_t cells) {
  Offsets o;
  o.pixel_offsets = kHeaderBytes;
  o.cell = o.pixel_offsets + pad8(4 * (pixels + 1));
  o.value = o.cell + pad8(4 * entries);
  o.background_weight = o.value + pad8(4 * entries);
  o.cell_pixels = o.background_weight + pad8(4 * pixels);
  o.cell_direct_pixels = o.cell_pixels + pad8(4 * cells);
  o.end = o.cell_direct_pixels + pad8(4 * cells);
  return o;
}
Offsets offsets_of(const CorrectionOperator& op) {
  return offsets_of(op.pixel_count(), op.entry_count(), op.grid.cell_count());
}


// After patching the payload: a valid checksum again, so that the later checks are reached.
void reseal(std::string& bytes) {
  poke(bytes, 80, transport_map_checksum(bytes.data() + kHeaderBytes, bytes.size() - kHeaderBytes));
}

// ------------------------------------------------------------------ operators

SheetGrid small_grid() {
  SheetGrid g;
  g.cols = 5;
  g.rows = 4;
  g.mm_per_px = 0.25;
  g.s0_mm = -1.125;
  g.t0_mm = 0.75;
  return g;
}

// 4x3 pixels on a 5x4 grid, filled by hand: pixels without entries, a cell no
// pixel sees (19), an odd entry count (every array but pixel_offsets padded),
// and values whose bits must survive (-0.0, a denormal, 0, 1).
CorrectionOperator small_operator() {
  CorrectionOperator op;
  op.width = 4;
  op.height = 3;
  op.grid = small_grid();
  const int counts[12] = {2, 0, 3, 1, 4, 2, 1, 0, 3, 2, 1, 2};  // 21 entries
  op.pixel_offsets = {0};
  for (int p = 0; p < 12; ++p) {
    for (int k = 0; k < counts[p]; ++k) {
      op.cell.push_back(static_cast<std::uint32_t>((p * 7 + k * 3) % 19));
      op.value.push_back(0.1f * static_cast<float>(p + 1) + 0.0137f * static_cast<float>(k));
    }
    op.pixel_offsets.push_back(static_cast<std::uint32_t>(op.cell.size()));
  }
  op.value[1] = -0.0f;
  op.value[4] = std::numeric_limits<float>::denorm_min();
  op.value[7] = 0.0f;
  op.value[20] = 1.0f;
  for (int p = 0; p < 12; ++p) op.background_weight.push_back(p == 0 ? 0.0f : 1.0f / static_cast<float>(p + 2));
  for (int c = 0; c < 20; ++c) {
    op.cell_pixels.push_back(c == 19 ? 0.0f : 0.03125f * static_cast<float>(c + 1));
    op.cell_direct_pixels.push_back(c % 3 == 0 ? 0.0f : 0.0078125f * static_cast<float>(c + 1));
  }
  finish_correction_operator(op);
  return op;
}

// Larger (a few kB), for the failed-write test.
CorrectionOperator bigger_operator() {
  CorrectionOperator op;
  op.width = 40;
  op.height = 30;
  op.grid.cols = 20;
  op.grid.rows = 20;
  op.grid.mm_per_px = 0.5;
  op.pixel_offsets = {0};
  for (std::size_t p = 0; p < op.pixel_count(); ++p) {
    for (std::size_t k = 0; k < 3; ++k) {
      op.cell.push_back(static_cast<std::uint32_t>((p * 13 + k) % op.grid.cell_count()));
      op.value.push_back(0.25f + 0.001f * static_cast<float>(k));
    }
    op.pixel_offsets.push_back(static_cast<std::uint32_t>(op.cell.size()));
  }
  op.background_weight.assign(op.pixel_count(), 0.25f);
  op.cell_pixels.assign(op.grid.cell_count(), 1.5f);
  op.cell_direct_pixels.assign(op.grid.cell_count(), 0.75f);
  finish_correction_operator(op);
  return op;
}

template <typename T>
void expect_same_bits(const std::vector<T>& a, const std::vector<T>& b, const char* name) {
  ASSERT_EQ(a.size(), b.size()) << name;
  EXPECT_TRUE(a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0) << name << " differs";
}

void expect_identical(const CorrectionOperator& a, const CorrectionOperator& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_TRUE(a.grid == b.grid);
  expect_same_bits(a.pixel_offsets, b.pixel_offsets, "pixel_offsets");
  expect_same_bits(a.cell, b.cell, "cell");
  expect_same_bits(a.value, b.value, "value");
  expect_same_bits(a.background_weight, b.background_weight, "background_weight");
  expect_same_bits(a.cell_pixels, b.cell_pixels, "cell_pixels");
  expect_same_bits(a.cell_direct_pixels, b.cell_direct_pixels, "cell_direct_pixels");
  expect_same_bits(a.cell_weight, b.cell_weight, "cell_weight");
  expect_same_bits(a.cell_offsets, b.cell_offsets, "cell_offsets");
  expect_same_bits(a.entry_pixel, b.entry_pixel, "entry_pixel");
  expect_same_bits(a.value_by_cell, b.value_by_cell, "value_by_cell");
}

// ------------------------------------------------------------------ round trip

TEST(CorrectionOperatorFile, RoundTripIsBitIdenticalAndFollowsTheDocumentedLayout) {
  TempDir dir("glasspiv_cof");
  const CorrectionOperator op = small_operator();
  ASSERT_EQ(op.entry_count(), 21u);
  ASSERT_EQ(op.cell_offsets.size(), 21u);  // derived by finish_correction_operator
  const std::string path = dir.file("cam0.cop");
  const std::uint64_t fp = 0x0123456789abcdefull;
  write_correction_operator(path, op, fp);

  std::uint64_t read_fp = 0;
  const CorrectionOperator back = read_correction_operator(path, &read_fp);
  EXPECT_EQ(read_fp, fp);
  expect_identical(op, back);
  EXPECT_TRUE(std::signbit(back.value[1]));
  EXPECT_EQ(back.value[4], std::numeric_limits<float>::denorm_min());
  // The arrays by cell are derived on reading, not stored: they are there all the same.
  EXPECT_EQ(back.cell_offsets.size(), op.grid.cell_count() + 1);
  EXPECT_EQ(back.entry_pixel.size(), op.entry_count());

  const std::string bytes = read_file(path);
  const Offsets o = offsets_of(op);
  ASSERT_EQ(bytes.size(), o.end);
  EXPECT_EQ(bytes.compare(0, 8, "GPIVCOPR"), 0);
  EXPECT_EQ(peek<std::uint32_t>(bytes, 8), kCorrectionOperatorFormatVersion);
  EXPECT_EQ(peek<std::uint32_t>(bytes, 12), kHeaderBytes);
  EXPECT_EQ(peek<std::uint64_t>(bytes, 16), fp);
  EXPECT_EQ(peek<std::uint32_t>(bytes, 24), kCorrectionOperatorVersion);
  EXPECT_EQ(peek<std::uint32_t>(bytes, 28), 0u);
  EXPECT_EQ(peek<std::int32_t>(bytes, 32), 4);
  EXPECT_EQ(peek<std::int32_t>(bytes, 36), 3);
  EXPECT_EQ(peek<std::int32_t>(bytes, 40), 5);
  EXPECT_EQ(peek<std::int32_t>(bytes, 44), 4);
  EXPECT_EQ(peek<double>(bytes, 48), 0.25);
  EXPECT_EQ(peek<double>(bytes, 56), -1.125);
  EXPECT_EQ(peek<double>(bytes, 64), 0.75);
  EXPECT_EQ(peek<std::uint64_t>(bytes, 72), 21u);
  EXPECT_EQ(peek<std::uint64_t>(bytes, 80), transport_map_checksum(bytes.data() + kHeaderBytes, bytes.size() - kHeaderBytes));
  EXPECT_EQ(std::memcmp(bytes.data() + o.pixel_offsets, op.pixel_offsets.data(), 4 * 13), 0);
  EXPECT_EQ(std::memcmp(bytes.data() + o.cell, op.cell.data(), 4 * 21), 0);
  EXPECT_EQ(std::memcmp(bytes.data() + o.value, op.value.data(), 4 * 21), 0);
  EXPECT_EQ(std::memcmp(bytes.data() + o.background_weight, op.background_weight.data(), 4 * 12), 0);
  EXPECT_EQ(std::memcmp(bytes.data() + o.cell_pixels, op.cell_pixels.data(), 4 * 20), 0);
  EXPECT_EQ(std::memcmp(bytes.data() + o.cell_direct_pixels, op.cell_direct_pixels.data(), 4 * 20), 0);
  // Padding is zero bytes (after pixel_offsets, cell and value: 52, 84, 84 bytes).
  for (std::size_t at : {o.pixel_offsets + 52, o.cell + 84, o.value + 84})
    EXPECT_EQ(bytes.substr(at, 4), std::string(4, '\0')) << at;

  // Writing the same operator again gives the same bytes, and no temporary is left behind.
  write_correction_operator(path, op, fp);
  EXPECT_EQ(read_file(path), bytes);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"cam0.cop"});
}

TEST(CorrectionOperatorFile, RoundTripOfOnePixelWithoutEntries) {
  TempDir dir("glasspiv_cof");
  CorrectionOperator tiny;
  tiny.width = tiny.height = 1;
  tiny.grid.cols = tiny.grid.rows = 1;
  tiny.pixel_offsets = {0, 0};
  tiny.background_weight = {0.75f};
  tiny.cell_pixels = {0.0f};
  tiny.cell_direct_pixels = {0.0f};
  finish_correction_operator(tiny);
  write_correction_operator(dir.file("tiny.cop"), tiny, 0);
  expect_identical(tiny, read_correction_operator(dir.file("tiny.cop")));
  EXPECT_EQ(fs::file_size(dir.file("tiny.cop")), offsets_of(1, 0, 1).end);
}

// ------------------------------------------------------------------ writer

TEST(CorrectionOperatorFile, WriterRefusesAnInconsistentOperator) {
  TempDir dir("glasspiv_cof");
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const std::map<std::string, std::function<void(CorrectionOperator&)>> breakages = {
      {"short value", [](CorrectionOperator& op) { op.value.pop_back(); }},
      {"short cell", [](CorrectionOperator& op) { op.cell.pop_back(); }},
      {"short pixel_offsets", [](CorrectionOperator& op) { op.pixel_offsets.pop_back(); }},
      {"short background", [](CorrectionOperator& op) { op.background_weight.pop_back(); }},
      {"long cell_pixels", [](CorrectionOperator& op) { op.cell_pixels.push_back(0); }},
      {"no cell_direct_pixels", [](CorrectionOperator& op) { op.cell_direct_pixels.clear(); }},
      {"offsets start", [](CorrectionOperator& op) { op.pixel_offsets[0] = 1; }},
      {"offsets decrease", [](CorrectionOperator& op) { std::swap(op.pixel_offsets[3], op.pixel_offsets[9]); }},
      {"last offset", [](CorrectionOperator& op) { op.pixel_offsets.back() -= 1; }},
      {"cell out of range", [](CorrectionOperator& op) { op.cell[5] = 20; }},
      {"NaN value", [nan](CorrectionOperator& op) { op.value[2] = nan; }},
      {"negative value", [](CorrectionOperator& op) { op.value[2] = -1e-30f; }},
      {"infinite background", [inf](CorrectionOperator& op) { op.background_weight[3] = inf; }},
      {"NaN cell_pixels", [nan](CorrectionOperator& op) { op.cell_pixels[7] = nan; }},
      {"negative cell_direct_pixels", [](CorrectionOperator& op) { op.cell_direct_pixels[19] = -2; }},
      {"width", [](CorrectionOperator& op) { op.width = 0; }},
      {"grid cols", [](CorrectionOperator& op) { op.grid.cols = 0; }},
      {"grid mm_per_px", [](CorrectionOperator& op) { op.grid.mm_per_px = 0; }},
      {"grid s0", [](CorrectionOperator& op) { op.grid.s0_mm = std::numeric_limits<double>::infinity(); }},
  };
  for (const auto& [name, breakage] : breakages) {
    CorrectionOperator bad = small_operator();
    breakage(bad);
    EXPECT_THROW(write_correction_operator(dir.file("bad.cop"), bad, 1), std::invalid_argument) << name;
  }
  EXPECT_TRUE(dir.entries().empty());
  // The unbroken operator is written.
  EXPECT_NO_THROW(write_correction_operator(dir.file("good.cop"), small_operator(), 1));
}

// ------------------------------------------------------------------ fingerprint

struct FingerprintInputs {
  std::uint64_t map_fingerprint = 0x9a3e5d1f0c7b2486ull;
  SheetGrid grid = small_grid();
  OperatorOptions options;
  std::uint64_t fingerprint() const { return correction_operator_fingerprint(map_fingerprint, grid, options); }
};

// The documented byte stream, hashed by an FNV-1a 64 written out here.
TEST(CorrectionOperatorFingerprint, IsFnv1aOfTheDocumentedByteStream) {
  const FingerprintInputs in;
  std::string stream;
  auto add = [&](auto v) { stream.append(reinterpret_cast<const char*>(&v), sizeof v); };  // little-endian host
  add(kCorrectionOperatorVersion);
  add(in.map_fingerprint);
  add(std::int32_t{in.grid.cols});
  add(std::int32_t{in.grid.rows});
  add(in.grid.mm_per_px);
  add(in.grid.s0_mm);
  add(in.grid.t0_mm);
  add(std::uint32_t{in.options.footprint_filter ? 1u : 0u});
  add(std::int32_t{in.options.max_taps_per_axis});
  add(std::uint32_t{in.options.taps_by_weight ? 1u : 0u});
  ASSERT_EQ(stream.size(), 4u + 8 + 4 + 4 + 3 * 8 + 4 + 4 + 4);
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : stream) h = (h ^ c) * 1099511628211ull;
  EXPECT_EQ(in.fingerprint(), h);
}

TEST(CorrectionOperatorFingerprint, ChangesWithEverySingleInput) {
  const FingerprintInputs base;
  EXPECT_EQ(base.fingerprint(), FingerprintInputs().fingerprint());
  // -0.0 and 0.0 are the same input.
  FingerprintInputs zero = base, negative_zero = base;
  zero.grid.t0_mm = 0.0;
  negative_zero.grid.t0_mm = -0.0;
  EXPECT_EQ(zero.fingerprint(), negative_zero.fingerprint());

  const std::vector<std::pair<std::string, std::function<void(FingerprintInputs&)>>> changes = {
      {"map fingerprint, last bit", [](FingerprintInputs& in) { in.map_fingerprint ^= 1; }},
      {"map fingerprint, first bit", [](FingerprintInputs& in) { in.map_fingerprint ^= 1ull << 63; }},
      {"grid.cols", [](FingerprintInputs& in) { in.grid.cols += 1; }},
      {"grid.rows", [](FingerprintInputs& in) { in.grid.rows += 1; }},
      {"cols and rows swapped", [](FingerprintInputs& in) { std::swap(in.grid.cols, in.grid.rows); }},
      {"grid.mm_per_px, last bit", [](FingerprintInputs& in) { in.grid.mm_per_px = std::nextafter(in.grid.mm_per_px, 1.0); }},
      {"grid.s0_mm", [](FingerprintInputs& in) { in.grid.s0_mm += 1e-12; }},
      {"grid.t0_mm", [](FingerprintInputs& in) { in.grid.t0_mm += 1e-12; }},
      {"s0 and t0 swapped", [](FingerprintInputs& in) { std::swap(in.grid.s0_mm, in.grid.t0_mm); }},
      {"options.footprint_filter", [](FingerprintInputs& in) { in.options.footprint_filter = !in.options.footprint_filter; }},
      {"options.max_taps_per_axis", [](FingerprintInputs& in) { in.options.max_taps_per_axis += 1; }},
      {"options.taps_by_weight", [](FingerprintInputs& in) { in.options.taps_by_weight = !in.options.taps_by_weight; }},
  };
  std::map<std::uint64_t, std::string> seen = {{base.fingerprint(), "base"}};
  for (const auto& [name, change] : changes) {
    FingerprintInputs in = base;
    change(in);
    const std::uint64_t fp = in.fingerprint();
    EXPECT_NE(fp, base.fingerprint()) << name;
    const auto [it, fresh] = seen.emplace(fp, name);
    EXPECT_TRUE(fresh) << name << " gives the fingerprint of " << it->second;
  }
}

// The fingerprint hashes every field of these structs and the file stores
// every array of the operator that finish_correction_operator does not derive.
// A struct that grows fails here until correction_operator_fingerprint hashes
// the new field (SheetGrid: and the header stores it) or the file stores the
// new array; then update the size. LP64 layouts.
TEST(CorrectionOperatorFingerprint, HashesEveryFieldOfTheInputStructs) {
#if defined(__LP64__)
  EXPECT_EQ(sizeof(SheetGrid), 32u) << "SheetGrid changed: hash the new field and store it in the header";
  EXPECT_EQ(sizeof(OperatorOptions), 12u) << "OperatorOptions changed: hash the new field";
  EXPECT_EQ(sizeof(CorrectionOperator), 2 * sizeof(int) + sizeof(SheetGrid) + 10 * sizeof(std::vector<float>))
      << "CorrectionOperator changed: store a new stored array in the file (or derive it on reading)";
#else
  GTEST_SKIP() << "struct sizes are checked on LP64 hosts";
#endif
}

// ------------------------------------------------------------------ read errors

TEST(CorrectionOperatorFile, ReadErrorsNameThePathAndTheField) {
  TempDir dir("glasspiv_cof");
  const CorrectionOperator op = small_operator();
  const std::string path = dir.file("op.cop");
  write_correction_operator(path, op, 42);
  const std::string good = read_file(path);
  const Offsets o = offsets_of(op);
  const double dnan = std::numeric_limits<double>::quiet_NaN();
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();

  struct Case {
    std::string name, field;
    std::function<void(std::string&)> damage;
  };
  auto resealed = [](std::function<void(std::string&)> f) {
    return [f](std::string& b) {
      f(b);
      reseal(b);
    };
  };
  const std::vector<Case> cases = {
      {"empty file", "magic", [](std::string& b) { b.clear(); }},
      {"magic", "magic", [](std::string& b) { b[4] = 'X'; }},
      {"a transport map's magic", "magic", [](std::string& b) { b.replace(0, 8, "GPIVTMAP"); }},
      {"ends before the version", "header", [](std::string& b) { b.resize(12); }},
      {"version", "header.version", [](std::string& b) { poke<std::uint32_t>(b, 8, 2); }},
      {"header size", "header.header_size", [](std::string& b) { poke<std::uint32_t>(b, 12, 144); }},
      {"ends inside the header", "header", [](std::string& b) { b.resize(50); }},
      {"operator version 0", "header.operator_version", [](std::string& b) { poke<std::uint32_t>(b, 24, 0); }},
      {"reserved", "header.reserved", [](std::string& b) { poke<std::uint32_t>(b, 28, 1); }},
      {"width", "header.width", [](std::string& b) { poke<std::int32_t>(b, 32, 0); }},
      {"height", "header.height", [](std::string& b) { poke<std::int32_t>(b, 36, -3); }},
      {"grid cols", "header.grid.cols", [](std::string& b) { poke<std::int32_t>(b, 40, 0); }},
      {"grid rows", "header.grid.rows", [](std::string& b) { poke<std::int32_t>(b, 44, -1); }},
      {"grid too big", "header.grid", [](std::string& b) { poke<std::int32_t>(b, 44, 1 << 30); }},
      {"mm_per_px zero", "header.grid.mm_per_px", [](std::string& b) { poke<double>(b, 48, 0.0); }},
      {"mm_per_px NaN", "header.grid.mm_per_px", [dnan](std::string& b) { poke<double>(b, 48, dnan); }},
      {"s0 infinite", "header.grid.s0_mm",
       [](std::string& b) { poke<double>(b, 56, -std::numeric_limits<double>::infinity()); }},
      {"t0 NaN", "header.grid.t0_mm", [dnan](std::string& b) { poke<double>(b, 64, dnan); }},
      {"entry count beyond u32", "header.entry_count", [](std::string& b) { poke<std::uint64_t>(b, 72, 1ull << 32); }},
      {"entry count 23 instead of 21", "payload",
       [](std::string& b) { poke<std::uint64_t>(b, 72, 23); }},
      {"entry count huge", "payload", [](std::string& b) { poke<std::uint64_t>(b, 72, 0xffffffffull); }},
      {"pixel count overflowing", "payload",
       [](std::string& b) {
         poke<std::int32_t>(b, 32, INT_MAX);
         poke<std::int32_t>(b, 36, INT_MAX);
       }},
      {"more grid cells", "payload", [](std::string& b) { poke<std::int32_t>(b, 40, 1000); }},
      {"truncated", "payload", [](std::string& b) { b.resize(b.size() - 1); }},
      {"trailing bytes", "payload", [](std::string& b) { b += std::string(8, '\0'); }},
      {"checksum in the header", "header.checksum", [](std::string& b) { b[80] ^= 1; }},
      {"flipped payload byte", "header.checksum", [o](std::string& b) { b[o.value + 9] ^= 0x10; }},
      {"flipped padding byte", "header.checksum", [o](std::string& b) { b[o.cell + 85] = 1; }},
      {"flipped bit in the last array", "header.checksum", [](std::string& b) { b[b.size() - 5] ^= 0x80; }},
      {"offsets start", "pixel_offsets", resealed([o](std::string& b) { poke<std::uint32_t>(b, o.pixel_offsets, 1); })},
      {"offsets decrease", "pixel_offsets",
       resealed([o](std::string& b) { poke<std::uint32_t>(b, o.pixel_offsets + 4 * 5, 0xfffffff0u); })},
      {"offsets end", "pixel_offsets",
       resealed([o](std::string& b) { poke<std::uint32_t>(b, o.pixel_offsets + 4 * 12, 20); })},
      {"cell out of range", "cell", resealed([o](std::string& b) { poke<std::uint32_t>(b, o.cell + 4 * 20, 20); })},
      {"cell far out of range", "cell",
       resealed([o](std::string& b) { poke<std::uint32_t>(b, o.cell, 0xffffffffu); })},
      {"NaN value", "value", resealed([o, nan](std::string& b) { poke<float>(b, o.value + 4 * 3, nan); })},
      {"infinite value", "value", resealed([o, inf](std::string& b) { poke<float>(b, o.value + 4 * 20, inf); })},
      {"negative value", "value", resealed([o](std::string& b) { poke<float>(b, o.value, -0.5f); })},
      {"NaN background weight", "background_weight",
       resealed([o, nan](std::string& b) { poke<float>(b, o.background_weight + 4 * 11, nan); })},
      {"negative background weight", "background_weight",
       resealed([o, inf](std::string& b) { poke<float>(b, o.background_weight, -inf); })},
      {"infinite cell_pixels", "cell_pixels",
       resealed([o, inf](std::string& b) { poke<float>(b, o.cell_pixels + 4 * 19, inf); })},
      {"negative cell_pixels", "cell_pixels",
       resealed([o](std::string& b) { poke<float>(b, o.cell_pixels + 4 * 2, -1.0f); })},
      {"NaN cell_direct_pixels", "cell_direct_pixels",
       resealed([o, nan](std::string& b) { poke<float>(b, o.cell_direct_pixels + 4 * 19, nan); })},
  };
  for (const Case& k : cases) {
    std::string bytes = good;
    k.damage(bytes);
    write_file_atomically(path, bytes);
    try {
      read_correction_operator(path);
      ADD_FAILURE() << k.name << ": no error";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path) << k.name;
      EXPECT_EQ(e.field(), k.field) << k.name << ": " << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    } catch (const std::exception& e) {
      ADD_FAILURE() << k.name << ": not an InputError: " << e.what();
    }
  }
  // The undamaged bytes read back (the cases above damaged copies only).
  write_file_atomically(path, good);
  std::uint64_t fp = 0;
  expect_identical(op, read_correction_operator(path, &fp));
  EXPECT_EQ(fp, 42u);

  try {
    read_correction_operator(dir.file("missing.cop"));
    ADD_FAILURE() << "missing file read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), dir.file("missing.cop"));
    EXPECT_EQ(e.field(), "");
  }
  EXPECT_THROW(read_correction_operator(dir.file("")), InputError);  // the folder itself
}

TEST(CorrectionOperatorFile, ErrorMessagesSayWhatIsWrong) {
  TempDir dir("glasspiv_cof");
  const CorrectionOperator op = small_operator();
  const std::string path = dir.file("op.cop");
  write_correction_operator(path, op, 1);
  std::string bytes = read_file(path);
  poke<float>(bytes, offsets_of(op).value + 4 * 3, std::numeric_limits<float>::quiet_NaN());
  reseal(bytes);
  write_file_atomically(path, bytes);
  try {
    read_correction_operator(path);
    ADD_FAILURE() << "NaN read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.problem(), "value[3] is nan, must be finite and not negative");
  }
  bytes = read_file(path);
  bytes.resize(bytes.size() - 8);
  write_file_atomically(path, bytes);
  try {
    read_correction_operator(path);
    ADD_FAILURE() << "truncated file read";
  } catch (const InputError& e) {
    const std::size_t full = offsets_of(op).end;
    EXPECT_EQ(e.problem(), "file is " + std::to_string(full - 8) + " bytes, the header (4x3 pixels, 21 entries, 5x4 "
                           "cells) needs " + std::to_string(full) + ": truncated");
  }
}

// ------------------------------------------------------------------ cache lookup

TEST(CorrectionOperatorCache, LoadsOnlyAnIntactOperatorOfTheSameSetup) {
  TempDir dir("glasspiv_cof");
  const CorrectionOperator op = small_operator();
  const FingerprintInputs in;
  const std::uint64_t fp = in.fingerprint();
  const std::string path = dir.file("cache.cop");
  std::string why = "stale";

  EXPECT_FALSE(load_cached_correction_operator(path, fp, &why));
  EXPECT_EQ(why, "no file");

  write_correction_operator(path, op, fp);
  const auto hit = load_cached_correction_operator(path, fp, &why);
  ASSERT_TRUE(hit);
  EXPECT_EQ(why, "");
  expect_identical(op, *hit);

  FingerprintInputs other_in = in;
  other_in.options.max_taps_per_axis = 8;
  const std::uint64_t other = other_in.fingerprint();
  EXPECT_FALSE(load_cached_correction_operator(path, other, &why));
  EXPECT_EQ(why, "made for another setup (fingerprint " + fingerprint_hex(fp) + ", wanted " + fingerprint_hex(other) +
                     ")");
  EXPECT_FALSE(load_cached_correction_operator(path, other));  // why is optional

  const std::string good = read_file(path);
  auto expect_unreadable = [&](const std::string& bytes, const std::string& field, const std::string& what) {
    write_file_atomically(path, bytes);
    std::string reason;
    EXPECT_FALSE(load_cached_correction_operator(path, fp, &reason)) << what;
    EXPECT_EQ(reason.rfind("unreadable: " + path + ": field '" + field + "'", 0), 0u) << what << ": " << reason;
    EXPECT_EQ(reason.find('\n'), std::string::npos) << reason;
  };
  expect_unreadable(good.substr(0, good.size() - 8), "payload", "truncated");
  expect_unreadable(good.substr(0, 40), "header", "truncated header");
  std::string flipped = good;
  flipped[good.size() / 2] ^= 0x10;
  expect_unreadable(flipped, "header.checksum", "flipped payload byte");
  std::string magic = good;
  magic[3] = 'X';
  expect_unreadable(magic, "magic", "wrong magic");
  expect_unreadable("", "magic", "empty file");

  // Another setup's file is refused on its header alone: its damaged payload is not read.
  write_file_atomically(path, flipped);
  EXPECT_FALSE(load_cached_correction_operator(path, other, &why));
  EXPECT_EQ(why.rfind("made for another setup", 0), 0u) << why;

  // The intact file is found again.
  write_file_atomically(path, good);
  EXPECT_TRUE(load_cached_correction_operator(path, fp, &why));
  EXPECT_EQ(why, "");
}

// ------------------------------------------------------------------ atomic write

// A write that fails half way (file size limit: the write gets EFBIG) throws,
// leaves the existing file as it was and no temporary behind.
TEST(CorrectionOperatorFile, FailedWriteLeavesTheExistingFileUntouched) {
  TempDir dir("glasspiv_cof");
  const std::string path = dir.file("keep.cop");
  const CorrectionOperator small = small_operator();
  write_correction_operator(path, small, 5);
  const std::string before = read_file(path);
  ASSERT_LT(before.size(), 4096u);

  const CorrectionOperator big = bigger_operator();
  ASSERT_GT(offsets_of(big).end, 8192u);
  rlimit old{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
  auto* old_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit low = old;
  low.rlim_cur = 4096;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &low), 0);
  bool threw = false;
  try {
    write_correction_operator(path, big, 6);
  } catch (const InputError& e) {
    threw = true;
    EXPECT_EQ(e.file(), path);
  }
  ::setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_TRUE(threw);
  EXPECT_EQ(read_file(path), before);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"keep.cop"});
  std::uint64_t fp = 0;
  expect_identical(small, read_correction_operator(path, &fp));
  EXPECT_EQ(fp, 5u);

  // And without the limit the same write replaces it.
  write_correction_operator(path, big, 6);
  expect_identical(big, read_correction_operator(path, &fp));
  EXPECT_EQ(fp, 6u);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"keep.cop"});
}

}  // namespace
}  // namespace glasspiv
