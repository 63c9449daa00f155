#pragma once
// The pixel at which a camera sees a world point through the traced model
// (refraction-aware projection): the inverse of "trace the pixel's ray and see
// where it lands". A fiducial corner seen through a window, a wall or a
// packing of glass spheres appears displaced, so the plain pinhole projection
// of the corner is wrong; the pose fit uses this projection instead.
// Double precision, mm, px. No I/O.
//
// Method: Newton on the pixel. The map F(pixel) = where the refracted-only
// path of the pixel's camera ray meets the plane of the target rectangle,
// expressed in that plane's 2-D axes (right, up) relative to the point; its
// root is the sought pixel. The Jacobian dF/dpixel comes from central
// differences on the pixel (OpaqueHit carries no ray differentials). Steps are
// backtracked (halved) until the residual |F| decreases and the path stays
// valid; they are clamped to the image. Where the path passes beside the
// rectangle into the background, F continues on the rectangle's infinite plane
// along the last segment, so a start just off the marker still converges.
// A point seen along several paths (directly and through a sphere, or as the
// images of neighbouring spheres) has several solutions; Newton finds the one
// whose basin holds start_px.
#include <Eigen/Core>
#include <functional>
#include <vector>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "render/path_tracer.h"

namespace glasspiv {

struct TracedProjectionOptions {
  double tolerance_mm = 1e-7;  // |F| at the solution, in the target plane
  int max_iterations = 20;     // Newton steps
  // Tracing of every pixel ray. reflections is forced off (only the refracted
  // path is wanted: with it off the tree is a single path); min_weight is kept
  // tiny so that a path near grazing incidence is not cut by its Fresnel loss.
  TraceOptions trace{false, 1e-12, 32};
};

enum class TracedProjectionStatus {
  ok,             // converged: the pixel's refracted path meets target_solid first, at the point to tolerance_mm
  not_converged,  // max_iterations spent, or no step reduced |F| (pixel_px: best iterate, not an observation)
  blocked,        // the path meets another opaque solid first (at start_px, or wherever a step led): the point
                  // is hidden, at least along the images reachable from start_px
  left_image,     // the solution lies outside the image [-0.5, width - 0.5] x [-0.5, height - 0.5]
  no_path,        // the refracted path does not reach the target plane: total internal reflection, cut by
                  // depth, a pixel the lens cannot unproject, or the point is not on the rectangle
};

const char* to_string(TracedProjectionStatus status);

struct TracedProjection {
  TracedProjectionStatus status = TracedProjectionStatus::no_path;
  Eigen::Vector2d pixel_px = Eigen::Vector2d::Zero();  // meaningful only when ok
  int iterations = 0;                                  // Newton steps taken (the final polishing step included)
  double residual_mm = 0;                              // |F| at pixel_px (infinity when no path)
  // d(in-plane point, right and up axes)/d(pixel col, row) at pixel_px, mm per px
  // (central differences); its inverse is d(pixel)/d(in-plane point). Zero unless ok.
  Eigen::Matrix2d dplane_dpixel = Eigen::Matrix2d::Zero();

  bool ok() const { return status == TracedProjectionStatus::ok; }
};

// The pixel at which the camera (model, camera_from_world) sees point_world_mm,
// which lies on the opaque Rectangle scene.solids[target_solid] (a marker),
// through everything in the scene. index must have been made from scene.
// start_px: the Newton start (e.g. the pinhole projection), clamped into the
// image. A point seen with no glass in between converges to its pinhole
// projection in one or two steps. Throws std::invalid_argument when
// target_solid is not an opaque Rectangle of the scene.
TracedProjection project_through_scene(const TraceScene& scene, const SceneIndex& index, const CameraModel& model,
                                       const RigidTransform& camera_from_world, const Eigen::Vector3d& point_world_mm,
                                       int target_solid, const Eigen::Vector2d& start_px,
                                       const TracedProjectionOptions& options = {});

// A projector for the extrinsic fit (the shape of calib/fit/extrinsic_fit.h's
// PointProjector): projector(camera_from_world, i, &pixel) projects
// points_world_mm[i], lying on scene.solids[target_solids[i]], through the scene
// and returns false unless the status is ok. Each solve starts from the pinhole
// projection of the point under the given pose (no warm start from an earlier
// solution), so the pixel depends on the pose alone and a caller that
// differentiates numerically sees a smooth, repeatable function; Newton then
// converges far below tolerance_mm. A point behind the camera returns false.
// scene and index are held by reference and must outlive the projector; it may
// be called from several threads at once. Throws std::invalid_argument when
// the two vectors differ in length or a target is not an opaque Rectangle.
std::function<bool(const RigidTransform& camera_from_world, int point_index, Eigen::Vector2d* pixel_px)>
traced_point_projector(const TraceScene& scene, const SceneIndex& index, const CameraModel& model,
                       std::vector<Eigen::Vector3d> points_world_mm, std::vector<int> target_solids,
                       const TracedProjectionOptions& options = {});

}  // namespace glasspiv
