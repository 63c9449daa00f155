#pragma once
// Meshes the render tests share: an icosphere with exact radial normals.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "render/triangle_mesh.h"

namespace glasspiv {

inline double signed_volume(const MeshArrays& a) {
  double v = 0;
  for (const MeshTriangle& t : a.triangles)
    v += a.vertices_mm[t[0]].dot(a.vertices_mm[t[1]].cross(a.vertices_mm[t[2]])) / 6;
  return v;
}

// An icosahedron subdivided `level` times (each triangle into four), the new
// vertices projected onto the sphere: radius r, centre c, outward winding; the
// normals are the exact radial ones (per vertex).
inline MeshArrays icosphere(int level, double r = 20, const Eigen::Vector3d& c = Eigen::Vector3d::Zero()) {
  const double g = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> unit = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                                {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (Eigen::Vector3d& u : unit) u.normalize();
  std::vector<MeshTriangle> tri = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                   {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                   {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                   {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middle;
    auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = middle.find(key);
      if (it != middle.end()) return it->second;
      unit.push_back((unit[a] + unit[b]).normalized());
      return middle[key] = static_cast<std::uint32_t>(unit.size() - 1);
    };
    std::vector<MeshTriangle> next;
    for (const MeshTriangle& t : tri) {
      const std::uint32_t ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({t[1], bc, ab});
      next.push_back({t[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    tri = std::move(next);
  }
  MeshArrays a;
  for (const Eigen::Vector3d& u : unit) {
    a.vertices_mm.push_back(c + r * u);
    a.normals.push_back(u);
  }
  a.triangles = tri;
  if (signed_volume(a) < 0)
    for (MeshTriangle& t : a.triangles) std::swap(t[1], t[2]);
  return a;
}

}  // namespace glasspiv
