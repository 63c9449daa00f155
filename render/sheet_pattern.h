#pragma once
// Pictures to lay on the sheet (or on a rectangle) when no image file is
// given: a checkerboard, a line grid, and a seeded field of Gaussian particle
// images like a PIV recording's. Each covers a given extent centred on the
// origin, in the SheetTexture convention. No I/O.
#include <cstdint>
#include <vector>

namespace glasspiv {

struct SheetPicture {
  int rows = 0, cols = 0;
  double mm_per_texel = 1;
  std::vector<float> values;  // row-major, in [0, 1]
};

// Squares of square_mm, a corner on the origin; texels_per_square texels each.
SheetPicture checkerboard_picture(double extent_s_mm, double extent_t_mm, double square_mm,
                                  int texels_per_square = 8);

// Lines of width line_mm every pitch_mm (a line through the origin), value 1 on
// the lines, 0 between, area-sampled at mm_per_texel.
SheetPicture grid_picture(double extent_s_mm, double extent_t_mm, double pitch_mm, double line_mm,
                          double mm_per_texel);

// Particles at a uniform random density (per mm^2), each a Gaussian of
// diameter_mm at 1/e^2 with peak 1, summed and clipped to 1; seeded
// (std::mt19937_64), so the same arguments give the same picture.
SheetPicture particle_picture(double extent_s_mm, double extent_t_mm, double particles_per_mm2, double diameter_mm,
                              double mm_per_texel, std::uint64_t seed);

}  // namespace glasspiv
