#include "render/packing.h"

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "util/input_error.h"

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

std::uint64_t packing_sphere_count(const Packing& packing) {
  if (packing.layers < 1 || packing.layer_size[0] < 1 || packing.layer_size[1] < 1) return 0;
  // In double: exact below 2^53, and the comparisons with the limits need no more.
  const std::array<int, 2> even = layer_grid(packing, 0), odd = layer_grid(packing, 1);
  const double even_layers = std::ceil(packing.layers / 2.0), odd_layers = std::floor(packing.layers / 2.0);
  const double n = even_layers * double(even[0]) * double(even[1]) + odd_layers * double(odd[0]) * double(odd[1]);
  if (!(n < 18446744073709549568.0)) return std::numeric_limits<std::uint64_t>::max();
  return static_cast<std::uint64_t>(n);
}

Eigen::Vector3d packing_sphere_centre(const Packing& packing, int layer, int i, int j) {
  const LatticeGeometry g = lattice_geometry(packing.lattice, packing.diameter_mm);
  const double shift = g.odd_layers_shifted && layer % 2 == 1 ? g.pitch_mm / 2 : 0.0;
  return packing.origin_mm + Eigen::Vector3d(i * g.pitch_mm + shift, j * g.pitch_mm + shift, layer * g.layer_spacing_mm);
}

std::vector<SphereSolid> expand_packing(const Packing& packing) {
  const std::uint64_t count = packing_sphere_count(packing);
  if (count > kMaxSceneSolids)
    throw InputError("", packing.field,
                     fmt::format("expands to {} spheres, more than the {} solids a scene may hold", count,
                                 kMaxSceneSolids));
  std::vector<SphereSolid> spheres;
  spheres.reserve(static_cast<std::size_t>(count));
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
