#include "correct/correction_operator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "render/parallel_rows.h"

namespace glasspiv {

std::size_t CorrectionOperator::memory_bytes() const {
  return (pixel_offsets.size() + cell.size() + cell_offsets.size() + entry_pixel.size()) * sizeof(std::uint32_t) +
         (value.size() + background_weight.size() + cell_pixels.size() + cell_direct_pixels.size() + cell_weight.size() + value_by_cell.size()) *
             sizeof(float);
}

namespace {

// The entries of one row of pixels, before concatenation.
struct RowEntries {
  std::vector<std::uint32_t> counts;  // entries per pixel
  std::vector<std::uint32_t> cell;
  std::vector<float> value, fraction;  // A[p, c] and the unweighted footprint fraction
  std::vector<float> direct_fraction;  // the fraction from crossings without a reflection
};

struct Splat {
  std::uint32_t cell;
  float value, fraction, direct_fraction;
};

// Bilinear splat of (w, f) at fractional cell coordinates (x, y); taps outside the grid are lost
// (only footprints reaching past the sheet's extent lose any).
void splat(const SheetGrid& g, double x, double y, double w, double f, bool direct, std::vector<Splat>& out) {
  const double fx0 = std::floor(x), fy0 = std::floor(y);
  if (!(fx0 >= -1 && fy0 >= -1 && fx0 < g.cols && fy0 < g.rows)) return;
  const int x0 = static_cast<int>(fx0), y0 = static_cast<int>(fy0);
  const double ax = x - fx0, ay = y - fy0;
  const double k[4] = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
  for (int i = 0; i < 4; ++i) {
    const int cx = x0 + (i & 1), cy = y0 + (i >> 1);
    if (k[i] <= 0 || cx < 0 || cy < 0 || cx >= g.cols || cy >= g.rows) continue;
    out.push_back({static_cast<std::uint32_t>(static_cast<std::size_t>(cy) * g.cols + cx), static_cast<float>(w * k[i]),
                   static_cast<float>(f * k[i]), direct ? static_cast<float>(f * k[i]) : 0.0f});
  }
}

void check_map(const TransportMap& map) {
  const std::size_t n = map.crossing_count();
  if (map.width < 1 || map.height < 1 || map.pixel_offsets.size() != map.pixel_count() + 1 ||
      map.pixel_offsets.back() != n || map.s_mm.size() != n || map.t_mm.size() != n ||
      map.background_weight.size() != map.pixel_count())
    throw std::invalid_argument("correction operator: the transport map's arrays are inconsistent");
  if (map.ds_dcol.size() != n || map.ds_drow.size() != n || map.dt_dcol.size() != n || map.dt_drow.size() != n)
    throw std::invalid_argument("correction operator: the transport map has no footprint Jacobians");
  if (map.samples_per_axis < 1) throw std::invalid_argument("correction operator: samples per axis < 1");
}

}  // namespace

CorrectionOperator build_correction_operator(const TransportMap& map, const SheetGrid& grid,
                                             const OperatorOptions& options, int threads,
                                             const std::function<void(int, int)>& progress) {
  check_map(map);
  if (grid.cols < 1 || grid.rows < 1 || grid.cell_count() > kMaxSheetGridCells || !(grid.mm_per_px > 0) ||
      !std::isfinite(grid.mm_per_px) || !std::isfinite(grid.s0_mm) || !std::isfinite(grid.t0_mm))
    throw std::invalid_argument("correction operator: bad sheet grid");
  if (options.max_taps_per_axis < 1 || options.max_taps_per_axis > 256)
    throw std::invalid_argument("correction operator: max_taps_per_axis must be in [1, 256]");

  const double inv_k = 1.0 / map.samples_per_axis, inv_mm = 1.0 / grid.mm_per_px;
  const double sample_share = inv_k * inv_k;
  const int max_taps = options.max_taps_per_axis;
  std::vector<RowEntries> rows(static_cast<std::size_t>(map.height));
  parallel_rows(
      map.height, threads,
      [&](int row) {
        RowEntries& out = rows[static_cast<std::size_t>(row)];
        out.counts.assign(static_cast<std::size_t>(map.width), 0);
        std::vector<Splat> splats;
        for (int col = 0; col < map.width; ++col) {
          const std::size_t p = static_cast<std::size_t>(row) * map.width + col;
          splats.clear();
          for (std::uint32_t i = map.pixel_offsets[p]; i < map.pixel_offsets[p + 1]; ++i) {
            const double w = map.weight[i];
            const bool direct = map.tag[i] != static_cast<std::uint8_t>(CrossingTag::with_reflections);
            const double x = grid.col(map.s_mm[i]), y = grid.row(map.t_mm[i]);
            // Footprint axes in cells (x = col grows with s, y = row grows with -t).
            const double ax = map.ds_dcol[i] * inv_k * inv_mm, ay = -map.dt_dcol[i] * inv_k * inv_mm;
            const double bx = map.ds_drow[i] * inv_k * inv_mm, by = -map.dt_drow[i] * inv_k * inv_mm;
            const double la = std::hypot(ax, ay), lb = std::hypot(bx, by);
            int na = 1, nb = 1;
            if (options.footprint_filter && std::isfinite(la) && std::isfinite(lb)) {
              const int cap = options.taps_by_weight
                                  ? std::clamp(static_cast<int>(std::ceil(max_taps * std::sqrt(std::max(0.0, w)))), 1, max_taps)
                                  : max_taps;
              na = std::clamp(static_cast<int>(std::ceil(la)), 1, cap);
              nb = std::clamp(static_cast<int>(std::ceil(lb)), 1, cap);
            }
            const double share = 1.0 / (na * nb);
            for (int j = 0; j < nb; ++j) {
              const double v = (j + 0.5) / nb - 0.5;
              for (int k = 0; k < na; ++k) {
                const double u = (k + 0.5) / na - 0.5;
                const double tx = na * nb == 1 ? x : x + u * ax + v * bx;
                const double ty = na * nb == 1 ? y : y + u * ay + v * by;
                // A sample is 1/k^2 of its pixel (its weight already is).
                splat(grid, tx, ty, w * share, share * sample_share, direct, splats);
              }
            }
          }
          // One entry per cell: sort by cell and merge.
          std::sort(splats.begin(), splats.end(), [](const Splat& a, const Splat& b) { return a.cell < b.cell; });
          std::uint32_t n = 0;
          for (std::size_t i = 0; i < splats.size();) {
            double value = 0, fraction = 0, direct_fraction = 0;
            const std::uint32_t c = splats[i].cell;
            for (; i < splats.size() && splats[i].cell == c; ++i) {
              value += splats[i].value;
              fraction += splats[i].fraction;
              direct_fraction += splats[i].direct_fraction;
            }
            if (value <= 0 && fraction <= 0) continue;
            out.cell.push_back(c);
            out.value.push_back(static_cast<float>(value));
            out.fraction.push_back(static_cast<float>(fraction));
            out.direct_fraction.push_back(static_cast<float>(direct_fraction));
            ++n;
          }
          out.counts[static_cast<std::size_t>(col)] = n;
        }
      },
      progress);

  CorrectionOperator op;
  op.width = map.width;
  op.height = map.height;
  op.grid = grid;
  std::size_t total = 0;
  for (const RowEntries& r : rows) total += r.cell.size();
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw std::overflow_error("correction operator: more than 2^32 - 1 entries (choose a coarser grid)");
  op.pixel_offsets.reserve(op.pixel_count() + 1);
  op.cell.reserve(total);
  op.value.reserve(total);
  op.cell_pixels.assign(grid.cell_count(), 0.0f);
  op.cell_direct_pixels.assign(grid.cell_count(), 0.0f);
  std::vector<double> pixels(grid.cell_count(), 0.0), direct(grid.cell_count(), 0.0);
  std::uint32_t offset = 0;
  op.pixel_offsets.push_back(0);
  for (RowEntries& r : rows) {
    for (std::uint32_t n : r.counts) op.pixel_offsets.push_back(offset += n);
    op.cell.insert(op.cell.end(), r.cell.begin(), r.cell.end());
    op.value.insert(op.value.end(), r.value.begin(), r.value.end());
    for (std::size_t i = 0; i < r.cell.size(); ++i) {
      pixels[r.cell[i]] += r.fraction[i];
      direct[r.cell[i]] += r.direct_fraction[i];
    }
    r = RowEntries{};
  }
  for (std::size_t c = 0; c < pixels.size(); ++c) {
    op.cell_pixels[c] = static_cast<float>(pixels[c]);
    op.cell_direct_pixels[c] = static_cast<float>(direct[c]);
  }
  op.background_weight = map.background_weight;
  finish_correction_operator(op);
  return op;
}

void finish_correction_operator(CorrectionOperator& op) {
  const std::size_t cells = op.grid.cell_count(), n = op.value.size();
  if (op.pixel_offsets.size() != op.pixel_count() + 1 || op.pixel_offsets.front() != 0 ||
      op.pixel_offsets.back() != n || op.cell.size() != n || op.background_weight.size() != op.pixel_count() ||
      op.cell_pixels.size() != cells || op.cell_direct_pixels.size() != cells)
    throw std::invalid_argument("correction operator: inconsistent arrays");
  for (std::size_t p = 0; p < op.pixel_count(); ++p)
    if (op.pixel_offsets[p] > op.pixel_offsets[p + 1])
      throw std::invalid_argument("correction operator: pixel offsets decrease");
  op.cell_offsets.assign(cells + 1, 0);
  for (std::uint32_t c : op.cell) {
    if (c >= cells) throw std::invalid_argument("correction operator: cell index outside the grid");
    ++op.cell_offsets[c + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) op.cell_offsets[c + 1] += op.cell_offsets[c];
  op.entry_pixel.resize(n);
  op.value_by_cell.resize(n);
  std::vector<std::uint32_t> next(op.cell_offsets.begin(), op.cell_offsets.end() - 1);
  for (std::size_t p = 0; p < op.pixel_count(); ++p) {
    for (std::uint32_t i = op.pixel_offsets[p]; i < op.pixel_offsets[p + 1]; ++i) {
      const std::uint32_t slot = next[op.cell[i]]++;
      op.entry_pixel[slot] = static_cast<std::uint32_t>(p);
      op.value_by_cell[slot] = op.value[i];
    }
  }
  op.cell_weight.assign(cells, 0.0f);
  for (std::size_t c = 0; c < cells; ++c) {
    double sum = 0;
    for (std::uint32_t i = op.cell_offsets[c]; i < op.cell_offsets[c + 1]; ++i) sum += op.value_by_cell[i];
    op.cell_weight[c] = static_cast<float>(sum);
  }
}

namespace {
// Rows of at least this many items per parallel task: per-frame passes take milliseconds,
// so a task must be worth the handing out.
constexpr std::size_t kItemsPerTask = 16384;

template <typename Fn>
void parallel_ranges(std::size_t items, const Fn& fn) {
  const int tasks = static_cast<int>(std::max<std::size_t>(1, (items + kItemsPerTask - 1) / kItemsPerTask));
  parallel_rows(tasks, 0, [&](int t) {
    const std::size_t begin = static_cast<std::size_t>(t) * kItemsPerTask;
    fn(begin, std::min(items, begin + kItemsPerTask));
  });
}
}  // namespace

void apply_forward(const CorrectionOperator& op, const float* sheet, double background_radiance, float* image) {
  parallel_ranges(op.pixel_count(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) {
      double sum = static_cast<double>(op.background_weight[p]) * background_radiance;
      for (std::uint32_t i = op.pixel_offsets[p]; i < op.pixel_offsets[p + 1]; ++i)
        sum += static_cast<double>(op.value[i]) * sheet[op.cell[i]];
      image[p] = static_cast<float>(sum);
    }
  });
}

void apply_transpose(const CorrectionOperator& op, const float* image, float* per_cell) {
  parallel_ranges(op.grid.cell_count(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c) {
      double sum = 0;
      for (std::uint32_t i = op.cell_offsets[c]; i < op.cell_offsets[c + 1]; ++i)
        sum += static_cast<double>(op.value_by_cell[i]) * image[op.entry_pixel[i]];
      per_cell[c] = static_cast<float>(sum);
    }
  });
}

}  // namespace glasspiv
