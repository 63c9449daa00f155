#pragma once
// The scene file of a fitted model: what `glasspiv align fit` writes. The
// drawing's Scene with every value the fit changed, so that the fitted model
// is read back as any scene is. No I/O.
//  - Glass spheres: every one explicit (a packing's spheres are written out as
//    `type: sphere` solids, in the packing's order, with their material), at its
//    fitted centre and diameter; the packings are removed.
//  - Glass index: each glass material a solid uses becomes "<name>_fitted", a
//    constant index (relative to air, as the scene format takes it) equal to the
//    fitted index at the scene's wavelength. Dispersion is not kept: the fitted
//    scene holds at its wavelength only (docs/alignment.md).
//  - The sheet: its fitted origin and axes (the plate's pose); extent and
//    thickness kept.
//  - Cameras: each fitted camera's pose; a fitted focal scale writes that camera
//    inline with fx, fy scaled.
#include <vector>

#include "calib/rigid_transform.h"
#include "render/path_tracer.h"
#include "render/scene.h"

namespace glasspiv {

struct FittedCamera {
  int scene_camera = 0;  // index into Scene::cameras
  RigidTransform camera_from_world;
  double focal_scale = 1;
};

// `fitted`: the fitted TraceScene, built from `drawing` by build_trace_scene
// (same solids in the same order). Throws std::invalid_argument when the
// solid counts differ.
Scene fitted_scene(const Scene& drawing, const TraceScene& fitted, const std::vector<FittedCamera>& cameras);

}  // namespace glasspiv
