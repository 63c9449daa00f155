#pragma once
// A plate photographed in the sheet plane, as the model fit sees it: the
// target's picture at exact scale laid on the sheet (align/model_fit.h
// PlatePicture). The plate's centre is the sheet's origin, its x axis (board
// right) the sheet's s axis, its y axis (board down) the sheet's -t axis: the
// plate defines the sheet. No I/O.
#include <memory>

#include "align/model_fit.h"
#include "render/sheet_texture.h"
#include "targets/target_spec.h"

namespace glasspiv {

struct PlateTexture {
  std::unique_ptr<SheetTexture> texture;  // 1 = paper, 0 = ink
  double width_mm = 0, height_mm = 0;     // the pattern (board_size_mm)

  PlatePicture picture() const { return {texture.get(), width_mm, height_mm}; }
};

// The target's pattern rendered with exact area coverage at mm_per_texel
// (targets/target_image.h target_ink_coverage). The raster's last row and column may reach
// past the pattern (white): the texture's centre is placed where the pattern's
// centre lands, so the plate stays centred on the sheet origin to round-off.
// Throws InputError for an invalid spec or a raster over render_target's limit.
PlateTexture plate_texture(const TargetSpec& spec, double mm_per_texel);

}  // namespace glasspiv
