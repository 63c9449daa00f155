#include "sim/marker_setup.h"

#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "util/atomic_file.h"

namespace glasspiv {

std::string write_marker_setup(const std::string& folder, const MarkerSetupOptions& o) {
  std::filesystem::create_directories(folder);
  std::string solids;
  // Markers on two rectangular rings (z = 0 and z = depth), each ring walked
  // around its perimeter; the inner ring is smaller so that no marker hides another.
  const int per_ring = (o.markers + 1) / 2;
  for (int i = 0; i < o.markers; ++i) {
    const int ring = i < per_ring ? 0 : 1;
    const int k = ring == 0 ? i : i - per_ring, n = ring == 0 ? per_ring : o.markers - per_ring;
    const double half_w = ring == 0 ? 95.0 : 70.0, half_h = ring == 0 ? 75.0 : 55.0;
    const double perimeter = 4 * (half_w + half_h), s = perimeter * (k + 0.5) / n;
    double x, y;
    if (s < 2 * half_w) {
      x = -half_w + s, y = half_h;
    } else if (s < 2 * half_w + 2 * half_h) {
      x = half_w, y = half_h - (s - 2 * half_w);
    } else if (s < 4 * half_w + 2 * half_h) {
      x = half_w - (s - 2 * half_w - 2 * half_h), y = -half_h;
    } else {
      x = -half_w, y = -half_h + (s - 4 * half_w - 2 * half_h);
    }
    const std::string spec = fmt::format("marker_{:02d}.yaml", i);
    write_file_atomically((std::filesystem::path(folder) / spec).string(),
                          fmt::format("glasspiv_target: 1\nkind: aruco_marker\ndictionary: DICT_4X4_50\n"
                                      "marker_id: {}\nmarker_size_mm: {}\n",
                                      i, o.marker_size_mm));
    // The rectangle holds the marker and its white quiet zone.
    const double side = 2 * o.marker_size_mm;
    solids += fmt::format(
        "  - type: rectangle\n    centre_mm: [{:.6f}, {:.6f}, {:.6f}]\n    size_mm: [{:.6f}, {:.6f}]\n"
        "    normal: [0, 0, -1]\n    up: [0, 1, 0]\n    texture: {}\n",
        x, y, ring * o.depth_mm, side, side, spec);
  }
  if (o.window_thickness_mm > 0)
    solids += fmt::format(
        "  - type: slab\n    point_mm: [0, 0, {:.6f}]\n    normal: [0, 0, 1]\n    thickness_mm: {:.6f}\n"
        "    extent_mm: [600, 600]\n    up: [0, 1, 0]\n    material: N-BK7\n",
        -100 - o.window_thickness_mm, o.window_thickness_mm);
  const std::string scene = fmt::format(
      "glasspiv_scene: 1\n# A frame of ArUco markers (sim/marker_setup.h).\nwavelength_nm: 532\nfluid: air\n"
      "solids:\n{}"
      "sheet: {{origin_mm: [0, 0, 30], s_axis: [1, 0, 0], t_axis: [0, 1, 0], extent_mm: [150, 120], thickness_mm: 1}}\n"
      "background: {{radiance: 0.35}}\n"
      "cameras:\n  - name: cam\n"
      "    model: {{image_size_px: [{}, {}], lens_model: opencv5, focal_length_px: [{}, {}],\n"
      "            principal_point_px: [{}, {}], distortion_coefficients: [-0.08, 0.05, 0.0003, -0.0002, 0.01]}}\n"
      "    pose: {{position_mm: [23, -17, {}], look_at_mm: [2, 3, 30], up: [0.03, 1, 0]}}\n",
      solids, o.width_px, o.height_px, o.focal_px, o.focal_px * 1.0004, 0.5 * (o.width_px - 1) + 7.3,
      0.5 * (o.height_px - 1) - 4.1, -o.camera_distance_mm);
  const std::string path = (std::filesystem::path(folder) / "scene.yaml").string();
  write_file_atomically(path, scene);
  return path;
}

}  // namespace glasspiv
