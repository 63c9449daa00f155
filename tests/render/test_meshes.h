#pragma once
// Meshes the render tests share: an icosphere with exact radial normals and a
// grid-tessellated cube with exact vertex coordinates.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
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

// The surface of the cube [0, n]^3 as an n x n grid of squares per face, each
// split into two triangles: every vertex and edge midpoint has exact (integer
// or half-integer) coordinates.
inline MeshArrays grid_cube(int n) {
  MeshArrays a;
  std::map<std::array<int, 3>, std::uint32_t> index;
  auto vertex = [&](std::array<int, 3> p) {
    const auto it = index.find(p);
    if (it != index.end()) return it->second;
    a.vertices_mm.emplace_back(p[0], p[1], p[2]);
    return index[p] = static_cast<std::uint32_t>(a.vertices_mm.size() - 1);
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side : {0, n}) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;  // e_u x e_v = e_axis
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          auto at = [&](int di, int dj) {
            std::array<int, 3> p{};
            p[axis] = side;
            p[u] = i + di;
            p[v] = j + dj;
            return vertex(p);
          };
          const std::uint32_t p00 = at(0, 0), p10 = at(1, 0), p11 = at(1, 1), p01 = at(0, 1);
          // Alternate the diagonal so vertices have 4, 6 and 8 triangles around them.
          std::array<MeshTriangle, 2> two = (i + j) % 2 ? std::array<MeshTriangle, 2>{{{p00, p10, p11}, {p00, p11, p01}}}
                                                        : std::array<MeshTriangle, 2>{{{p00, p10, p01}, {p10, p11, p01}}};
          for (MeshTriangle t : two) {
            if (side == 0) std::swap(t[1], t[2]);  // outward is -axis there
            a.triangles.push_back(t);
          }
        }
    }
  return a;
}

}  // namespace glasspiv
