#include "render/packing.h"

#include <cmath>

#include <fmt/format.h>

namespace glasspiv {

LatticeGeometry lattice_geometry(Lattice lattice, double diameter_mm) {
  const double d = diameter_mm;
  LatticeGeometry g;
  switch (lattice) {
    case Lattice::sc:
      g.pitch_mm = d;
      g.layer_spacing_mm = d;
      g.odd_layers_shifted = false;
      g.cubic_cell_mm = d;
      break;
    case Lattice::bcc:
      g.cubic_cell_mm = 2 * d / std::sqrt(3.0);
      g.pitch_mm = g.cubic_cell_mm;
      g.layer_spacing_mm = g.cubic_cell_mm / 2;
      g.odd_layers_shifted = true;
      break;
    case Lattice::fcc:
      g.cubic_cell_mm = d * std::sqrt(2.0);
      g.pitch_mm = d;
      g.layer_spacing_mm = d / std::sqrt(2.0);
      g.odd_layers_shifted = true;
      break;
  }
  return g;
}

namespace {
std::array<int, 2> layer_grid(const Packing& packing, int layer) {
  const bool shifted = lattice_geometry(packing.lattice, packing.diameter_mm).odd_layers_shifted && layer % 2 == 1;
  const int nx = packing.layer_size[0] - (shifted ? 1 : 0);
  const int ny = packing.layer_size[1] - (shifted ? 1 : 0);
  return {std::max(nx, 0), std::max(ny, 0)};
}
}  // namespace

int spheres_in_layer(const Packing& packing, int layer) {
  const auto grid = layer_grid(packing, layer);
  return grid[0] * grid[1];
}

Eigen::Vector3d packing_sphere_centre(const Packing& packing, int layer, int i, int j) {
  const LatticeGeometry g = lattice_geometry(packing.lattice, packing.diameter_mm);
  const double shift = g.odd_layers_shifted && layer % 2 == 1 ? g.pitch_mm / 2 : 0.0;
  return packing.origin_mm + Eigen::Vector3d(i * g.pitch_mm + shift, j * g.pitch_mm + shift, layer * g.layer_spacing_mm);
}

std::vector<SphereSolid> expand_packing(const Packing& packing) {
  std::vector<SphereSolid> spheres;
  for (int layer = 0; layer < packing.layers; ++layer) {
    const auto grid = layer_grid(packing, layer);
    for (int j = 0; j < grid[1]; ++j)
      for (int i = 0; i < grid[0]; ++i) {
        SphereSolid s;
        s.centre_mm = packing_sphere_centre(packing, layer, i, j);
        s.diameter_mm = packing.diameter_mm;
        s.material = packing.material;
        for (const PackingOverride& o : packing.overrides) {
          bool hit = false;
          if (o.sphere) hit = (*o.sphere)[0] == layer && (*o.sphere)[1] == i && (*o.sphere)[2] == j;
          if (o.region_mm)
            hit = ((s.centre_mm.array() >= (*o.region_mm)[0].array()) &&
                   (s.centre_mm.array() <= (*o.region_mm)[1].array())).all();
          if (hit) s.material = o.material;
        }
        s.field = fmt::format("{}.spheres[{},{},{}]", packing.field.empty() ? "packing" : packing.field, layer, i, j);
        spheres.push_back(std::move(s));
      }
  }
  return spheres;
}

}  // namespace glasspiv
