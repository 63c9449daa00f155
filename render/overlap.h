#pragma once
// Do two solids of a scene overlap? The tracer needs solids that at most touch
// (inside a solid it only looks for that solid's own surface), so the scene
// builder refuses overlaps. No I/O.
//
// Exact for sphere-sphere, sphere-box, box-box (separating axes) and
// sphere-cylinder; for pairs involving a mesh, or a cylinder and a box or
// another cylinder, a sampled test: surface points of each solid (mesh
// vertices and triangle centres; box corners, edge and face grids; cylinder
// rims and side grid) tested against the other. The sampled test finds every
// overlap deeper than the sampling's spacing (about 1/8 of the smaller solid)
// and may miss a thinner sliver. Rectangles have no inside and are skipped.
#include <optional>
#include <utility>
#include <vector>

#include "render/shapes.h"

namespace glasspiv {

// The first overlapping pair (i < j, in index order) by more than
// tolerance_mm, or std::nullopt. Pairs whose bounding boxes are apart are
// skipped (sweep along x), so large packings cost ~n log n.
std::optional<std::pair<int, int>> find_overlap(const std::vector<Shape>& shapes, double tolerance_mm = 1e-6);

// Whether two solids overlap by more than tolerance_mm (see above).
bool overlap(const Shape& a, const Shape& b, double tolerance_mm = 1e-6);

}  // namespace glasspiv
