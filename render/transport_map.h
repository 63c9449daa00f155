#pragma once
// The light-transport map of one camera (DESIGN.md section 3): for every pixel,
// its crossings of the light sheet, traced once per setup and reused for every
// image. Compact struct-of-arrays in CSR layout, 32-bit floats in mm. No I/O.
//
// Per pixel p (row-major, p = row * width + col) the crossings are
// [pixel_offsets[p], pixel_offsets[p + 1]) in s_mm, t_mm, weight, tag and the
// footprint Jacobian d(s, t)/d(pixel) in ds_dcol, ds_drow, dt_dcol, dt_drow
// (mm per pixel; col grows to the right, row grows down), carried by ray
// differentials through every refraction and reflection.
// With samples_per_axis = k > 1 each pixel is traced at k x k stratified
// sub-pixel positions (cell centres of a k x k grid over the pixel's square),
// every weight divided by k^2; crossings of all samples are listed in sample
// order (row-major over the sub-grid). Pixel (0, 0) is the centre of the
// top-left pixel (docs/conventions.md).
//
// With TraceOptions::reflection_grid g > 1 (and reflections on) reflected
// subtrees that agree among anchors on every g-th sample are interpolated
// between them (render/reflection_grid.h); each sample's refracted chain is
// traced, unless TraceOptions::grid_whole_samples interpolates the whole
// sample. A sample's interpolated crossings follow its traced ones.
//
// Known limit: a pixel whose ray cannot be unprojected (past the lens model's
// fold) has no crossings and no background weight (counted in unproject_failures).
#include <cstdint>
#include <functional>
#include <vector>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "render/path_tracer.h"

namespace glasspiv {

// What the build did and what it skipped (docs/tracer.md).
struct TransportStats {
  long camera_rays = 0;        // camera rays traced (pixels x samples, less samples_interpolated)
  long branches_traced = 0;    // segments followed, summed over all rays (TraceCounts)
  long crossings = 0;          // sheet crossings stored
  long pixels_without_solid_hit = 0;  // no sample of the pixel met any solid
  long unproject_failures = 0;        // samples whose pixel ray could not be computed
  long closed_form_rays = 0;          // camera rays proven to miss all solids: no BVH query
  long branches_cut_by_weight = 0;    // below TraceOptions::min_weight
  long branches_cut_by_depth = 0;     // beyond TraceOptions::max_depth
  long reflections_skipped = 0;       // not spawned (TraceOptions::reflections = false)
  long subtrees_interpolated = 0;     // reflected subtrees interpolated, not traced
                                      // (TraceOptions::reflection_grid); not kept in map files
  long samples_interpolated = 0;      // camera samples interpolated whole, not traced
                                      // (TraceOptions::grid_whole_samples); not kept in map files
  double cut_weight = 0;              // weight of those three, summed over pixels (1 = one whole pixel)
  int threads = 0;                    // threads used
};

struct TransportMap {
  int width = 0, height = 0;
  int samples_per_axis = 1;
  std::vector<std::uint32_t> pixel_offsets;  // width * height + 1
  std::vector<float> s_mm, t_mm, weight;     // per crossing
  std::vector<std::uint8_t> tag;             // per crossing: static_cast<uint8_t>(CrossingTag)
  std::vector<float> ds_dcol, ds_drow, dt_dcol, dt_drow;  // per crossing: footprint Jacobian, mm/px
  std::vector<float> background_weight;      // per pixel: weight that left the scene
  std::vector<float> opaque_weight;          // per pixel: weight that ended on opaque solids
  TransportStats stats;

  std::size_t pixel_count() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
  std::size_t crossing_count() const { return weight.size(); }
  // Bytes held by the arrays (capacity not counted).
  std::size_t memory_bytes() const;
};

// Builds the map of a camera. threads <= 0: std::thread::hardware_concurrency().
// Rows are handed to threads dynamically; each writes its pixels' entries in
// place and its crossings into its own buffer, and the buffers are
// concatenated in row order, so the output is bit-identical for any thread
// count. The arrays are advised onto huge pages (util/huge_pages.h). Throws std::invalid_argument for samples_per_axis < 1 and
// std::overflow_error beyond 2^32 - 1 crossings; std::invalid_argument for a
// reflection_grid < 1 or a negative or non-finite reflection_grid_tolerance.
// progress (optional) is called from the calling thread with (rows done, rows)
// about every 1/100 of the work; it must not throw.
TransportMap build_transport_map(const TraceScene& scene, const CameraModel& camera,
                                 const RigidTransform& camera_from_world, const TraceOptions& options,
                                 int samples_per_axis = 1, int threads = 0,
                                 const std::function<void(int, int)>& progress = {});

}  // namespace glasspiv
