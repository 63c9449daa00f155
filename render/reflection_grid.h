#pragma once
// Reflected light on a coarser grid of camera samples (TraceOptions::
// reflection_grid, docs/tracer.md). Ghost light carries a few per cent of a
// pixel's weight but, with its Fresnel trees, most of a map's segments. The
// transport map traces it whole on every g-th sample of each axis only (the
// anchors); every other sample traces its own refracted chain, which carries
// most of the light, and takes those of its reflected subtrees
// (ReflectedSubtree) that agree among the four anchors around it (its cell)
// from them, interpolated; the others it traces.
//
// A subtree agrees in a cell when all four anchors have it (the same id: their
// refracted chains met the same surfaces up to its reflection), with weights
// at the reflection within `tolerance` relative, and with the same
// crossings (the same paths, in the same order), each anchor's crossing
// predicted from its edge neighbour's position and footprint Jacobian to
// within `tolerance` of a footprint (the square root of |det J|, the smaller
// of the two), each crossing's weight equal to within `tolerance` relative,
// and the subtree's light that left the scene or ended on opaque solids equal
// to within `tolerance` relative or within the cut-off of reflected light
// (GridTolerance::weight_floor): those
// sums jump by a cut branch's weight where a branch near the cut-off is
// followed at one anchor and cut at the next, which the tracer's cut-off
// already allows for.
// No I/O.
#include <cstdint>
#include <vector>

#include "render/path_tracer.h"

namespace glasspiv {

// One sheet crossing as the map stores it (float, weight already divided by
// the samples per pixel) and its path.
struct GridCrossing {
  std::uint64_t path = 0;
  float s_mm = 0, t_mm = 0, weight = 0;
  float ds_dcol = 0, ds_drow = 0, dt_dcol = 0, dt_drow = 0;  // mm per pixel
  std::uint8_t tag = 0;
};

// c in the map's float form, its weight times `scale` (1 / samples^2).
GridCrossing grid_crossing(const SheetCrossing& c, double scale);

// One reflected subtree of an anchor (weights in the map's units).
struct SubtreeRecord {
  std::uint64_t id = 0;
  float weight = 0;                  // at the reflection, of the camera ray's unit weight
  float background = 0, opaque = 0;  // its light that left the scene / ended on opaque solids
  float cut = 0;                     // its light cut by weight or depth (statistics only)
  std::uint32_t first = 0, count = 0;  // its crossings among the anchor's
};

struct SubtreeCorners;

// The anchors of one anchor row, in column order: each one's whole trace (what
// the map stores for it) and its subtrees.
class AnchorRow {
 public:
  // Appends the next anchor: r's result with weights times scale, or nullptr
  // for a ray that could not be unprojected.
  void add(const TraceResult* r, double scale);
  // Appends anchor i of `from` (another row's), as it is there.
  void add_copy(const AnchorRow& from, int i);
  // Appends an anchor interpolated whole at (fx, fy) of a coarser cell that
  // agrees whole (cell_agrees_whole): its refracted chain from `chain`'s
  // corners (the whole trace's escaped and opaque light with it), then each of
  // the cell's `count` agreeing subtrees, each a subtree record of its own
  // (weight at the reflection bilinear), as add() would have stored the trace.
  // met_solid: the corners'.
  void add_interpolated(const SubtreeCorners& chain, const SubtreeCorners* subtrees, std::size_t count,
                        double cell_px, double fx, double fy, bool met_solid);
  // Appends to the last anchor the subtrees its trace deferred (`count` of
  // them, each interpolated at (fx, fy) of a coarser cell from its corners),
  // each a subtree record of its own, their light added to the anchor's.
  // Returns their cut light (statistics).
  double append_interpolated_subtrees(const SubtreeCorners* const* subtrees, std::size_t count, double cell_px,
                                    double fx, double fy);
  // Empties the row, keeping its buffers' capacity for the next row.
  void clear();
  int size() const { return static_cast<int>(met_solid_.size()); }
  // Anchor i's crossings, all of them, as traced.
  const GridCrossing* crossings(int i) const { return crossings_.data() + begin_[at(i)]; }
  int crossing_count(int i) const { return static_cast<int>(begin_[at(i) + 1] - begin_[at(i)]); }
  double background(int i) const { return background_[at(i)]; }
  double opaque(int i) const { return opaque_[at(i)]; }
  // Whether anchor i's ray met a solid (for TransportStats::pixels_without_solid_hit).
  bool met_solid(int i) const { return met_solid_[at(i)] != 0; }
  // Anchor i's whole trace as one record for the comparison and interpolation
  // of whole samples (TraceOptions::grid_whole_samples): weight 1, the whole
  // trace's background, opaque and cut light, and its refracted chain's
  // crossings (the first ones); nullptr for an anchor whose ray could not be
  // unprojected or whose crossings were not in the tracer's order.
  const SubtreeRecord* chain(int i) const { return chain_ok_[at(i)] ? &chain_[at(i)] : nullptr; }
  // Anchor i's subtrees, in the order traced; the one with `id`, or nullptr.
  const SubtreeRecord* subtrees(int i) const { return subtrees_.data() + subtree_begin_[at(i)]; }
  int subtree_count(int i) const { return static_cast<int>(subtree_begin_[at(i) + 1] - subtree_begin_[at(i)]); }
  const SubtreeRecord* find_subtree(int i, std::uint64_t id) const;

 private:
  static std::size_t at(int i) { return static_cast<std::size_t>(i); }
  std::vector<std::uint32_t> begin_{0}, subtree_begin_{0};  // per anchor + 1
  std::vector<GridCrossing> crossings_;
  std::vector<SubtreeRecord> subtrees_;
  std::vector<double> background_, opaque_;  // the whole trace's, as the map sums them
  std::vector<std::uint8_t> met_solid_;
  std::vector<SubtreeRecord> chain_;
  std::vector<std::uint8_t> chain_ok_;
};

// One subtree at the four corners of a cell: [0] top left, [1] top right (g
// samples to the right), [2] bottom left (g samples down), [3] bottom right.
struct SubtreeCorners {
  const SubtreeRecord* record[4];
  const GridCrossing* crossings[4];  // each corner's crossings of the subtree
};

// The subtree `id` at the corners of the cell whose top-left anchor is
// `col` of `top` (bottom: the next anchor row); false where a corner lacks it.
bool subtree_corners(const AnchorRow& top, const AnchorRow& bottom, int col, std::uint64_t id, SubtreeCorners* out);

// How closely a subtree must agree among the anchors (see the top).
struct GridTolerance {
  double relative = 0.1;    // of a footprint; of a weight
  double weight_floor = 0;  // the reflected light's cut-off in the map's units
                            // (max(min_weight, min_weight_reflected) / samples^2)
};

// Whether the subtree may be interpolated in the cell (see the top); cell_px:
// the cell's side in pixels (g / samples_per_axis).
bool subtree_agrees(const SubtreeCorners& corners, double cell_px, const GridTolerance& tolerance);

// Subtrees that agree, each with the range of its weight at the reflection
// over the four anchors, widened by the tolerance: what a sample may defer
// (DeferredSubtrees); a sample whose own reflection falls outside (a total
// internal reflection where the anchors' were partial) traces it. corners:
// where each lies in the anchor rows, for interpolate_subtree (valid while
// they live).
struct AgreeingSubtrees {
  std::vector<std::uint64_t> ids;
  std::vector<double> min_weight, max_weight;
  std::vector<SubtreeCorners> corners;

  void clear() {
    ids.clear();
    min_weight.clear();
    max_weight.clear();
    corners.clear();
  }
};

// The subtrees that agree in the cell of top-left anchor `col`, in the order
// of its top-left anchor's; appended to *out.
void agreeing_subtrees(const AnchorRow& top, const AnchorRow& bottom, int col, double cell_px,
                       const GridTolerance& tolerance, AgreeingSubtrees* out);

// The cell of top-left anchor `col` agrees whole when the four anchors met
// solids alike, their refracted chains (AnchorRow::chain) agree as a subtree
// does (the whole trace's escaped and opaque light compared as a subtree's,
// within `tolerance`), and every subtree of each anchor agrees: `agreeing`
// holds the cell's agreeing subtrees (from agreeing_subtrees), and each anchor
// must have as many. Then *chain gets the chains' corners.
bool cell_agrees_whole(const AnchorRow& top, const AnchorRow& bottom, int col, double cell_px,
                       const GridTolerance& tolerance, std::size_t agreeing, SubtreeCorners* chain);

// The subtree at the point (fx, fy) in [0, 1]^2 of the cell: each crossing's
// position interpolated from the corners' positions and footprint Jacobians
// (cubic Hermite along both axes, exact where the position is quadratic in
// the pixel), its Jacobian and weight and the subtree's weights bilinearly.
// Appends the crossings to *out; adds to the three weights.
void interpolate_subtree(const SubtreeCorners& corners, double cell_px, double fx, double fy,
                         std::vector<GridCrossing>* out, double* background, double* opaque, double* cut);

}  // namespace glasspiv
