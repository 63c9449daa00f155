#pragma once
// What the correction commands (correct, coverage) and the demo share: a
// scene's cameras made ready for correction on one sheet grid, each with its
// correction operator, from the caches when they are valid (an operator found
// in its cache needs no transport map at all: nothing is traced).
#include <cstdint>
#include <string>
#include <vector>

#include "correct/camera_resampler.h"
#include "correct/cell_mask.h"
#include "correct/correction_defaults.h"
#include "correct/correction_operator.h"
#include "render/path_tracer.h"
#include "render/scene.h"

namespace glasspiv {

struct CorrectionSettings {
  TraceOptions trace = correction_trace_options();
  int samples = 1;           // per pixel axis, for the map
  OperatorOptions op;
  MaskOptions mask;
  int binning = 1;           // cameras read out K x K binned
  std::string cache_dir;     // "" = no cache
  int threads = 0;
  bool report = true;        // print what was traced, built or reused
};

struct CorrectionCamera {
  std::string name, field;   // field: where the scene defines it, for errors
  CameraModel model;
  RigidTransform pose;
  CorrectionOperator op;
  std::uint64_t op_fingerprint = 0;  // correction_operator_fingerprint: what op was built from
};

struct CorrectionScene {
  Scene scene;
  TraceScene trace;
  std::vector<CorrectionCamera> cameras;
};

// Reads the scene and builds its trace scene; InputError for a scene without a
// sheet or cameras. No camera is prepared yet.
CorrectionScene read_correction_scene(const std::string& path);

// Index of the camera called name in scene.cameras; "" = the first. InputError
// (field `field`) naming the cameras the scene has for an unknown name.
int find_camera(const Scene& scene, const std::string& name, const std::string& field);

// The glass-removed view of camera index: its map, and the median pixel
// footprint on the sheet (the default grid pitch). InputError if it does not see the sheet.
struct GlassRemovedView {
  TransportMap map;
  double footprint_mm = 0;
};
GlassRemovedView glass_removed_view(const CorrectionScene& cs, int camera_index, const CorrectionSettings& s);

// Adds camera index on grid to cs.cameras (map and operator from the caches
// or traced and built, printed when s.report). InputError if the camera sees
// none of the sheet.
void add_correction_camera(CorrectionScene& cs, int camera_index, const SheetGrid& grid, const CorrectionSettings& s);

std::vector<CameraOperator> camera_operators(const CorrectionScene& cs);

// The cache files add_correction_camera reads and writes for camera index
// ("" when s.cache_dir is empty): its transport map, and its operator on a
// grid of cols x rows (op "" when cols is 0).
struct CorrectionCacheFiles {
  std::string map, op;
};
CorrectionCacheFiles correction_cache_files(const Scene& scene, int camera_index, const CorrectionSettings& s,
                                            int cols = 0, int rows = 0);

}  // namespace glasspiv
