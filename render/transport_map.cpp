#include "render/transport_map.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "render/crossing_sink.h"
#include "render/parallel_rows.h"
#include "render/reflection_grid.h"
#include "render/row_camera_rays.h"
#include "render/trace_scene_builder.h"
#include "util/huge_pages.h"

namespace glasspiv {

std::size_t TransportMap::memory_bytes() const {
  return pixel_offsets.size() * sizeof(std::uint32_t) +
         (s_mm.size() + t_mm.size() + weight.size() + ds_dcol.size() + ds_drow.size() + dt_dcol.size() +
          dt_drow.size()) * sizeof(float) +
         tag.size() + (background_weight.size() + opaque_weight.size()) * sizeof(float);
}

namespace {

// What the traced samples of a row (or of an anchor row) did.
struct RowStats {
  long camera_rays = 0, branches = 0, no_hit_pixels = 0, unproject_failures = 0;
  long closed_form = 0, cut_by_weight = 0, cut_by_depth = 0, reflections_skipped = 0, interpolated = 0;
  long samples_interpolated = 0;
  double cut_weight = 0;

  // One traced sample, weights times scale (its deferred subtrees are not cut).
  void add(const TraceResult& r, double scale) {
    ++camera_rays;
    branches += r.counts.branches_traced;
    closed_form += r.counts.closed_form;
    cut_by_weight += r.counts.cut_by_weight;
    cut_by_depth += r.counts.cut_by_depth;
    reflections_skipped += r.counts.reflections_skipped;
    cut_weight += (r.cut_by_weight_weight + r.cut_by_depth_weight + r.skipped_reflection_weight) * scale;
  }
  void add_to(TransportStats* st) const {
    st->camera_rays += camera_rays;
    st->branches_traced += branches;
    st->pixels_without_solid_hit += no_hit_pixels;
    st->unproject_failures += unproject_failures;
    st->closed_form_rays += closed_form;
    st->branches_cut_by_weight += cut_by_weight;
    st->branches_cut_by_depth += cut_by_depth;
    st->reflections_skipped += reflections_skipped;
    st->subtrees_interpolated += interpolated;
    st->samples_interpolated += samples_interpolated;
    st->cut_weight += cut_weight;
  }
};

// The map's per-pixel arrays, written in place by the rows: each pixel's
// crossing count (in pixel_offsets[p + 1], summed into offsets once every row
// is done), its escaped and its opaque weight.
struct PixelArrays {
  std::uint32_t* counts = nullptr;
  float* background = nullptr;
  float* opaque = nullptr;
  int width = 0;
};

// A row's per-pixel entries and statistics (its crossings go to the CrossingSink).
struct RowBuffer {
  std::uint32_t* counts = nullptr;  // the row's slices of PixelArrays
  float *background = nullptr, *opaque = nullptr;
  RowStats stats;

  // Row `row`'s per-pixel entries go to its slices of `pixels`.
  void start_row(const PixelArrays& pixels, int row) {
    const std::size_t first = static_cast<std::size_t>(row) * static_cast<std::size_t>(pixels.width);
    counts = pixels.counts + first;
    background = pixels.background + first;
    opaque = pixels.opaque + first;
  }
};

// One pixel's sums over its samples, appending their crossings to the row's.
struct PixelSums {
  bool any_hit = false;
  double background = 0, opaque = 0;
  std::uint32_t count = 0;

  // A traced sample, weights times scale.
  void add_traced(const TraceResult& r, double scale, RowCrossings* scratch) {
    any_hit = any_hit || r.met_solid();
    for (const SheetCrossing& c : r.crossings) scratch->push(grid_crossing(c, scale));
    count += static_cast<std::uint32_t>(r.crossings.size());
    background += r.background_weight * scale;
    opaque += r.opaque_weight * scale;
  }
  void add_crossings(const GridCrossing* c, std::size_t n, RowCrossings* scratch) {
    for (std::size_t i = 0; i < n; ++i) scratch->push(c[i]);
    count += static_cast<std::uint32_t>(n);
  }
  // The pixel's entry in the row, `col`.
  void store(int col, RowBuffer* out) const {
    if (!any_hit) ++out->stats.no_hit_pixels;
    out->counts[static_cast<std::size_t>(col)] = count;
    out->background[static_cast<std::size_t>(col)] = static_cast<float>(background);
    out->opaque[static_cast<std::size_t>(col)] = static_cast<float>(opaque);
  }
};

// The camera samples as one lattice of (width k) x (height k) points, and its
// reflection grid: anchors on every g-th point of each axis, cells between
// four of them.
struct SampleLattice {
  int k = 1, g = 1, width = 0, height = 0;  // width, height in samples
  int anchors_x = 0, anchors_y = 0;
  SampleLattice(int width_px, int height_px, int samples_per_axis, int grid)
      : k(samples_per_axis), g(grid), width(width_px * samples_per_axis), height(height_px * samples_per_axis) {
    anchors_x = (width - 1) / g + 1;
    anchors_y = (height - 1) / g + 1;
  }
  // The pixel coordinates of sample (x, y), as RowCameraRays makes them.
  Eigen::Vector2d pixel(int x, int y) const {
    const int col = x / k, sx = x % k, row = y / k, sy = y % k;
    return {col + (sx + 0.5) / k - 0.5, row + (sy + 0.5) / k - 0.5};
  }
  bool is_anchor(int x, int y) const { return x % g == 0 && y % g == 0; }
  int cells_x() const { return std::max(anchors_x - 1, 0); }
  int cells_y() const { return std::max(anchors_y - 1, 0); }
  // Whether sample (x, y) has four anchors around it (its cell: x / g, y / g).
  bool in_cell(int x, int y) const { return x / g < cells_x() && y / g < cells_y(); }
};

void trace_row(const TraceScene& scene, const SceneIndex& index, const CameraModel& camera,
               const RigidTransform& camera_from_world, const TraceOptions& options, int k, int row,
               const PixelArrays& pixels, RowBuffer* out, CrossingSink* sink) {
  thread_local TraceResult r;  // reused: no allocation per ray
  // The row's crossings grow here, in one buffer per thread that keeps its
  // capacity from row to row, and go to the sink when the row is done.
  thread_local RowCrossings scratch;
  scratch.clear();
  const int width = camera.width_px();
  const double inv_samples = 1.0 / (static_cast<double>(k) * k);
  out->start_row(pixels, row);
  RowCameraRays rays(camera, camera_from_world, row, k);
  for (int col = 0; col < width; ++col) {
    PixelSums pixel;
    for (int sample = 0; sample < k * k; ++sample) {
      const std::optional<CameraRay>& ray = rays.next();
      if (!ray) {
        ++out->stats.unproject_failures;
        continue;
      }
      trace_ray(scene, index, *ray, options, &r);
      out->stats.add(r, inv_samples);
      pixel.add_traced(r, inv_samples, &scratch);
    }
    pixel.store(col, out);
  }
  sink->commit(row, &scratch);
}

// The reflection grid's anchors: anchor row ay, traced whole.
void trace_anchor_row(const TraceScene& scene, const SceneIndex& index, const CameraModel& camera,
                      const RigidTransform& camera_from_world, const TraceOptions& options,
                      const SampleLattice& lattice, int ay, AnchorRow* out, RowStats* stats) {
  thread_local TraceResult r;
  thread_local std::vector<Eigen::Vector2d> pixels;
  thread_local std::vector<std::optional<CameraRay>> rays;
  pixels.clear();
  for (int ax = 0; ax < lattice.anchors_x; ++ax) pixels.push_back(lattice.pixel(ax * lattice.g, ay * lattice.g));
  CameraRayWarmStart warm;
  pixel_camera_rays(camera, camera_from_world, pixels, &rays, &warm);
  const double inv_samples = 1.0 / (static_cast<double>(lattice.k) * lattice.k);
  for (const std::optional<CameraRay>& ray : rays) {
    if (!ray) {
      ++stats->unproject_failures;
      out->add(nullptr, inv_samples);
      continue;
    }
    trace_ray(scene, index, *ray, options, &r);
    stats->add(r, inv_samples);
    out->add(&r, inv_samples);
  }
}

// The subtrees that agree in each cell of one cell row (CSR over its cells),
// and with TraceOptions::grid_whole_samples the cells that agree whole.
struct CellRow {
  std::vector<std::uint32_t> begin;  // cells_x + 1
  AgreeingSubtrees agreeing;
  std::vector<std::uint8_t> whole;     // cells_x, or empty
  std::vector<SubtreeCorners> chains;  // per cell (valid where whole)

  // Empties the row, keeping its buffers' capacity for the next row.
  void clear() {
    begin.clear();
    agreeing.clear();
    whole.clear();
    chains.clear();
  }
  bool agrees_whole(int cx) const { return !whole.empty() && whole[static_cast<std::size_t>(cx)] != 0; }
  // What a sample in cell cx defers (the cell's agreeing subtrees), and where
  // their corners lie.
  DeferredSubtrees deferred(int cx, const SubtreeCorners** corners) const {
    const std::uint32_t first = begin[static_cast<std::size_t>(cx)];
    DeferredSubtrees d;
    d.ids = agreeing.ids.data() + first;
    d.min_weight = agreeing.min_weight.data() + first;
    d.max_weight = agreeing.max_weight.data() + first;
    d.count = begin[static_cast<std::size_t>(cx) + 1] - first;
    *corners = agreeing.corners.data() + first;
    return d;
  }
};

// The corners of each subtree the tracer deferred (r.deferred, in its order):
// it defers only the ids it was given, `offered`, whose corners are `corners`.
void deferred_corners(const std::vector<std::uint64_t>& deferred, const DeferredSubtrees& offered,
                      const SubtreeCorners* corners, std::vector<const SubtreeCorners*>* out) {
  out->clear();
  for (std::uint64_t id : deferred) {
    const auto j = static_cast<std::size_t>(std::find(offered.ids, offered.ids + offered.count, id) - offered.ids);
    assert(j < offered.count);
    out->push_back(corners + j);
  }
}

// The cells of cell row cy between anchor rows top and bottom: their agreeing
// subtrees and, with `whole`, which agree whole.
void compare_cell_row(const AnchorRow& top, const AnchorRow& bottom, int cells_x, double cell_px,
                      const GridTolerance& tolerance, bool whole, CellRow* cr) {
  cr->begin.push_back(0);
  if (whole) {
    cr->whole.resize(static_cast<std::size_t>(cells_x));
    cr->chains.resize(static_cast<std::size_t>(cells_x));
  }
  for (int cx = 0; cx < cells_x; ++cx) {
    agreeing_subtrees(top, bottom, cx, cell_px, tolerance, &cr->agreeing);
    const std::uint32_t first = cr->begin.back();
    cr->begin.push_back(static_cast<std::uint32_t>(cr->agreeing.ids.size()));
    if (whole)
      cr->whole[static_cast<std::size_t>(cx)] = cell_agrees_whole(top, bottom, cx, cell_px, tolerance,
                                                                  cr->begin.back() - first,
                                                                  &cr->chains[static_cast<std::size_t>(cx)]);
  }
}

// Anchor and cell rows a band has finished with, kept with their buffers'
// capacity for the next band's rows: a row begun from empty vectors grows them
// by reallocation, every new block copied into and first touched page by page
// (6-8 % of a render's time with the grid, in the kernel's page faults and in
// memcpy).
template <class Row>
class SpareRows {
 public:
  // rows[first, end) take spare rows (empty, their capacity kept) while any are left.
  void reuse(std::vector<Row>* rows, int first, int end) {
    for (int i = first; i < end && !spare_.empty(); ++i) {
      (*rows)[static_cast<std::size_t>(i)] = std::move(spare_.back());
      spare_.pop_back();
    }
  }
  // rows[i] is read no more.
  void release(std::vector<Row>* rows, int i) {
    Row& r = (*rows)[static_cast<std::size_t>(i)];
    r.clear();
    spare_.push_back(std::move(r));
    r = Row{};
  }

 private:
  std::vector<Row> spare_;
};

// The coarse level of TraceOptions::reflection_grid_levels 2: anchors every
// 2g samples (traced whole), their cells compared.
struct CoarseGrid {
  SampleLattice lattice;
  std::vector<AnchorRow> anchors;
  std::vector<CellRow> cells;
};

// Where fine anchor index a (of the fine grid) lies on the coarse grid: its
// coarse cell and the fraction across it (a coarse anchor: a == 2 c, f == 0).
// false where no coarse cell holds it (beyond the last coarse anchor).
bool coarse_cell_of(int a, int coarse_cells, int* cell, double* f) {
  *cell = a / 2;
  *f = (a % 2) * 0.5;
  if (*cell >= coarse_cells && a % 2 == 0 && *cell > 0) {  // on the last coarse anchor: the cell before, far side
    *cell -= 1;
    *f = 1;
  }
  return *cell < coarse_cells;
}

// Fine anchor row ay with the coarse level: coarse anchors copied, every other
// anchor interpolated whole where its coarse cell agrees whole, else traced.
void fill_anchor_row_from_coarse(const TraceScene& scene, const SceneIndex& index, const CameraModel& camera,
                                 const RigidTransform& camera_from_world, const TraceOptions& options,
                                 const SampleLattice& lattice, const CoarseGrid& coarse, int ay, AnchorRow* out,
                                 RowStats* stats) {
  thread_local TraceResult r;
  thread_local std::vector<Eigen::Vector2d> pixels;
  thread_local std::vector<std::optional<CameraRay>> rays;
  thread_local std::vector<const SubtreeCorners*> deferred_list;
  const double inv_samples = 1.0 / (static_cast<double>(lattice.k) * lattice.k);
  const double coarse_cell_px = static_cast<double>(coarse.lattice.g) / lattice.k;
  const int cells_x = coarse.lattice.cells_x(), cells_y = coarse.lattice.cells_y();
  // What anchor ax is: a coarse anchor, interpolated (its cell and place in it), or traced.
  struct Place {
    int cx = 0, cy = 0;
    double fx = 0, fy = 0;
    bool in_cell = false, whole = false;
  };
  const auto place = [&](int ax) {
    Place p;
    p.in_cell = coarse_cell_of(ax, cells_x, &p.cx, &p.fx) && coarse_cell_of(ay, cells_y, &p.cy, &p.fy);
    p.whole = p.in_cell && coarse.cells[static_cast<std::size_t>(p.cy)].agrees_whole(p.cx);
    return p;
  };
  const auto is_coarse = [&](int ax) { return ax % 2 == 0 && ay % 2 == 0; };
  pixels.clear();
  for (int ax = 0; ax < lattice.anchors_x; ++ax)
    if (!is_coarse(ax) && !place(ax).whole) pixels.push_back(lattice.pixel(ax * lattice.g, ay * lattice.g));
  CameraRayWarmStart warm;
  pixel_camera_rays(camera, camera_from_world, pixels, &rays, &warm);
  std::size_t next_ray = 0;
  for (int ax = 0; ax < lattice.anchors_x; ++ax) {
    if (is_coarse(ax)) {  // traced (and counted) in its coarse row
      out->add_copy(coarse.anchors[static_cast<std::size_t>(ay / 2)], ax / 2);
      continue;
    }
    const Place p = place(ax);
    if (p.whole) {
      const CellRow& cr = coarse.cells[static_cast<std::size_t>(p.cy)];
      const auto cx = static_cast<std::size_t>(p.cx);
      const std::uint32_t first = cr.begin[cx], count = cr.begin[cx + 1] - first;
      out->add_interpolated(cr.chains[cx], cr.agreeing.corners.data() + first, count, coarse_cell_px, p.fx, p.fy,
                            coarse.anchors[static_cast<std::size_t>(p.cy)].met_solid(p.cx));
      const SubtreeRecord* chain = out->chain(out->size() - 1);
      stats->cut_weight += chain->cut;
      stats->interpolated += static_cast<long>(count);
      ++stats->samples_interpolated;
      continue;
    }
    const std::optional<CameraRay>& ray = rays[next_ray++];
    if (!ray) {
      ++stats->unproject_failures;
      out->add(nullptr, inv_samples);
      continue;
    }
    // In a coarse cell that does not agree whole, the subtrees that agree in
    // it are deferred and interpolated, as for a sample between anchors.
    DeferredSubtrees deferred;
    const SubtreeCorners* corners = nullptr;
    if (p.in_cell) deferred = coarse.cells[static_cast<std::size_t>(p.cy)].deferred(p.cx, &corners);
    trace_ray(scene, index, *ray, options, &r, deferred);
    stats->add(r, inv_samples);
    out->add(&r, inv_samples);
    if (r.deferred.empty()) continue;
    deferred_corners(r.deferred, deferred, corners, &deferred_list);
    stats->cut_weight +=
        out->append_interpolated_subtrees(deferred_list.data(), deferred_list.size(), coarse_cell_px, p.fx, p.fy);
    stats->interpolated += static_cast<long>(r.deferred.size());
  }
}

// A pixel row with the reflection grid: anchors from their rows; every other
// sample traced with the subtrees that agree in its cell deferred, and those
// interpolated.
void trace_row_on_grid(const TraceScene& scene, const SceneIndex& index, const CameraModel& camera,
                       const RigidTransform& camera_from_world, const TraceOptions& options,
                       const SampleLattice& lattice, const std::vector<AnchorRow>& anchors,
                       const std::vector<CellRow>& cells, int row, const PixelArrays& pixel_arrays, RowBuffer* out,
                       CrossingSink* sink) {
  thread_local TraceResult r;
  thread_local RowCrossings scratch;
  thread_local std::vector<Eigen::Vector2d> pixels;
  thread_local std::vector<std::optional<CameraRay>> rays;
  thread_local std::vector<GridCrossing> interpolated;
  thread_local std::vector<const SubtreeCorners*> deferred_list;
  scratch.clear();
  const int width = camera.width_px(), k = lattice.k, g = lattice.g;
  const double inv_samples = 1.0 / (static_cast<double>(k) * k);
  const double cell_px = static_cast<double>(g) / k;
  // A sample is traced unless it is an anchor or its cell agrees whole.
  const auto interpolated_whole = [&](int x, int y) {
    return lattice.in_cell(x, y) && cells[static_cast<std::size_t>(y / g)].agrees_whole(x / g);
  };
  pixels.clear();
  for (int col = 0; col < width; ++col)
    for (int sy = 0; sy < k; ++sy)
      for (int sx = 0; sx < k; ++sx) {
        const int x = col * k + sx, y = row * k + sy;
        if (!lattice.is_anchor(x, y) && !interpolated_whole(x, y)) pixels.push_back(lattice.pixel(x, y));
      }
  CameraRayWarmStart warm;
  pixel_camera_rays(camera, camera_from_world, pixels, &rays, &warm);
  std::size_t next_ray = 0;
  out->start_row(pixel_arrays, row);
  for (int col = 0; col < width; ++col) {
    PixelSums pixel;
    for (int sy = 0; sy < k; ++sy) {
      for (int sx = 0; sx < k; ++sx) {
        const int x = col * k + sx, y = row * k + sy;
        if (lattice.is_anchor(x, y)) {  // traced whole in its anchor row
          const AnchorRow& a = anchors[static_cast<std::size_t>(y / g)];
          const int i = x / g;
          pixel.add_crossings(a.crossings(i), static_cast<std::size_t>(a.crossing_count(i)), &scratch);
          pixel.background += a.background(i);
          pixel.opaque += a.opaque(i);
          pixel.any_hit = pixel.any_hit || a.met_solid(i);
          continue;
        }
        const double fx = static_cast<double>(x % g) / g, fy = static_cast<double>(y % g) / g;
        if (interpolated_whole(x, y)) {
          const CellRow& cr = cells[static_cast<std::size_t>(y / g)];
          const auto cx = static_cast<std::size_t>(x / g);
          interpolated.clear();
          // The chain's record carries the whole trace's escaped, opaque and cut light.
          double cut = 0, unused = 0;
          interpolate_subtree(cr.chains[cx], cell_px, fx, fy, &interpolated, &pixel.background, &pixel.opaque, &cut);
          for (std::uint32_t j = cr.begin[cx]; j < cr.begin[cx + 1]; ++j)
            interpolate_subtree(cr.agreeing.corners[j], cell_px, fx, fy, &interpolated, &unused, &unused, &unused);
          pixel.add_crossings(interpolated.data(), interpolated.size(), &scratch);
          pixel.any_hit = pixel.any_hit || anchors[static_cast<std::size_t>(y / g)].met_solid(x / g);  // as all four
          out->stats.cut_weight += cut;
          out->stats.interpolated += static_cast<long>(cr.begin[cx + 1] - cr.begin[cx]);
          ++out->stats.samples_interpolated;
          continue;
        }
        const std::optional<CameraRay>& ray = rays[next_ray++];
        if (!ray) {
          ++out->stats.unproject_failures;
          continue;
        }
        DeferredSubtrees deferred;
        const SubtreeCorners* corners = nullptr;
        if (lattice.in_cell(x, y)) deferred = cells[static_cast<std::size_t>(y / g)].deferred(x / g, &corners);
        trace_ray(scene, index, *ray, options, &r, deferred);
        out->stats.add(r, inv_samples);
        pixel.add_traced(r, inv_samples, &scratch);
        if (r.deferred.empty()) continue;
        deferred_corners(r.deferred, deferred, corners, &deferred_list);
        interpolated.clear();
        double cut = 0;
        for (const SubtreeCorners* c : deferred_list)
          interpolate_subtree(*c, cell_px, fx, fy, &interpolated, &pixel.background, &pixel.opaque, &cut);
        pixel.add_crossings(interpolated.data(), interpolated.size(), &scratch);
        out->stats.cut_weight += cut;
        out->stats.interpolated += static_cast<long>(r.deferred.size());
      }
    }
    pixel.store(col, out);
  }
  sink->commit(row, &scratch);
}

// The anchor rows pixel row `row` reads: [first, last].
std::pair<int, int> anchor_rows_of(const SampleLattice& lattice, int row) {
  const int first = row * lattice.k / lattice.g;
  const int last = std::min((row * lattice.k + lattice.k - 1) / lattice.g + 1, lattice.anchors_y - 1);
  return {first, last};
}

// The rows of a map: traced sample by sample, or with the reflection grid.
std::vector<RowBuffer> trace_rows(const TraceScene& scene, const SceneIndex& index, const CameraModel& camera,
                                  const RigidTransform& camera_from_world, const TraceOptions& options, int k,
                                  const PixelArrays& pixels, CrossingSink* sink, int* threads, std::vector<RowStats>* anchor_stats,
                                  const std::function<void(int, int)>& progress) {
  const int height = camera.height_px();
  std::vector<RowBuffer> rows(static_cast<std::size_t>(height));
  if (!reflection_grid_in_effect(options)) {
    // trace_ray throws only for non-finite rays, which pixel_camera_ray never produces.
    *threads = parallel_rows(
        height, *threads,
        [&](int row) {
          trace_row(scene, index, camera, camera_from_world, options, k, row, pixels,
                    &rows[static_cast<std::size_t>(row)], sink);
        },
        progress);
    return rows;
  }
  const SampleLattice lattice(camera.width_px(), height, k, options.reflection_grid);
  const int anchor_rows = lattice.anchors_y;
  std::vector<AnchorRow> anchors(static_cast<std::size_t>(anchor_rows));
  std::vector<CellRow> cells(static_cast<std::size_t>(anchor_rows));
  anchor_stats->assign(static_cast<std::size_t>(anchor_rows), RowStats{});
  const double cell_px = static_cast<double>(lattice.g) / k;
  GridTolerance tolerance;
  tolerance.relative = options.reflection_grid_tolerance;
  // Every branch of a subtree has been reflected: cut at the reflected cut-off.
  tolerance.weight_floor = std::max(options.min_weight, options.min_weight_reflected) / (static_cast<double>(k) * k);
  // Progress in pixel rows, as without the grid: anchor rows and pixel rows
  // counted alike and scaled to the image's rows.
  int reported = 0;
  const auto report = [&]() -> std::function<void(int, int)> {
    if (!progress) return {};
    return [&progress, &reported, height, total = static_cast<long>(anchor_rows) + height](int done, int) {
      progress(static_cast<int>((reported + done) * static_cast<long>(height) / total), height);
    };
  };
  const int requested_threads = *threads;
  *threads = 0;
  // A band of pixel rows at a time: its anchor rows traced, their cells
  // compared, its rows traced, and the anchor rows no later band reads freed
  // (their buffers kept for the next band's), so that the anchors never all
  // wait beside the finished rows.
  constexpr int kBandRows = 64;
  SpareRows<AnchorRow> spare_anchors;
  SpareRows<CellRow> spare_cells;
  int anchors_traced = 0, cells_compared = 0, anchors_freed = 0;
  // TraceOptions::reflection_grid_levels 2: the coarse grid the anchors come from.
  std::unique_ptr<CoarseGrid> coarse;
  std::vector<RowStats> coarse_stats;
  int coarse_traced = 0, coarse_compared = 0, coarse_freed = 0;
  const double coarse_cell_px = 2.0 * lattice.g / k;
  if (options.reflection_grid_levels > 1) {
    coarse = std::make_unique<CoarseGrid>(CoarseGrid{SampleLattice(camera.width_px(), height, k, 2 * lattice.g), {}, {}});
    coarse->anchors.resize(static_cast<std::size_t>(coarse->lattice.anchors_y));
    coarse->cells.resize(static_cast<std::size_t>(coarse->lattice.anchors_y));
    coarse_stats.assign(static_cast<std::size_t>(coarse->lattice.anchors_y), RowStats{});
  }
  for (int first_row = 0; first_row < height; first_row += kBandRows) {
    const int end_row = std::min(height, first_row + kBandRows);
    const int anchors_needed = anchor_rows_of(lattice, end_row - 1).second + 1;
    const int first_anchor = anchors_traced;
    if (coarse) {
      // The coarse rows and cells the band's fine anchor rows read.
      const int coarse_needed = std::min(coarse->lattice.anchors_y, (anchors_needed - 1) / 2 + 2);
      const int first_coarse = coarse_traced;
      spare_anchors.reuse(&coarse->anchors, first_coarse, coarse_needed);
      parallel_rows(coarse_needed - first_coarse, requested_threads, [&](int i) {
        const auto cy = static_cast<std::size_t>(first_coarse + i);
        trace_anchor_row(scene, index, camera, camera_from_world, options, coarse->lattice, first_coarse + i,
                         &coarse->anchors[cy], &coarse_stats[cy]);
      });
      coarse_traced = coarse_needed;
      const int first_cell = coarse_compared, cells_end = std::min(coarse_needed - 1, coarse->lattice.cells_y());
      spare_cells.reuse(&coarse->cells, first_cell, cells_end);
      parallel_rows(std::max(cells_end - first_cell, 0), requested_threads, [&](int i) {
        const auto cy = static_cast<std::size_t>(first_cell + i);
        compare_cell_row(coarse->anchors[cy], coarse->anchors[cy + 1], coarse->lattice.cells_x(), coarse_cell_px,
                         tolerance, true, &coarse->cells[cy]);
      });
      coarse_compared = std::max(cells_end, first_cell);
    }
    spare_anchors.reuse(&anchors, first_anchor, anchors_needed);
    parallel_rows(
        anchors_needed - first_anchor, requested_threads,
        [&](int i) {
          const auto ay = static_cast<std::size_t>(first_anchor + i);
          if (coarse)
            fill_anchor_row_from_coarse(scene, index, camera, camera_from_world, options, lattice, *coarse,
                                        first_anchor + i, &anchors[ay], &(*anchor_stats)[ay]);
          else
            trace_anchor_row(scene, index, camera, camera_from_world, options, lattice, first_anchor + i,
                             &anchors[ay], &(*anchor_stats)[ay]);
        },
        report());
    reported += anchors_needed - first_anchor;
    anchors_traced = anchors_needed;
    const int first_cell = cells_compared, cells_end = std::min(anchors_needed - 1, lattice.cells_y());
    spare_cells.reuse(&cells, first_cell, cells_end);
    parallel_rows(std::max(cells_end - first_cell, 0), requested_threads, [&](int i) {
      const auto cy = static_cast<std::size_t>(first_cell + i);
      compare_cell_row(anchors[cy], anchors[cy + 1], lattice.cells_x(), cell_px, tolerance, options.grid_whole_samples,
                       &cells[cy]);
    });
    cells_compared = std::max(cells_end, first_cell);
    *threads = std::max(*threads, parallel_rows(
                                      end_row - first_row, requested_threads,
                                      [&](int i) {
                                        trace_row_on_grid(scene, index, camera, camera_from_world, options, lattice,
                                                          anchors, cells, first_row + i, pixels,
                                                          &rows[static_cast<std::size_t>(first_row + i)], sink);
                                      },
                                      report()));
    reported += end_row - first_row;
    const int still_read = end_row < height ? anchor_rows_of(lattice, end_row).first : anchor_rows;
    for (; anchors_freed < still_read; ++anchors_freed) {
      spare_anchors.release(&anchors, anchors_freed);
      spare_cells.release(&cells, anchors_freed);
    }
    // Fine anchor rows from anchors_traced on read coarse cell rows from
    // anchors_traced / 2 - 1 on (coarse_cell_of).
    if (coarse)
      for (; coarse_freed < std::min(anchors_traced / 2 - 1, coarse_traced); ++coarse_freed) {
        spare_anchors.release(&coarse->anchors, coarse_freed);
        spare_cells.release(&coarse->cells, coarse_freed);
      }
  }
  for (const RowStats& st : coarse_stats) anchor_stats->push_back(st);
  return rows;
}

}  // namespace

TransportMap build_transport_map(const TraceScene& scene, const CameraModel& camera,
                                 const RigidTransform& camera_from_world, const TraceOptions& options,
                                 int samples_per_axis, int threads, const std::function<void(int, int)>& progress) {
  if (samples_per_axis < 1) throw std::invalid_argument("build_transport_map: samples_per_axis must be >= 1");
  const int width = camera.width_px(), height = camera.height_px();

  if (options.reflection_grid < 1)
    throw std::invalid_argument("build_transport_map: reflection_grid must be >= 1");
  if (!(options.reflection_grid_tolerance >= 0) || !std::isfinite(options.reflection_grid_tolerance))
    throw std::invalid_argument("build_transport_map: reflection_grid_tolerance must be finite and >= 0");
  if (options.reflection_grid_levels < 1 || options.reflection_grid_levels > 2)
    throw std::invalid_argument("build_transport_map: reflection_grid_levels must be 1 or 2");

  const std::unique_ptr<SceneIndex> index = make_scene_index(scene);
  TransportMap map;
  map.width = width;
  map.height = height;
  map.samples_per_axis = samples_per_axis;
  // The per-pixel arrays at their final size: the rows write their entries
  // there (no row copies, no second pass over them).
  const std::size_t pixel_count = map.pixel_count();
  reserve_huge(&map.pixel_offsets, pixel_count + 1);
  reserve_huge(&map.background_weight, pixel_count);
  reserve_huge(&map.opaque_weight, pixel_count);
  map.pixel_offsets.resize(pixel_count + 1);
  map.background_weight.resize(pixel_count);
  map.opaque_weight.resize(pixel_count);
  PixelArrays pixels;
  pixels.counts = map.pixel_offsets.data() + 1;
  pixels.background = map.background_weight.data();
  pixels.opaque = map.opaque_weight.data();
  pixels.width = width;
  std::vector<RowStats> anchor_stats;  // the reflection grid's anchor rows
  CrossingSink sink(height);
  const std::vector<RowBuffer> rows = trace_rows(scene, *index, camera, camera_from_world, options, samples_per_axis,
                                                 pixels, &sink, &threads, &anchor_stats, progress);

  map.stats.threads = threads;
  const std::size_t total = sink.size();
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw std::overflow_error("build_transport_map: more than 2^32 - 1 crossings");
  // Counts to offsets (no overflow: the sum is total).
  std::uint32_t offset = 0;
  for (std::size_t p = 1; p <= pixel_count; ++p) map.pixel_offsets[p] = offset += map.pixel_offsets[p];
  sink.move_into(&map, threads);
  for (const RowBuffer& rb : rows) rb.stats.add_to(&map.stats);
  for (const RowStats& st : anchor_stats) st.add_to(&map.stats);
  map.stats.crossings = static_cast<long>(total);
  return map;
}

}  // namespace glasspiv
