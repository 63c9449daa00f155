#pragma once
// The target spec file (YAML, docs/targets.md):
//
//   glasspiv_target: 1
//   kind: charuco            # chessboard | charuco | aprilgrid | aruco_marker | apriltag
//   squares: [11, 8]         # across, down (aprilgrid: tags: [6, 6])
//   square_size_mm: 15       # aprilgrid: tag_size_mm
//   marker_size_mm: 11       # charuco only; aprilgrid: tag_spacing_mm (the gap)
//   dictionary: DICT_5X5_100 # charuco: an OpenCV name; aprilgrid: tag36h11
//   first_id: 0              # optional, default 0
//   charuco_layout: opencv   # optional, default opencv; or legacy
//   name: lab board A        # optional, default the file's stem
//
// A single fiducial marker:
//
//   glasspiv_target: 1
//   kind: aruco_marker       # or apriltag
//   dictionary: DICT_4X4_50  # apriltag: a libapriltag family, tag36h11 ...
//   marker_id: 7             # apriltag: tag_id
//   marker_size_mm: 40       # apriltag: tag_size_mm
//
// A speckle plate (targets/speckle_plate.h):
//
//   glasspiv_target: 1
//   kind: speckle
//   plate_size_mm: [150, 120] # the pattern area, width and height
//   dot_diameter_mm: 0.5
//   fill: 0.4                # the fraction of the area inked, (0, 0.7]
//   seed: 1                  # an unsigned 64-bit integer, in digits
//
// Readers reject unknown keys, keys of another kind, wrong types and invalid
// values with InputError(file, field, problem).
#include <string>
#include <string_view>

#include "targets/target_spec.h"

namespace glasspiv {

// `path` names the source in errors and gives the default name (its stem).
TargetSpec parse_target_yaml(std::string_view contents, const std::string& path);
TargetSpec read_target_yaml(const std::string& path);

// Validates, then serialises; sizes are written at full precision.
std::string format_target_yaml(const TargetSpec& spec);
void write_target_yaml(const std::string& path, const TargetSpec& spec);

}  // namespace glasspiv
