#pragma once
// The model's adjustable parts, as alignment and the sensitivity analysis vary
// them: every glass solid moved together, every glass solid's refractive index
// offset together, the focal length scaled. No I/O.
#include <Eigen/Core>

#include "calib/camera_model.h"
#include "render/path_tracer.h"

namespace glasspiv {

// The scene with every glass solid moved by offset_mm (world axes) and its
// refractive index offset by refractive_index_offset. Spheres, boxes (slabs),
// cylinders and rectangles move; a glass triangle mesh is kept in place (its
// vertices and bounds would be rebuilt: not done), as are opaque solids.
TraceScene adjusted_glass(const TraceScene& scene, double refractive_index_offset, const Eigen::Vector3d& offset_mm);

// True when adjusted_glass would leave some glass in place (a glass mesh).
bool has_fixed_glass(const TraceScene& scene);

// The camera with fx and fy scaled by focal_scale (the principal point and the
// distortion kept).
CameraModel scaled_focal(const CameraModel& camera, double focal_scale);

}  // namespace glasspiv
