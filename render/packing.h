#pragma once
// Expanding a regular sphere packing (render/scene.h: Packing) into spheres.
//
// Every lattice is built from square layers in planes of constant z, stacked
// along +z; odd layers of bcc and fcc sit over the holes of the even ones,
// shifted by (pitch/2, pitch/2). With D the sphere diameter:
//   sc:  pitch D,            layer spacing D          (cubic cell a = D)
//   bcc: pitch a = 2D/sqrt3, layer spacing a/2 = D/sqrt3 (the [001] layers of the
//        cubic cell; a sphere touches its 8 neighbours in the layers above and
//        below, at a*sqrt3/2 = D, but not those in its own layer, at a)
//   fcc: pitch D,            layer spacing D/sqrt2   (square [001] layers of the
//        cubic cell a = D*sqrt2 seen along a face diagonal: 4 touching neighbours
//        in the layer, 4 above and 4 below)
// Even layers hold nx x ny spheres; odd bcc/fcc layers hold the (nx-1) x (ny-1)
// sites inside the first layer's footprint.
#include <cstdint>
#include <vector>

#include "render/scene.h"

namespace glasspiv {

struct LatticeGeometry {
  double pitch_mm = 0;          // in-layer spacing of neighbouring sites
  double layer_spacing_mm = 0;  // z distance between consecutive layers
  bool odd_layers_shifted = false;
  double cubic_cell_mm = 0;     // the conventional cubic cell a
};

LatticeGeometry lattice_geometry(Lattice lattice, double diameter_mm);

// Number of spheres in layer `layer` (0-based).
int spheres_in_layer(const Packing& packing, int layer);

// Number of spheres the packing expands to, computed without expanding it and
// without overflow (saturating at UINT64_MAX; 0 for non-positive counts).
std::uint64_t packing_sphere_count(const Packing& packing);

// The packing's spheres, layer by layer, j-major then i, with their material
// after the overrides and field "packings[k].spheres[layer,i,j]" (k from packing.field).
// Throws InputError("", packing.field, ...) before allocating anything if the
// packing holds more than kMaxSceneSolids spheres (render/scene.h).
std::vector<SphereSolid> expand_packing(const Packing& packing);

// The centre of sphere (layer, i, j); i, j index the layer's own grid.
Eigen::Vector3d packing_sphere_centre(const Packing& packing, int layer, int i, int j);

}  // namespace glasspiv
