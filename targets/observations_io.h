#pragma once
// Files of detected target corners (Observations, calib/observations.h):
//
//   glasspiv YAML (.yaml/.yml) or JSON (.json), docs/targets.md:
//     glasspiv_observations: 1
//     image_size_px: [4096, 3000]
//     target: charuco_11x8_15mm
//     views:
//       - source: shots/0001.png
//         corners:              # [id, x_px, y_px, board_x_mm, board_y_mm, board_z_mm]
//           - [0, 512.25, 384.5, 15, 15, 0]
//   numbers at full precision, so a file reads back exactly.
//
//   mrcal's corners.vnl (write only): "# filename x y level", then per view one
//   line per grid corner in row-major order ("filename x y 0", or "filename - - -"
//   for a corner not seen), or "filename - -" for a view without detections.
//   mrcal's pixel convention is glasspiv's.
#include <string>
#include <string_view>

#include "calib/observations.h"
#include "targets/target_spec.h"

namespace glasspiv {

enum class ObservationsFormat { yaml, json };

// .yaml / .yml -> yaml, .json -> json; InputError naming the path otherwise.
ObservationsFormat observations_format_for_path(const std::string& path);

// Throws InputError (file `path`) for anything malformed: unknown keys, wrong
// types, non-finite numbers, negative or repeated ids in a view, a pixel
// outside the image.
Observations parse_observations(std::string_view contents, ObservationsFormat format, const std::string& path);
std::string format_observations(const Observations& observations, ObservationsFormat format);

Observations read_observations(const std::string& path);                           // format by extension
void write_observations(const std::string& path, const Observations& observations);  // format by extension, atomic

// mrcal's corners.vnl for a chessboard or charuco target (its corners form the
// regular grid mrcal needs; an aprilgrid's do not: InputError). File names
// with white space cannot be written (InputError naming `path`).
std::string format_mrcal_corners_vnl(const Observations& observations, const TargetSpec& spec,
                                     const std::string& path = "");
void write_mrcal_corners_vnl(const std::string& path, const Observations& observations, const TargetSpec& spec);

}  // namespace glasspiv
