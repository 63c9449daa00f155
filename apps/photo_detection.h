#pragma once
// Finding a target in a set of photos: loading (8/16-bit, grey or colour),
// detection, a progress bar, a line per photo, optional overlay pictures, and the
// checks a session needs (one sensor size; the target found at least once).
// Shared by `calib detect`, `calib intrinsics` and the demo.
#include <string>
#include <vector>

#include "apps/cli_files.h"

#include "calib/observations.h"
#include "targets/target_spec.h"

namespace glasspiv {

struct PhotoDetectionOptions {
  std::string overlay_dir;      // write each photo with its corners and ids as PNG here ("" = none)
  bool lenient_layout = false;  // ChArUco even rows: keep views that do not prove the layout
  bool quiet = false;           // no per-photo lines on stdout
};

// Photos named directly, and the image files (tif, tiff, png, jpg, jpeg, bmp)
// inside folders, sorted by name. InputError for a path that does not exist or a
// folder without images.
std::vector<std::string> expand_photo_inputs(const std::vector<std::string>& inputs);

// The overlay PNG detect_in_photos writes for each photo (photos order) into
// `overlay_dir`: <stem>_corners.png, numbered _2, _3 ... for repeated stems.
// Empty when overlay_dir is "".
std::vector<std::string> overlay_paths(const std::vector<std::string>& photos, const std::string& overlay_dir);

// A file or folder a calib command writes, the option that names it ("-o",
// "--report", "--overlay-dir", ...) and its kind (OutputKind::folder for a folder).
using CalibOutput = OutputFile;

// Before any detection or fit: apps/cli_files.h check_outputs of the outputs
// given (empty paths are skipped) against the inputs (empty ones skipped).
void check_calib_outputs(const std::vector<std::string>& inputs, const std::vector<CalibOutput>& outputs);

// Detects `spec` in every photo. `target_path` names the spec in errors.
// Throws InputError for a photo given twice, before any detection: the same
// file (a folder and a file in it, a link) or a copy with the same bytes
// (util/file_identity.h), as one view counted twice would shrink a fit's
// uncertainty; for an unreadable photo (naming it), photos of different sizes
// (naming the file and both sizes), or a target found in none of them.
Observations detect_in_photos(const std::vector<std::string>& photos, const TargetSpec& spec,
                              const std::string& target_path, const PhotoDetectionOptions& options);

}  // namespace glasspiv
