#pragma once
// Fiducials fixed to the setup: scene rectangles whose texture is a target spec
// (.yaml). One description drives both the rendered picture of the setup (the
// board as printed, at true scale, centred on the rectangle) and the 3-D corner
// positions the pose needs. See docs/alignment.md.
//
// The board frame (targets/target_spec.h: origin at the pattern's top-left
// corner, x right, y down, mm) sits on the rectangle so that board x runs along
// the rectangle's right axis (up x normal) and board y along -up; the pattern
// with its white margin is centred on the rectangle, exactly as the texture
// rectangle_target_texture() makes is placed by the renderer.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/rigid_transform.h"
#include "render/scene.h"
#include "targets/target_image.h"
#include "targets/target_spec.h"

namespace glasspiv {

// Texels per mm of a target drawn on a scene rectangle: sharp edges for any
// camera that resolves less than 20 px per mm of the setup.
constexpr double kTargetTexturePxPerMm = 20.0;

// True for a texture path that names a target spec (.yaml, .yml).
bool is_target_file(const std::string& texture_path);

// The board as printed with its default margin, at kTargetTexturePxPerMm.
TargetRender rectangle_target_texture(const TargetSpec& spec);

// world_from_board of a target drawn on `rect` from `texture` (as the renderer
// places it). Throws InputError(scene_source, rect.field + ".size_mm", ...)
// when the pattern does not fit on the rectangle (it would be cut off).
RigidTransform world_from_board_on_rectangle(const RectangleSolid& rect, const TargetSpec& spec,
                                             const TargetRender& texture, const std::string& scene_source = "");

struct SceneFiducial {
  int rectangle = 0;            // index into Scene::rectangles
  std::string field;            // the rectangle's field in the scene file ("solids[4]")
  std::string target_file;      // the target spec it carries
  TargetSpec spec;
  RigidTransform world_from_board;
  std::vector<BoardCorner> corners_board;  // board_corners(spec), by id

  Eigen::Vector3d corner_world_mm(const BoardCorner& corner) const { return world_from_board.apply(corner.point_mm); }
};

// Every rectangle of the scene that carries a target spec with corners, in
// scene order; the specs are read and validated (InputError naming the spec
// file). A speckle plate (TargetKind::speckle) has no corners: its rectangle is
// drawn (rectangle_target_texture) but is no fiducial. Two single
// markers of one dictionary with the same id, or a marker id that a board of the
// same dictionary also uses, are an InputError naming both fields: a detection
// could not tell them apart.
std::vector<SceneFiducial> scene_fiducials(const Scene& scene);

}  // namespace glasspiv
