#pragma once
// The picture of the setup itself, to hold against a photograph (alignment):
// what the camera sees of the glass, the opaque parts, textured rectangles
// (targets, markers) and the background, through every refraction and
// reflection the tracer follows. Unlike the forward render it is traced per
// image (no map): it is made once per alignment step, not per PIV frame.
// No I/O.
//
// Light model (simple on purpose; only edges and markers have to line up with
// the photograph): a branch that leaves the scene sees background_radiance; a
// branch that ends on an opaque solid sees ambient * albedo * texture(u, v)
// (texture 1 where there is none), u and v in mm along the rectangle's right
// and up axes from its centre. The sheet is not drawn (its light is the PIV
// image's, not the setup's).
#include <functional>
#include <vector>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "render/path_tracer.h"
#include "render/sheet_texture.h"

namespace glasspiv {

struct SetupLook {
  double background_radiance = 0;
  double ambient = 1;
  // Per solid index; nullptr (or a shorter vector) = untextured. Placement on a
  // rectangle follows SheetTexture (centred, column along right, row along -up).
  std::vector<const SheetTexture*> textures;
};

struct SetupRenderStats {
  long camera_rays = 0, branches_traced = 0, unproject_failures = 0, closed_form_rays = 0;
  int threads = 0;
};

// Row-major width x height radiance; samples_per_axis^2 stratified samples per
// pixel, averaged. Deterministic for any thread count.
std::vector<float> render_setup(const TraceScene& scene, const SetupLook& look, const CameraModel& camera,
                                const RigidTransform& camera_from_world, const TraceOptions& options,
                                int samples_per_axis = 2, int threads = 0,
                                const std::function<void(int, int)>& progress = {},
                                SetupRenderStats* stats = nullptr);
// The same with an index made from `scene` once (renders of one scene from
// many poses, as alignment makes them, need not rebuild it).
std::vector<float> render_setup(const TraceScene& scene, const SceneIndex& index, const SetupLook& look,
                                const CameraModel& camera, const RigidTransform& camera_from_world,
                                const TraceOptions& options, int samples_per_axis = 2, int threads = 0,
                                const std::function<void(int, int)>& progress = {},
                                SetupRenderStats* stats = nullptr);

}  // namespace glasspiv
