#pragma once
// The corrected image on the camera's own grid: the reconstructed sheet seen by
// the same camera with the glass removed (same lens, pose, pixels), so that
// existing calibrations and PIV settings keep working (docs/correction.md).
// No I/O.
#include <cstdint>
#include <vector>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "correct/cell_mask.h"
#include "correct/correction_operator.h"
#include "render/transport_map.h"

namespace glasspiv {

// The camera's transport map with every solid removed (same fluid and sheet):
// each pixel's ray meets the sheet once, directly, with its footprint.
TransportMap glass_removed_map(const TraceScene& scene, const CameraModel& camera,
                               const RigidTransform& camera_from_world, int samples_per_axis = 1, int threads = 0);

// Median side length sqrt|det J| of the pixels' footprints on the sheet (mm):
// the sheet grid that matches the camera's own resolution. 0 for a map with no crossings.
double median_footprint_mm(const TransportMap& map);

// Pixel-by-cell resampling of a sheet field onto the glass-free camera,
// restricted to valid cells and renormalised over them: a pixel whose
// footprint has at least min_valid_fraction of its weight on valid cells gets
// the weighted mean of those cells and is valid; other pixels get 0.
struct CameraResampler {
  int width = 0, height = 0;
  std::vector<std::uint32_t> pixel_offsets, cell;
  std::vector<float> value;
  std::vector<std::uint8_t> pixel_valid;  // 255 valid, 0 not
};

CameraResampler make_camera_resampler(const CorrectionOperator& glass_removed, const std::vector<CellState>& states,
                                      double min_valid_fraction = 0.5);

// image = resampled sheet (width * height values).
void resample_to_camera(const CameraResampler& r, const float* sheet, float* image);

}  // namespace glasspiv
