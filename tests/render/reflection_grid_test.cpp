// The reflection grid (render/reflection_grid.h): the tracer's subtree
// bookkeeping and deferral, the agreement test and the interpolation on
// fields with a known answer, and maps built with the grid against the same
// maps traced whole.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <tuple>

#include "calib/camera_model.h"
#include "render/forward_render.h"
#include "render/path_tracer.h"
#include "render/reflection_grid.h"
#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"
#include "render/transport_map.h"
#include "tests/render/test_maps.h"

namespace glasspiv {
namespace {

CameraModel pinhole() { return CameraModel(40, 30, 120.0, 110.0, 19.3, 14.6); }

// A glass slab and a sphere in front of the sheet, no absorption: every bit
// of a subtree's weight ends in the background, on the sheet side or cut.
TraceScene slab_and_sphere() {
  TraceScene scene;
  scene.sheet.origin_mm = Eigen::Vector3d(0, 0, 200);
  scene.sheet.extent_s_mm = scene.sheet.extent_t_mm = 1000;
  scene.solids.push_back({make_slab(Eigen::Vector3d(0, 0, 65), Eigen::Vector3d::UnitZ(), 10, 1000),
                          TraceMaterial::glass(1.5)});
  scene.solids.push_back({Sphere{Eigen::Vector3d(3, -2, 120), 15}, TraceMaterial::glass(1.6)});
  return scene;
}

CameraRay ray_towards(double x, double y) {
  CameraRay ray;
  ray.direction = Eigen::Vector3d(x, y, 1);
  ray.ddirection_dpixel << 1.0 / 120, 0, 0, 1.0 / 110, 0, 0;
  return ray;
}

TEST(TraceRaySubtrees, EachSubtreeAccountsForItsWeightAndItsCrossingsAreContiguous) {
  const TraceScene scene = slab_and_sphere();
  const auto index = make_scene_index(scene);
  TraceOptions options;
  options.min_weight = 1e-5;
  TraceResult r;
  int rays_with_subtrees = 0;
  for (double x : {-0.1, 0.0, 0.02, 0.05})
    for (double y : {-0.05, 0.0, 0.03}) {
      trace_ray(scene, *index, ray_towards(x, y), options, &r);
      if (r.subtrees.empty()) continue;
      ++rays_with_subtrees;
      std::vector<std::uint64_t> ids;
      for (const ReflectedSubtree& st : r.subtrees) {
        // No absorption, no opaque solids: what was spawned left, or was cut.
        EXPECT_NEAR(st.weight, st.background_weight + st.opaque_weight + st.cut_weight, 1e-12);
        ids.push_back(st.id);
      }
      std::sort(ids.begin(), ids.end());
      EXPECT_EQ(std::adjacent_find(ids.begin(), ids.end()), ids.end()) << "subtree ids repeat";
      // The refracted chain's crossings first, then each subtree's in one run.
      std::vector<int> runs;
      for (const SheetCrossing& c : r.crossings) {
        EXPECT_EQ(c.subtree >= 0, c.tag == CrossingTag::with_reflections);
        if (c.subtree < 0) {
          EXPECT_TRUE(runs.empty()) << "a refracted-chain crossing after a subtree's";
        } else if (runs.empty() || runs.back() != c.subtree) {
          EXPECT_EQ(std::find(runs.begin(), runs.end(), c.subtree), runs.end()) << "subtree split in two runs";
          runs.push_back(c.subtree);
        }
      }
      EXPECT_NEAR(r.terminal_weight_sum(), 1, 1e-12);
    }
  EXPECT_GE(rays_with_subtrees, 6);
}

TEST(TraceRaySubtrees, DeferredSubtreesAreNotTracedAndTheRefractedChainIsUnchanged) {
  const TraceScene scene = slab_and_sphere();
  const auto index = make_scene_index(scene);
  TraceOptions options;
  options.min_weight = 1e-5;
  TraceResult whole, part;
  trace_ray(scene, *index, ray_towards(0.02, 0.03), options, &whole);
  ASSERT_GE(whole.subtrees.size(), 3u);
  std::vector<std::uint64_t> ids;
  double spawned = 0;
  for (const ReflectedSubtree& st : whole.subtrees) {
    ids.push_back(st.id);
    spawned += st.weight;
  }
  const std::vector<double> any_from(ids.size(), 0.0), any_to(ids.size(), 1.0);
  trace_ray(scene, *index, ray_towards(0.02, 0.03), options, &part,
            DeferredSubtrees{ids.data(), any_from.data(), any_to.data(), ids.size()});
  EXPECT_EQ(part.deferred, ids);  // met in the order they were spawned
  EXPECT_EQ(part.deferred_weight, spawned);
  EXPECT_TRUE(part.subtrees.empty());
  EXPECT_NEAR(part.terminal_weight_sum(), 1, 1e-12);
  std::size_t n = 0;
  for (const SheetCrossing& c : whole.crossings) {
    if (c.subtree >= 0) continue;
    ASSERT_LT(n, part.crossings.size());
    EXPECT_EQ(part.crossings[n].s_mm, c.s_mm);
    EXPECT_EQ(part.crossings[n].weight, c.weight);
    EXPECT_EQ(part.crossings[n].path, c.path);
    ++n;
  }
  EXPECT_EQ(n, part.crossings.size());
  // Deferring one subtree leaves the others traced as before.
  trace_ray(scene, *index, ray_towards(0.02, 0.03), options, &part,
            DeferredSubtrees{ids.data() + 1, any_from.data(), any_to.data(), 1});
  EXPECT_EQ(part.deferred, std::vector<std::uint64_t>{ids[1]});
  EXPECT_EQ(part.subtrees.size(), whole.subtrees.size() - 1);
  // A subtree whose weight at the reflection lies outside the range given is
  // traced, not deferred (a total internal reflection where the caller's
  // subtrees were partial reflections).
  const double w1 = whole.subtrees[1].weight;
  const double below[] = {0.5 * w1}, above[] = {2 * w1}, around_lo[] = {0.9 * w1}, around_hi[] = {1.1 * w1};
  trace_ray(scene, *index, ray_towards(0.02, 0.03), options, &part, DeferredSubtrees{ids.data() + 1, above, above, 1});
  EXPECT_TRUE(part.deferred.empty());
  EXPECT_EQ(part.subtrees.size(), whole.subtrees.size());
  trace_ray(scene, *index, ray_towards(0.02, 0.03), options, &part, DeferredSubtrees{ids.data() + 1, below, below, 1});
  EXPECT_TRUE(part.deferred.empty());
  trace_ray(scene, *index, ray_towards(0.02, 0.03), options, &part,
            DeferredSubtrees{ids.data() + 1, around_lo, around_hi, 1});
  EXPECT_EQ(part.deferred.size(), 1u);
}

// ---------------------------------------------------------------- on a known field

constexpr double kCellPx = 2;

// A subtree with one crossing whose position is quadratic in the pixel,
// s = 3 + 0.5 c - 0.2 r + 0.005 c^2 + 0.002 c r + 0.003 r^2,
// t = -1 + 0.1 c + 0.4 r - 0.004 c^2 + 0.001 c r + 0.002 r^2 (mm; c, r: col,
// row), its footprint Jacobian the derivative, weight 0.04 + 0.001 c.
TraceResult quadratic_anchor(double col, double row, std::uint64_t id = 77) {
  TraceResult r;
  ReflectedSubtree& st = r.subtrees.emplace_back();
  st.id = id;
  st.weight = 0.05;
  st.background_weight = 0.01;
  SheetCrossing& main = r.crossings.emplace_back();
  main.s_mm = col;
  main.weight = 0.9;
  SheetCrossing& c = r.crossings.emplace_back();
  c.s_mm = 3 + 0.5 * col - 0.2 * row + 0.005 * col * col + 0.002 * col * row + 0.003 * row * row;
  c.t_mm = -1 + 0.1 * col + 0.4 * row - 0.004 * col * col + 0.001 * col * row + 0.002 * row * row;
  c.dst_dpixel << 0.5 + 0.01 * col + 0.002 * row, -0.2 + 0.002 * col + 0.006 * row,  //
      0.1 - 0.008 * col + 0.001 * row, 0.4 + 0.001 * col + 0.004 * row;
  c.weight = 0.04 + 0.001 * col;
  c.tag = CrossingTag::with_reflections;
  c.path = 1234;
  c.subtree = 0;
  r.background_weight = 0.06;
  return r;
}

// Anchor rows of one cell at the origin, each corner's trace make(col, row),
// corner c's changed by `edit`.
template <typename Make, typename Edit>
std::pair<AnchorRow, AnchorRow> cell_rows_of(Make make, int corner, Edit edit) {
  AnchorRow top, bottom;
  for (int i = 0; i < 4; ++i) {
    TraceResult r = make((i & 1) * kCellPx, (i >> 1) * kCellPx);
    if (i == corner) edit(r);
    (i < 2 ? top : bottom).add(&r, 1.0);
  }
  return {std::move(top), std::move(bottom)};
}

template <typename Edit>
std::pair<AnchorRow, AnchorRow> cell_rows(int corner, Edit edit) {
  return cell_rows_of([](double col, double row) { return quadratic_anchor(col, row); }, corner, edit);
}

std::vector<std::uint64_t> agreeing(const std::pair<AnchorRow, AnchorRow>& rows, double tolerance = 0.1) {
  GridTolerance tol;
  tol.relative = tolerance;
  tol.weight_floor = 1e-2;
  AgreeingSubtrees out;
  agreeing_subtrees(rows.first, rows.second, 0, kCellPx, tol, &out);
  EXPECT_EQ(out.min_weight.size(), out.ids.size());
  for (std::size_t i = 0; i < out.ids.size(); ++i) {  // every corner's 0.05, widened by the tolerance
    EXPECT_NEAR(out.min_weight[i], 0.05 * (1 - tolerance), 1e-9);
    EXPECT_NEAR(out.max_weight[i], 0.05 * (1 + tolerance), 1e-9);
  }
  return out.ids;
}

TEST(ReflectionGrid, AQuadraticSubtreeAgreesAndIsInterpolatedExactly) {
  const auto rows = cell_rows(-1, [](TraceResult&) {});
  ASSERT_EQ(agreeing(rows), std::vector<std::uint64_t>{77});
  SubtreeCorners corners;
  ASSERT_TRUE(subtree_corners(rows.first, rows.second, 0, 77, &corners));
  for (double fx : {0.0, 0.5, 0.25})
    for (double fy : {0.0, 0.5, 0.75}) {
      std::vector<GridCrossing> out;
      double background = 0, opaque = 0, cut = 0;
      interpolate_subtree(corners, kCellPx, fx, fy, &out, &background, &opaque, &cut);
      ASSERT_EQ(out.size(), 1u);
      const double col = fx * kCellPx, row = fy * kCellPx;
      // Float storage: |s|, |t| < 5 mm, so a few 1e-7 mm (a linear blend of
      // the corners would miss by up to 0.005 mm here).
      EXPECT_NEAR(out[0].s_mm, 3 + 0.5 * col - 0.2 * row + 0.005 * col * col + 0.002 * col * row + 0.003 * row * row,
                  2e-6);
      EXPECT_NEAR(out[0].t_mm, -1 + 0.1 * col + 0.4 * row - 0.004 * col * col + 0.001 * col * row + 0.002 * row * row,
                  2e-6);
      EXPECT_NEAR(out[0].weight, 0.04 + 0.001 * col, 1e-8);
      EXPECT_NEAR(out[0].ds_drow, -0.2 + 0.002 * col + 0.006 * row, 1e-7);  // linear: the blend is exact
      EXPECT_EQ(out[0].path, 1234u);
      EXPECT_EQ(out[0].tag, static_cast<std::uint8_t>(CrossingTag::with_reflections));
      EXPECT_NEAR(background, 0.01, 1e-8);
    }
}

TEST(ReflectionGrid, ASubtreeThatDisagreesAnywhereIsTraced) {
  for (int corner = 0; corner < 4; ++corner) {
    SCOPED_TRACE(corner);
    // Off by a fifth of a footprint (sqrt |det J| >= 0.469 mm): beyond 0.1 with
    // the curvature's own miss (< 0.02 mm), within 0.25.
    const auto moved = cell_rows(corner, [](TraceResult& r) { r.crossings[1].s_mm += 0.2 * 0.469; });
    EXPECT_TRUE(agreeing(moved).empty());
    EXPECT_EQ(agreeing(moved, 0.25).size(), 1u);
    EXPECT_TRUE(agreeing(cell_rows(corner, [](TraceResult& r) { r.crossings[1].path = 99; })).empty());
    EXPECT_TRUE(agreeing(cell_rows(corner, [](TraceResult& r) { r.crossings[1].weight *= 1.2; })).empty());
    EXPECT_TRUE(agreeing(cell_rows(corner, [](TraceResult& r) { r.crossings.pop_back(); })).empty());
    EXPECT_TRUE(agreeing(cell_rows(corner, [](TraceResult& r) { r.subtrees[0].id = 78; })).empty());
    EXPECT_TRUE(agreeing(cell_rows(corner, [](TraceResult& r) { r.subtrees[0].weight *= 1.2; })).empty());
    EXPECT_TRUE(agreeing(cell_rows(corner, [](TraceResult& r) { r.crossings[1].dst_dpixel *= 1.5; })).empty());
    // Light that left the scene: within the cut-off's 1e-2 it agrees, beyond it not.
    EXPECT_EQ(agreeing(cell_rows(corner, [](TraceResult& r) { r.subtrees[0].background_weight += 0.009; })).size(), 1u);
    EXPECT_TRUE(agreeing(cell_rows(corner, [](TraceResult& r) { r.subtrees[0].background_weight += 0.02; })).empty());
  }
  // A corner whose ray could not be unprojected has no subtrees.
  AnchorRow top, bottom;
  const TraceResult r = quadratic_anchor(0, 0);
  top.add(&r, 1.0);
  top.add(nullptr, 1.0);
  bottom.add(&r, 1.0);
  bottom.add(&r, 1.0);
  AgreeingSubtrees none;
  agreeing_subtrees(top, bottom, 0, kCellPx, GridTolerance{}, &none);
  EXPECT_TRUE(none.ids.empty());
  EXPECT_EQ(top.crossing_count(1), 0);
  EXPECT_FALSE(top.met_solid(1));
}

// An anchor whose refracted chain's one crossing is quadratic in the pixel too
// (path 999, weight 0.9), beside quadratic_anchor's subtree 77; it met solids.
TraceResult whole_anchor(double col, double row) {
  TraceResult r = quadratic_anchor(col, row);
  SheetCrossing& main = r.crossings[0];
  main.s_mm = -2 + 0.3 * col + 0.1 * row + 0.002 * col * col - 0.001 * col * row + 0.004 * row * row;
  main.t_mm = 5 - 0.1 * col + 0.6 * row + 0.003 * col * col + 0.002 * col * row - 0.001 * row * row;
  main.dst_dpixel << 0.3 + 0.004 * col - 0.001 * row, 0.1 - 0.001 * col + 0.008 * row,  //
      -0.1 + 0.006 * col + 0.002 * row, 0.6 + 0.002 * col - 0.002 * row;
  main.weight = 0.9;
  main.path = 999;
  main.tag = CrossingTag::refracted_only;
  r.counts.branches_traced = 5;
  r.cut_by_weight_weight = 0.004;
  return r;
}

template <typename Edit>
std::pair<AnchorRow, AnchorRow> whole_rows(int corner, Edit edit) {
  return cell_rows_of(whole_anchor, corner, edit);
}

// Whether the cell agrees whole (cell_agrees_whole after agreeing_subtrees).
bool agrees_whole(const std::pair<AnchorRow, AnchorRow>& rows, SubtreeCorners* chain) {
  GridTolerance tol;
  tol.weight_floor = 1e-2;
  AgreeingSubtrees out;
  agreeing_subtrees(rows.first, rows.second, 0, kCellPx, tol, &out);
  return cell_agrees_whole(rows.first, rows.second, 0, kCellPx, tol, out.ids.size(), chain);
}

TEST(ReflectionGrid, ACellThatAgreesWholeInterpolatesTheRefractedChainAndTheWholeTracesLight) {
  SubtreeCorners chain;
  const auto rows = whole_rows(-1, [](TraceResult&) {});  // the corners point into these
  ASSERT_TRUE(agrees_whole(rows, &chain));
  for (double fx : {0.0, 0.5, 0.25})
    for (double fy : {0.0, 0.5, 0.75}) {
      std::vector<GridCrossing> out;
      double background = 0, opaque = 0, cut = 0;
      interpolate_subtree(chain, kCellPx, fx, fy, &out, &background, &opaque, &cut);
      ASSERT_EQ(out.size(), 1u);  // the chain's crossing only: the subtree's are its own record's
      const double col = fx * kCellPx, row = fy * kCellPx;
      EXPECT_NEAR(out[0].s_mm, -2 + 0.3 * col + 0.1 * row + 0.002 * col * col - 0.001 * col * row + 0.004 * row * row,
                  2e-6);
      EXPECT_NEAR(out[0].t_mm, 5 - 0.1 * col + 0.6 * row + 0.003 * col * col + 0.002 * col * row - 0.001 * row * row,
                  2e-6);
      EXPECT_NEAR(out[0].weight, 0.9, 1e-7);
      EXPECT_EQ(out[0].path, 999u);
      EXPECT_EQ(out[0].tag, static_cast<std::uint8_t>(CrossingTag::refracted_only));
      // The whole trace's light, subtrees' shares included, not the chain's alone.
      EXPECT_NEAR(background, 0.06, 1e-8);
      EXPECT_NEAR(cut, 0.004, 1e-8);
    }
}

TEST(ReflectionGrid, ACellWithAnyDisagreementIsNotInterpolatedWhole) {
  for (int corner = 0; corner < 4; ++corner) {
    SCOPED_TRACE(corner);
    SubtreeCorners chain;
    // The chain's crossing off by a fifth of a footprint (sqrt |det J| >= 0.42 mm).
    EXPECT_FALSE(agrees_whole(whole_rows(corner, [](TraceResult& r) { r.crossings[0].s_mm += 0.2 * 0.42; }), &chain));
    EXPECT_FALSE(agrees_whole(whole_rows(corner, [](TraceResult& r) { r.crossings[0].path = 1; }), &chain));
    EXPECT_FALSE(agrees_whole(whole_rows(corner, [](TraceResult& r) { r.crossings[0].weight *= 0.8; }), &chain));
    // The chain ends elsewhere: no chain crossing, its light left the scene.
    EXPECT_FALSE(agrees_whole(whole_rows(corner,
                                         [](TraceResult& r) {
                                           r.crossings.erase(r.crossings.begin());
                                           r.background_weight += 0.9;
                                         }),
                              &chain));
    // The subtree disagrees, or one corner has one more.
    EXPECT_FALSE(agrees_whole(whole_rows(corner, [](TraceResult& r) { r.crossings[1].path = 99; }), &chain));
    EXPECT_FALSE(agrees_whole(whole_rows(corner,
                                         [](TraceResult& r) {
                                           ReflectedSubtree& st = r.subtrees.emplace_back();
                                           st.id = 78;
                                           st.weight = 0.02;
                                         }),
                              &chain));
    // Its ray met no solid where the others' did.
    EXPECT_FALSE(agrees_whole(whole_rows(corner, [](TraceResult& r) { r.counts.branches_traced = 1; }), &chain));
    // Light that left the scene beyond the cut-off of 1e-2.
    EXPECT_FALSE(agrees_whole(whole_rows(corner, [](TraceResult& r) { r.background_weight += 0.02; }), &chain));
    EXPECT_TRUE(agrees_whole(whole_rows(corner, [](TraceResult& r) { r.background_weight += 0.005; }), &chain));
  }
  // A corner whose ray could not be unprojected.
  AnchorRow top, bottom;
  const TraceResult r = whole_anchor(0, 0);
  top.add(&r, 1.0);
  top.add(nullptr, 1.0);
  bottom.add(&r, 1.0);
  bottom.add(&r, 1.0);
  SubtreeCorners chain;
  EXPECT_EQ(top.chain(1), nullptr);
  EXPECT_FALSE(cell_agrees_whole(top, bottom, 0, kCellPx, GridTolerance{}, 0, &chain));
}

// ---------------------------------------------------------------- maps

// Pixel p's crossings as (s, t, weight, footprint), sorted.
struct Crossing {
  double s, t, w, footprint;
  bool operator<(const Crossing& o) const { return std::tie(s, t, w) < std::tie(o.s, o.t, o.w); }
};
std::vector<Crossing> crossings_of(const TransportMap& m, std::size_t p) {
  std::vector<Crossing> out;
  for (std::uint32_t i = m.pixel_offsets[p]; i < m.pixel_offsets[p + 1]; ++i)
    out.push_back({m.s_mm[i], m.t_mm[i], m.weight[i],
                   std::sqrt(std::abs(m.ds_dcol[i] * m.dt_drow[i] - m.ds_drow[i] * m.dt_dcol[i]))});
  std::sort(out.begin(), out.end());
  return out;
}

// The slab's ghosts (light reflected inside it, twice or more) are smooth in
// the pixel: the grid interpolates them and lands where the tracer does. A
// camera 150 rows tall: the map is built in bands of 64 rows.
TEST(ReflectionGridMap, InterpolatedGhostsLandWhereTheTracerPutsThem) {
  for (int k : {1, 2}) {
  SCOPED_TRACE(k);
  TraceScene scene = slab_and_sphere();
  scene.solids.pop_back();  // the slab alone
  const CameraModel cam(40, 150, 120.0, 110.0, 19.3, 74.6);
  TraceOptions options;
  options.min_weight = 1e-4;
  const TransportMap whole = build_transport_map(scene, cam, RigidTransform{}, options, k, 2);
  options.reflection_grid = 2;
  const TransportMap grid = build_transport_map(scene, cam, RigidTransform{}, options, k, 2);
  EXPECT_GT(grid.stats.subtrees_interpolated, 2000 * k * k);
  EXPECT_LT(grid.stats.branches_traced, whole.stats.branches_traced * 0.6);
  ASSERT_EQ(grid.pixel_count(), whole.pixel_count());
  double worst_position = 0, worst_weight = 0;
  for (std::size_t p = 0; p < whole.pixel_count(); ++p) {
    const std::vector<Crossing> a = crossings_of(whole, p), b = crossings_of(grid, p);
    ASSERT_EQ(a.size(), b.size()) << "pixel " << p;
    for (std::size_t i = 0; i < a.size(); ++i) {
      worst_position = std::max(worst_position, std::hypot(a[i].s - b[i].s, a[i].t - b[i].t) / a[i].footprint);
      worst_weight = std::max(worst_weight, std::abs(a[i].w - b[i].w) / a[i].w);
    }
    // Weights are blended bilinearly: the Fresnel weights' curvature over a
    // 2 px cell leaves a few 1e-6 at the steep edges of this view.
    EXPECT_NEAR(grid.background_weight[p], whole.background_weight[p], 1e-5) << "pixel " << p;
  }
  // The slab's ghost positions are smooth but not affine in the pixel (the
  // lateral shift grows with the angle): second-order terms over a 2 px cell,
  // well inside the 0.1 footprint the agreement test allows.
  EXPECT_LT(worst_position, 1e-2);
  EXPECT_LT(worst_weight, 1e-3);
  std::printf("slab ghosts, %d x %d samples: %ld subtrees interpolated, worst %.2e footprints, %.2e relative weight\n",
              k, k, grid.stats.subtrees_interpolated, worst_position, worst_weight);
  }
}

TEST(ReflectionGridMap, AnchorsAreTracedWholeAndTheResultIsTheSameOnAnyThreadCount) {
  const TraceScene scene = slab_and_sphere();
  TraceOptions options;
  options.min_weight = 1e-4;
  const TransportMap whole = build_transport_map(scene, pinhole(), RigidTransform{}, options, 1, 1);
  options.reflection_grid = 2;
  const TransportMap one = build_transport_map(scene, pinhole(), RigidTransform{}, options, 1, 1);
  const TransportMap three = build_transport_map(scene, pinhole(), RigidTransform{}, options, 1, 3);
  expect_same_map_arrays(one, three);
  EXPECT_EQ(one.stats.branches_traced, three.stats.branches_traced);
  EXPECT_EQ(one.stats.subtrees_interpolated, three.stats.subtrees_interpolated);
  for (int row = 0; row < whole.height; row += 2)
    for (int col = 0; col < whole.width; col += 2) {
      const std::size_t p = static_cast<std::size_t>(row) * whole.width + col;
      ASSERT_EQ(one.pixel_offsets[p + 1] - one.pixel_offsets[p], whole.pixel_offsets[p + 1] - whole.pixel_offsets[p]);
      for (std::uint32_t i = 0; i < whole.pixel_offsets[p + 1] - whole.pixel_offsets[p]; ++i) {
        EXPECT_EQ(one.s_mm[one.pixel_offsets[p] + i], whole.s_mm[whole.pixel_offsets[p] + i]);
        EXPECT_EQ(one.weight[one.pixel_offsets[p] + i], whole.weight[whole.pixel_offsets[p] + i]);
      }
      EXPECT_EQ(one.background_weight[p], whole.background_weight[p]);
    }
  // With two samples per axis the anchors are every other sample.
  const TransportMap k2 = build_transport_map(scene, pinhole(), RigidTransform{}, options, 2, 2);
  EXPECT_EQ(k2.stats.camera_rays, 4 * 40 * 30);
  EXPECT_GT(k2.stats.subtrees_interpolated, 0);
}

// Sizes, samples and grids that do not divide each other, images of one row
// or column, a grid larger than the image, cells across bands of rows: the
// light is kept, and where the grid equals the samples per axis each pixel's
// first sample is an anchor whose crossings (listed first) are the whole
// trace's to the bit.
TEST(ReflectionGridMap, AnySamplingAndGridKeepsTheLightAndAnchorsExact) {
  const TraceScene scene = slab_and_sphere();
  const auto index = make_scene_index(scene);
  struct Case {
    int width, height, k, g;
  };
  for (const Case& c : {Case{40, 150, 3, 3}, Case{13, 67, 1, 3}, Case{1, 5, 1, 2}, Case{5, 1, 2, 2},
                        Case{7, 130, 2, 5}, Case{9, 9, 1, 64}, Case{20, 140, 2, 2}}) {
    SCOPED_TRACE(testing::Message() << c.width << "x" << c.height << " k " << c.k << " g " << c.g);
    const CameraModel cam(c.width, c.height, 120.0, 110.0, 0.5 * (c.width - 1), 0.5 * (c.height - 1));
    TraceOptions options;
    options.min_weight = 1e-4;
    const TransportMap whole = build_transport_map(scene, cam, RigidTransform{}, options, c.k, 2);
    options.reflection_grid = c.g;
    const TransportMap grid = build_transport_map(scene, cam, RigidTransform{}, options, c.k, 2);
    EXPECT_EQ(grid.stats.camera_rays, whole.stats.camera_rays);
    EXPECT_EQ(grid.stats.pixels_without_solid_hit, whole.stats.pixels_without_solid_hit);
    double light_whole = 0, light_grid = 0;
    for (float w : whole.weight) light_whole += w;
    for (float w : grid.weight) light_grid += w;
    EXPECT_NEAR(light_grid, light_whole, 1e-4 * light_whole);
    // The anchors' escaped ghost light may differ by the tolerance (10 %) of
    // it; a pixel's escaped ghost light is a few per cent, so interpolated
    // between them it moves by well under 1e-3.
    for (std::size_t p = 0; p < whole.pixel_count(); ++p)
      EXPECT_NEAR(grid.background_weight[p], whole.background_weight[p], 1e-3) << "pixel " << p;
    if (c.g != c.k) continue;
    TraceResult r;
    for (int row = 0; row < c.height; ++row)
      for (int col = 0; col < c.width; ++col) {
        const double first = 0.5 / c.k - 0.5;  // sample (0, 0) of the pixel
        trace_ray(scene, *index, *pixel_camera_ray(cam, RigidTransform{}, Eigen::Vector2d(col + first, row + first)),
                  options, &r);
        const std::size_t p = static_cast<std::size_t>(row) * c.width + col;
        const std::uint32_t a = grid.pixel_offsets[p], b = whole.pixel_offsets[p];
        ASSERT_LE(a + r.crossings.size(), grid.pixel_offsets[p + 1]);
        for (std::size_t i = 0; i < r.crossings.size(); ++i) {
          EXPECT_EQ(grid.s_mm[a + i], whole.s_mm[b + i]);
          EXPECT_EQ(grid.t_mm[a + i], whole.t_mm[b + i]);
          EXPECT_EQ(grid.weight[a + i], whole.weight[b + i]);
          EXPECT_EQ(grid.ds_dcol[a + i], whole.ds_dcol[b + i]);
          EXPECT_EQ(grid.dt_drow[a + i], whole.dt_drow[b + i]);
          EXPECT_EQ(grid.tag[a + i], whole.tag[b + i]);
        }
      }
  }
}

// Whole samples: on the slab, whose every path is smooth in the pixel, most
// samples are interpolated whole, with or without reflections, and land where
// the tracer puts them; the anchors stay exact and the map is the same on any
// thread count. With reflection_grid_levels 2 the anchors between the coarse
// ones are interpolated too, over cells twice as wide.
TEST(ReflectionGridMap, WholeSamplesLandWhereTheTracerPutsThem) {
  for (int levels : {1, 2})
  for (bool reflections : {true, false})
    for (int k : {1, 2}) {
      SCOPED_TRACE(testing::Message() << "levels " << levels << " reflections " << reflections << " k " << k);
      TraceScene scene = slab_and_sphere();
      scene.solids.pop_back();  // the slab alone
      const CameraModel cam(40, 150, 120.0, 110.0, 19.3, 74.6);
      TraceOptions options;
      options.min_weight = 1e-4;
      options.reflections = reflections;
      const TransportMap whole = build_transport_map(scene, cam, RigidTransform{}, options, k, 2);
      options.reflection_grid = 2;
      options.grid_whole_samples = true;
      options.reflection_grid_levels = levels;
      const TransportMap grid = build_transport_map(scene, cam, RigidTransform{}, options, k, 2);
      const long samples = 40L * 150 * k * k;
      EXPECT_EQ(grid.stats.camera_rays + grid.stats.samples_interpolated, samples);
      // All but the anchors (a quarter; a sixteenth with the coarse level) and
      // the last rows and columns of samples.
      EXPECT_GT(grid.stats.samples_interpolated, samples * (levels == 1 ? 0.7 : 0.85));
      EXPECT_EQ(grid.stats.pixels_without_solid_hit, whole.stats.pixels_without_solid_hit);
      ASSERT_EQ(grid.pixel_count(), whole.pixel_count());
      double worst_position = 0, worst_weight = 0, worst_background = 0;
      for (std::size_t p = 0; p < whole.pixel_count(); ++p) {
        const std::vector<Crossing> a = crossings_of(whole, p), b = crossings_of(grid, p);
        ASSERT_EQ(a.size(), b.size()) << "pixel " << p;
        for (std::size_t i = 0; i < a.size(); ++i) {
          worst_position = std::max(worst_position, std::hypot(a[i].s - b[i].s, a[i].t - b[i].t) / a[i].footprint);
          worst_weight = std::max(worst_weight, std::abs(a[i].w - b[i].w) / a[i].w);
        }
        worst_background = std::max(worst_background, std::abs(double(grid.background_weight[p]) - whole.background_weight[p]));
      }
      // As the interpolated ghosts above: second-order terms over a 2 px cell
      // (4 px with the coarse level: four times the second-order term).
      EXPECT_LT(worst_position, levels == 1 ? 1e-2 : 4e-2);
      EXPECT_LT(worst_weight, levels == 1 ? 1e-3 : 4e-3);
      EXPECT_LT(worst_background, levels == 1 ? 1e-5 : 4e-5);
      std::printf("slab, whole samples, levels %d, reflections %d, %d x %d samples: %ld of %ld interpolated, worst "
                  "%.2e footprints, %.2e relative weight, %.1e background\n",
                  levels, reflections, k, k, grid.stats.samples_interpolated, samples, worst_position, worst_weight,
                  worst_background);
      const TransportMap one = build_transport_map(scene, cam, RigidTransform{}, options, k, 1);
      expect_same_map_arrays(one, grid);
    }
}

// Slab and sphere: wherever a sphere's rim lies between anchors the samples
// are traced, so every pixel keeps the whole trace's crossings, and the
// anchors' are the whole trace's to the bit (with the coarse level of
// reflection_grid_levels 2, the coarse anchors').
TEST(ReflectionGridMap, WholeSamplesNeverBridgeASpheresRim) {
  for (int levels : {1, 2}) {
  SCOPED_TRACE(testing::Message() << "levels " << levels);
  const TraceScene scene = slab_and_sphere();
  TraceOptions options;
  options.min_weight = 1e-4;
  const TransportMap whole = build_transport_map(scene, pinhole(), RigidTransform{}, options, 1, 2);
  options.reflection_grid = 2;
  options.grid_whole_samples = true;
  options.reflection_grid_levels = levels;
  const TransportMap grid = build_transport_map(scene, pinhole(), RigidTransform{}, options, 1, 2);
  EXPECT_GT(grid.stats.samples_interpolated, 0);
  EXPECT_LT(grid.stats.samples_interpolated, 40 * 30 * 3 / 4);  // the sphere's samples are traced
  for (std::size_t p = 0; p < whole.pixel_count(); ++p) {
    ASSERT_EQ(grid.pixel_offsets[p + 1] - grid.pixel_offsets[p], whole.pixel_offsets[p + 1] - whole.pixel_offsets[p])
        << "pixel " << p;
    EXPECT_NEAR(grid.background_weight[p], whole.background_weight[p], 1e-3) << "pixel " << p;
  }
  for (int row = 0; row < whole.height; row += 2 * levels)
    for (int col = 0; col < whole.width; col += 2 * levels) {
      const std::size_t p = static_cast<std::size_t>(row) * whole.width + col;
      for (std::uint32_t i = 0; i < whole.pixel_offsets[p + 1] - whole.pixel_offsets[p]; ++i) {
        EXPECT_EQ(grid.s_mm[grid.pixel_offsets[p] + i], whole.s_mm[whole.pixel_offsets[p] + i]);
        EXPECT_EQ(grid.weight[grid.pixel_offsets[p] + i], whole.weight[whole.pixel_offsets[p] + i]);
      }
    }
  }
}

TEST(ReflectionGridMap, WithoutReflectionsOrAGridTheMapIsTracedWhole) {
  const TraceScene scene = slab_and_sphere();
  TraceOptions options;
  options.reflections = false;
  const TransportMap plain = build_transport_map(scene, pinhole(), RigidTransform{}, options, 1, 2);
  options.reflection_grid = 4;
  const TransportMap grid = build_transport_map(scene, pinhole(), RigidTransform{}, options, 1, 2);
  expect_same_map_arrays(plain, grid);
  EXPECT_EQ(grid.stats.subtrees_interpolated, 0);
  EXPECT_EQ(grid.stats.branches_traced, plain.stats.branches_traced);
}

TEST(ReflectionGridMap, ProgressCountsPixelRowsUpToTheImagesHeight) {
  const TraceScene scene = slab_and_sphere();
  const CameraModel cam(40, 150, 120.0, 110.0, 19.3, 74.6);
  TraceOptions options;
  options.reflection_grid = 2;
  int last = -1, calls = 0;
  bool in_range = true, monotonic = true;
  build_transport_map(scene, cam, RigidTransform{}, options, 1, 2, [&](int done, int rows) {
    in_range = in_range && rows == 150 && done >= 0 && done <= rows;
    monotonic = monotonic && done >= last;
    last = done;
    ++calls;
  });
  EXPECT_TRUE(in_range);
  EXPECT_TRUE(monotonic);
  EXPECT_EQ(last, 150);
  EXPECT_GE(calls, 2);
}

TEST(ReflectionGridMap, BadOptionsAreRefused) {
  const TraceScene scene = slab_and_sphere();
  TraceOptions options;
  options.reflection_grid = 0;
  EXPECT_THROW(build_transport_map(scene, pinhole(), RigidTransform{}, options), std::invalid_argument);
  options.reflection_grid = 2;
  options.reflection_grid_tolerance = -0.1;
  EXPECT_THROW(build_transport_map(scene, pinhole(), RigidTransform{}, options), std::invalid_argument);
  options.reflection_grid_tolerance = std::nan("");
  EXPECT_THROW(build_transport_map(scene, pinhole(), RigidTransform{}, options), std::invalid_argument);
  options.reflection_grid_tolerance = 0.1;
  for (int levels : {0, 3}) {
    options.reflection_grid_levels = levels;
    EXPECT_THROW(build_transport_map(scene, pinhole(), RigidTransform{}, options), std::invalid_argument);
  }
}

// The packed bed: the grid's image against the image traced whole, on a
// checkerboard sheet (0/1), and the light it keeps.
TEST(ReflectionGridMap, ReactorImageStaysCloseToTheWholeTrace) {
  const Scene scene = read_scene(std::string(GLASSPIV_SOURCE_DIR) + "/data/scenes/reactor.yaml");
  const TraceScene ts = build_trace_scene(scene);
  const Camera& camera = scene.cameras[0].camera;
  const CameraModel cam = binned(camera.model, 8);  // 320 x 270 px over the whole view
  const TransportMap whole = build_transport_map(ts, cam, *camera.camera_from_world, TraceOptions{}, 1, 2);
  const double mm = 5;
  auto checker = [mm](double s, double t) {
    return static_cast<double>((static_cast<long>(std::floor(s / mm)) + static_cast<long>(std::floor(t / mm))) & 1);
  };
  const std::vector<float> a = forward_render_values(whole, checker);
  double light_a = 0;
  for (float w : whole.weight) light_a += w;
  // The grid alone, and with whole samples and the coarse level (anchors
  // interpolated over 4 px cells too).
  for (int levels : {1, 2}) {
    SCOPED_TRACE(testing::Message() << "levels " << levels);
    TraceOptions options;
    options.reflection_grid = 2;
    options.grid_whole_samples = levels == 2;
    options.reflection_grid_levels = levels;
    const TransportMap grid = build_transport_map(ts, cam, *camera.camera_from_world, options, 1, 2);
    EXPECT_GT(grid.stats.subtrees_interpolated, 10000);
    EXPECT_LT(grid.stats.branches_traced, whole.stats.branches_traced * 0.9);
    const std::vector<float> b = forward_render_values(grid, checker);
    double sum = 0, worst = 0, light_b = 0;
    for (std::size_t p = 0; p < a.size(); ++p) {
      sum += (a[p] - b[p]) * (a[p] - b[p]);
      worst = std::max(worst, static_cast<double>(std::abs(a[p] - b[p])));
    }
    for (float w : grid.weight) light_b += w;
    const double rms = std::sqrt(sum / a.size());
    // Point samples of a 0/1 checkerboard: a ghost crossing moved across an
    // edge changes its pixel by its weight (a few 1e-2), so the largest
    // difference is one ghost's weight; the RMS stays far below the 1-sample
    // render's own error against a converged one (0.02-0.03, bench/RESULTS.md).
    EXPECT_LT(rms, 2e-3);
    EXPECT_LT(worst, 0.1);
    EXPECT_NEAR(light_b / light_a, 1, 2e-3);
    std::printf("reactor 320x270, levels %d: branches %ld -> %ld, image RMS difference %.2e, largest %.3f\n", levels,
                whole.stats.branches_traced, grid.stats.branches_traced, rms, worst);
  }
}

}  // namespace
}  // namespace glasspiv
