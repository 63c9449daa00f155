#include "render/reflection_grid.h"

#include <algorithm>
#include <cmath>

namespace glasspiv {

GridCrossing grid_crossing(const SheetCrossing& c, double scale) {
  GridCrossing g;
  g.path = c.path;
  g.s_mm = static_cast<float>(c.s_mm);
  g.t_mm = static_cast<float>(c.t_mm);
  g.weight = static_cast<float>(c.weight * scale);
  g.ds_dcol = static_cast<float>(c.dst_dpixel(0, 0));
  g.ds_drow = static_cast<float>(c.dst_dpixel(0, 1));
  g.dt_dcol = static_cast<float>(c.dst_dpixel(1, 0));
  g.dt_drow = static_cast<float>(c.dst_dpixel(1, 1));
  g.tag = static_cast<std::uint8_t>(c.tag);
  return g;
}

void AnchorRow::clear() {
  begin_.assign(1, 0);
  subtree_begin_.assign(1, 0);
  crossings_.clear();
  subtrees_.clear();
  background_.clear();
  opaque_.clear();
  met_solid_.clear();
  chain_.clear();
  chain_ok_.clear();
}

void AnchorRow::add(const TraceResult* r, double scale) {
  const std::uint32_t first_crossing = static_cast<std::uint32_t>(crossings_.size());
  const std::size_t first_subtree = subtrees_.size();
  double background = 0, opaque = 0;
  SubtreeRecord chain;
  chain.weight = 1;
  bool chain_ok = r != nullptr;
  if (r) {
    for (const ReflectedSubtree& st : r->subtrees) {
      SubtreeRecord& rec = subtrees_.emplace_back();
      rec.id = st.id;
      rec.weight = static_cast<float>(st.weight);
      rec.background = static_cast<float>(st.background_weight * scale);
      rec.opaque = static_cast<float>(st.opaque_weight * scale);
      rec.cut = static_cast<float>(st.cut_weight * scale);
    }
    // Each subtree's crossings are contiguous in the tracer's order (it
    // follows a branch's descendants before popping an older branch).
    bool contiguous = true;
    int previous = -1;
    for (const SheetCrossing& c : r->crossings) {
      const std::uint32_t index = static_cast<std::uint32_t>(crossings_.size()) - first_crossing;
      crossings_.push_back(grid_crossing(c, scale));
      if (c.subtree < 0) {
        // The refracted chain's crossings come first (the tracer's order).
        if (index != chain.count) chain_ok = false;
        ++chain.count;
        previous = -1;
        continue;
      }
      SubtreeRecord& rec = subtrees_[first_subtree + static_cast<std::size_t>(c.subtree)];
      if (rec.count == 0) {
        rec.first = index;
      } else if (previous != c.subtree) {
        contiguous = false;
      }
      ++rec.count;
      previous = c.subtree;
    }
    if (!contiguous) {  // never seen: such an anchor's subtrees are traced
      subtrees_.resize(first_subtree);
      chain_ok = false;
    }
    background = r->background_weight * scale;
    opaque = r->opaque_weight * scale;
    chain.background = static_cast<float>(background);
    chain.opaque = static_cast<float>(opaque);
    chain.cut = static_cast<float>((r->cut_by_weight_weight + r->cut_by_depth_weight + r->skipped_reflection_weight) * scale);
  }
  chain_.push_back(chain);
  chain_ok_.push_back(chain_ok);
  begin_.push_back(static_cast<std::uint32_t>(crossings_.size()));
  subtree_begin_.push_back(static_cast<std::uint32_t>(subtrees_.size()));
  background_.push_back(background);
  opaque_.push_back(opaque);
  met_solid_.push_back(r && r->met_solid());
}

void AnchorRow::add_copy(const AnchorRow& from, int i) {
  crossings_.insert(crossings_.end(), from.crossings(i), from.crossings(i) + from.crossing_count(i));
  subtrees_.insert(subtrees_.end(), from.subtrees(i), from.subtrees(i) + from.subtree_count(i));
  chain_.push_back(from.chain_[at(i)]);
  chain_ok_.push_back(from.chain_ok_[at(i)]);
  begin_.push_back(static_cast<std::uint32_t>(crossings_.size()));
  subtree_begin_.push_back(static_cast<std::uint32_t>(subtrees_.size()));
  background_.push_back(from.background_[at(i)]);
  opaque_.push_back(from.opaque_[at(i)]);
  met_solid_.push_back(from.met_solid_[at(i)]);
}

namespace {

// The subtree of `corners` interpolated at (fx, fy), appended to crossings as
// a record whose crossings start `first` crossings after the anchor's first.
SubtreeRecord interpolated_record(const SubtreeCorners& corners, double cell_px, double fx, double fy,
                                  std::vector<GridCrossing>* crossings, std::size_t anchor_first) {
  SubtreeRecord rec;
  rec.id = corners.record[0]->id;
  const double beta[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
  double weight = 0, b = 0, o = 0, c = 0;
  for (int i = 0; i < 4; ++i) weight += beta[i] * corners.record[i]->weight;
  rec.weight = static_cast<float>(weight);
  rec.first = static_cast<std::uint32_t>(crossings->size() - anchor_first);
  interpolate_subtree(corners, cell_px, fx, fy, crossings, &b, &o, &c);
  rec.count = static_cast<std::uint32_t>(crossings->size() - anchor_first) - rec.first;
  rec.background = static_cast<float>(b);
  rec.opaque = static_cast<float>(o);
  rec.cut = static_cast<float>(c);
  return rec;
}

}  // namespace

void AnchorRow::add_interpolated(const SubtreeCorners& chain, const SubtreeCorners* subtrees, std::size_t count,
                                 double cell_px, double fx, double fy, bool met_solid) {
  const std::size_t first_crossing = crossings_.size();
  double background = 0, opaque = 0, cut = 0;
  interpolate_subtree(chain, cell_px, fx, fy, &crossings_, &background, &opaque, &cut);
  SubtreeRecord chain_record;
  chain_record.weight = 1;
  chain_record.background = static_cast<float>(background);
  chain_record.opaque = static_cast<float>(opaque);
  chain_record.cut = static_cast<float>(cut);
  chain_record.count = static_cast<std::uint32_t>(crossings_.size() - first_crossing);
  for (std::size_t j = 0; j < count; ++j)
    subtrees_.push_back(interpolated_record(subtrees[j], cell_px, fx, fy, &crossings_, first_crossing));
  chain_.push_back(chain_record);
  chain_ok_.push_back(1);
  begin_.push_back(static_cast<std::uint32_t>(crossings_.size()));
  subtree_begin_.push_back(static_cast<std::uint32_t>(subtrees_.size()));
  background_.push_back(background);
  opaque_.push_back(opaque);
  met_solid_.push_back(met_solid);
}

double AnchorRow::append_interpolated_subtrees(const SubtreeCorners* const* subtrees, std::size_t count,
                                             double cell_px, double fx, double fy) {
  const std::size_t first_crossing = begin_[begin_.size() - 2];
  SubtreeRecord& chain = chain_.back();
  double cut = 0;
  for (std::size_t j = 0; j < count; ++j) {
    const SubtreeRecord rec = interpolated_record(*subtrees[j], cell_px, fx, fy, &crossings_, first_crossing);
    subtrees_.push_back(rec);
    // The whole trace's light (the anchor's and its chain record's) takes the subtree's.
    background_.back() += rec.background;
    opaque_.back() += rec.opaque;
    chain.background += rec.background;
    chain.opaque += rec.opaque;
    chain.cut += rec.cut;
    cut += rec.cut;
  }
  begin_.back() = static_cast<std::uint32_t>(crossings_.size());
  subtree_begin_.back() = static_cast<std::uint32_t>(subtrees_.size());
  return cut;
}

const SubtreeRecord* AnchorRow::find_subtree(int i, std::uint64_t id) const {
  const SubtreeRecord* begin = subtrees(i);
  const SubtreeRecord* end = begin + subtree_count(i);
  const SubtreeRecord* found = std::find_if(begin, end, [id](const SubtreeRecord& s) { return s.id == id; });
  return found == end ? nullptr : found;
}

bool subtree_corners(const AnchorRow& top, const AnchorRow& bottom, int col, std::uint64_t id, SubtreeCorners* out) {
  const AnchorRow* rows[4] = {&top, &top, &bottom, &bottom};
  for (int i = 0; i < 4; ++i) {
    const int anchor = col + (i & 1);
    out->record[i] = rows[i]->find_subtree(anchor, id);
    if (!out->record[i]) return false;
    out->crossings[i] = rows[i]->crossings(anchor) + out->record[i]->first;
  }
  return true;
}

namespace {

// Weights equal to within `relative` of the larger or within `floor`; a
// further 1e-9 keeps two zeros (or float dust) equal.
bool weights_close(double a, double b, double relative, double floor) {
  return std::abs(a - b) <= std::max(relative * std::max(std::abs(a), std::abs(b)), floor) + 1e-9;
}

double footprint_mm(const GridCrossing& c) {
  return std::sqrt(std::abs(static_cast<double>(c.ds_dcol) * c.dt_drow - static_cast<double>(c.ds_drow) * c.dt_dcol));
}

// b's position predicted from a's, (dcol, drow) pixels away.
bool predicts(const GridCrossing& a, const GridCrossing& b, double dcol, double drow, double tolerance) {
  const double s = a.s_mm + a.ds_dcol * dcol + a.ds_drow * drow;
  const double t = a.t_mm + a.dt_dcol * dcol + a.dt_drow * drow;
  const double miss = std::hypot(s - b.s_mm, t - b.t_mm);
  const double footprint = std::min(footprint_mm(a), footprint_mm(b));
  return std::isfinite(miss) && footprint > 0 && miss <= tolerance * footprint;
}

// The cell's edges as (corner, corner, dcol, drow) in units of the cell side.
struct Edge {
  int a, b;
  double dcol, drow;
};
constexpr Edge kEdges[] = {{0, 1, 1, 0}, {2, 3, 1, 0}, {0, 2, 0, 1}, {1, 3, 0, 1}};

}  // namespace

bool subtree_agrees(const SubtreeCorners& corners, double cell_px, const GridTolerance& tolerance) {
  const std::uint32_t count = corners.record[0]->count;
  for (const SubtreeRecord* r : corners.record)
    if (r->count != count) return false;
  for (const Edge& e : kEdges) {
    const SubtreeRecord &ra = *corners.record[e.a], &rb = *corners.record[e.b];
    if (!weights_close(ra.weight, rb.weight, tolerance.relative, 0)) return false;
    if (!weights_close(ra.background, rb.background, tolerance.relative, tolerance.weight_floor) ||
        !weights_close(ra.opaque, rb.opaque, tolerance.relative, tolerance.weight_floor))
      return false;
    const double dcol = e.dcol * cell_px, drow = e.drow * cell_px;
    for (std::uint32_t m = 0; m < count; ++m) {
      const GridCrossing &a = corners.crossings[e.a][m], &b = corners.crossings[e.b][m];
      if (a.path != b.path || !weights_close(a.weight, b.weight, tolerance.relative, 0) ||
          !predicts(a, b, dcol, drow, tolerance.relative) || !predicts(b, a, -dcol, -drow, tolerance.relative))
        return false;
    }
  }
  return true;
}

void agreeing_subtrees(const AnchorRow& top, const AnchorRow& bottom, int col, double cell_px,
                       const GridTolerance& tolerance, AgreeingSubtrees* out) {
  const SubtreeRecord* own = top.subtrees(col);
  for (int j = 0; j < top.subtree_count(col); ++j) {
    SubtreeCorners corners;
    if (!subtree_corners(top, bottom, col, own[j].id, &corners) || !subtree_agrees(corners, cell_px, tolerance))
      continue;
    double lo = corners.record[0]->weight, hi = lo;
    for (const SubtreeRecord* r : corners.record) {
      lo = std::min(lo, static_cast<double>(r->weight));
      hi = std::max(hi, static_cast<double>(r->weight));
    }
    out->ids.push_back(own[j].id);
    out->corners.push_back(corners);
    out->min_weight.push_back(lo * (1 - tolerance.relative));
    out->max_weight.push_back(hi * (1 + tolerance.relative));
  }
}

bool cell_agrees_whole(const AnchorRow& top, const AnchorRow& bottom, int col, double cell_px,
                       const GridTolerance& tolerance, std::size_t agreeing, SubtreeCorners* chain) {
  const AnchorRow* rows[4] = {&top, &top, &bottom, &bottom};
  for (int i = 0; i < 4; ++i) {
    const int anchor = col + (i & 1);
    chain->record[i] = rows[i]->chain(anchor);
    if (!chain->record[i] || rows[i]->met_solid(anchor) != top.met_solid(col) ||
        static_cast<std::size_t>(rows[i]->subtree_count(anchor)) != agreeing)
      return false;
    chain->crossings[i] = rows[i]->crossings(anchor);
  }
  return subtree_agrees(*chain, cell_px, tolerance);
}

namespace {

// Cubic Hermite interpolation at f in [0, 1] between values v0, v1 with
// derivatives d0, d1 per unit of h: exact for polynomials of degree 3.
double hermite(double f, double v0, double v1, double d0, double d1, double h) {
  const double f2 = f * f, f3 = f2 * f;
  return (2 * f3 - 3 * f2 + 1) * v0 + (f3 - 2 * f2 + f) * h * d0 + (3 * f2 - 2 * f3) * v1 + (f3 - f2) * h * d1;
}

// One coordinate over the cell from the corners' values and derivatives along
// columns and rows: Hermite along one axis on the two edges (the other axis's
// derivative interpolated linearly there), then Hermite across; the mean of
// the two orders, so that neither axis is favoured. Exact for quadratics.
double patch(const double (&v)[4], const double (&dcol)[4], const double (&drow)[4], double fx, double fy,
             double cell_px) {
  const double top = hermite(fx, v[0], v[1], dcol[0], dcol[1], cell_px);
  const double bottom = hermite(fx, v[2], v[3], dcol[2], dcol[3], cell_px);
  const double rows_first = hermite(fy, top, bottom, drow[0] + fx * (drow[1] - drow[0]),
                                    drow[2] + fx * (drow[3] - drow[2]), cell_px);
  const double left = hermite(fy, v[0], v[2], drow[0], drow[2], cell_px);
  const double right = hermite(fy, v[1], v[3], drow[1], drow[3], cell_px);
  const double cols_first = hermite(fx, left, right, dcol[0] + fy * (dcol[2] - dcol[0]),
                                    dcol[1] + fy * (dcol[3] - dcol[1]), cell_px);
  return 0.5 * (rows_first + cols_first);
}

}  // namespace

void interpolate_subtree(const SubtreeCorners& corners, double cell_px, double fx, double fy,
                         std::vector<GridCrossing>* out, double* background, double* opaque, double* cut) {
  const double beta[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
  for (std::uint32_t m = 0; m < corners.record[0]->count; ++m) {
    double s[4], t[4], ds_dcol[4], ds_drow[4], dt_dcol[4], dt_drow[4];
    double w = 0;
    for (int i = 0; i < 4; ++i) {
      const GridCrossing& c = corners.crossings[i][m];
      s[i] = c.s_mm;
      t[i] = c.t_mm;
      ds_dcol[i] = c.ds_dcol;
      ds_drow[i] = c.ds_drow;
      dt_dcol[i] = c.dt_dcol;
      dt_drow[i] = c.dt_drow;
      w += beta[i] * c.weight;
    }
    const auto blend = [&](const double (&v)[4]) { return beta[0] * v[0] + beta[1] * v[1] + beta[2] * v[2] + beta[3] * v[3]; };
    GridCrossing& g = out->emplace_back(corners.crossings[0][m]);  // path and tag
    g.s_mm = static_cast<float>(patch(s, ds_dcol, ds_drow, fx, fy, cell_px));
    g.t_mm = static_cast<float>(patch(t, dt_dcol, dt_drow, fx, fy, cell_px));
    g.weight = static_cast<float>(w);
    g.ds_dcol = static_cast<float>(blend(ds_dcol));
    g.ds_drow = static_cast<float>(blend(ds_drow));
    g.dt_dcol = static_cast<float>(blend(dt_dcol));
    g.dt_drow = static_cast<float>(blend(dt_drow));
  }
  // The sums in locals: through the three pointers, which may alias for all
  // the compiler knows, every term was a store and a reload.
  double b = *background, o = *opaque, c = *cut;
  for (int i = 0; i < 4; ++i) {
    b += beta[i] * corners.record[i]->background;
    o += beta[i] * corners.record[i]->opaque;
    c += beta[i] * corners.record[i]->cut;
  }
  *background = b;
  *opaque = o;
  *cut = c;
}

}  // namespace glasspiv
