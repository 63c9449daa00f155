#include "align/scene_fiducials.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <utility>

#include <fmt/format.h>

#include "targets/target_yaml.h"
#include "util/input_error.h"

namespace glasspiv {

bool is_target_file(const std::string& texture_path) {
  std::string ext = std::filesystem::path(texture_path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".yaml" || ext == ".yml";
}

TargetRender rectangle_target_texture(const TargetSpec& spec) {
  return render_target(spec, kTargetTexturePxPerMm, default_margin_mm(spec));
}

RigidTransform world_from_board_on_rectangle(const RectangleSolid& rect, const TargetSpec& spec,
                                             const TargetRender& texture, const std::string& scene_source) {
  const Eigen::Vector3d normal = rect.normal.normalized();
  const Eigen::Vector3d right = rect.up.cross(normal).normalized();
  const Eigen::Vector3d up = normal.cross(right);
  // The renderer centres the texture: texel column c lies at s = (c - (cols - 1) / 2) / px_per_mm
  // along right, row r at t = -(r - (rows - 1) / 2) / px_per_mm along up; board x maps to texel
  // (x + margin) * px_per_mm - 0.5 (targets/target_image.h).
  const double width_mm = texture.image.cols / texture.px_per_mm;
  const double height_mm = texture.image.rows / texture.px_per_mm;
  const Eigen::Vector2d pattern_mm = board_size_mm(spec);
  const double s0 = texture.margin_mm - 0.5 * width_mm, t0 = 0.5 * height_mm - texture.margin_mm;
  // The pattern itself must lie on the rectangle (the margin may be cut).
  const double half_w = std::max(std::abs(s0), std::abs(s0 + pattern_mm.x()));
  const double half_h = std::max(std::abs(t0), std::abs(t0 - pattern_mm.y()));
  if (half_w > 0.5 * rect.size_mm[0] + 1e-9 || half_h > 0.5 * rect.size_mm[1] + 1e-9)
    throw InputError(scene_source, rect.field + ".size_mm",
                     fmt::format("the target ({:.6g} x {:.6g} mm) does not fit on the {:.6g} x {:.6g} mm rectangle",
                                 pattern_mm.x(), pattern_mm.y(), rect.size_mm[0], rect.size_mm[1]));
  RigidTransform world_from_board;
  world_from_board.rotation.col(0) = right;
  world_from_board.rotation.col(1) = -up;
  world_from_board.rotation.col(2) = right.cross(-up);
  world_from_board.translation_mm = rect.centre_mm + s0 * right + t0 * up;
  return world_from_board;
}

std::vector<SceneFiducial> scene_fiducials(const Scene& scene) {
  std::vector<SceneFiducial> out;
  for (std::size_t i = 0; i < scene.rectangles.size(); ++i) {
    const RectangleSolid& rect = scene.rectangles[i];
    if (rect.texture.empty() || !is_target_file(rect.texture)) continue;
    SceneFiducial f;
    f.rectangle = static_cast<int>(i);
    f.field = rect.field;
    f.target_file = rect.texture;
    f.spec = read_target_yaml(rect.texture);
    if (f.spec.kind == TargetKind::speckle) continue;  // a texture without corners, not a fiducial
    f.world_from_board = world_from_board_on_rectangle(rect, f.spec, rectangle_target_texture(f.spec), scene.source);
    f.corners_board = board_corners(f.spec);
    out.push_back(std::move(f));
  }
  // Marker ids must name one fiducial per dictionary.
  std::map<std::pair<std::string, int>, const SceneFiducial*> owner;
  for (const SceneFiducial& f : out) {
    for (const BoardMarker& m : board_markers(f.spec)) {
      const auto key = std::make_pair(f.spec.dictionary, m.id);
      const auto [it, fresh] = owner.emplace(key, &f);
      if (!fresh && it->second != &f)
        throw InputError(scene.source, f.field,
                         fmt::format("marker {} of {} is also on {}: a photo could not tell them apart", m.id,
                                     f.spec.dictionary, it->second->field));
    }
  }
  return out;
}

}  // namespace glasspiv
