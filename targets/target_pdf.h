#pragma once
// A target as a PDF at exact scale (cairo's PDF surface): the page of
// target_page() (pattern, margin, caption and 100 mm scale bar), one page of
// target_svg_size_mm() mm, i.e. mm * 72 / 25.4 points, drawn as vector fills
// and text (a speckle plate's dots as circular arcs). See docs/targets.md.
#include <string>

#include "targets/target_spec.h"

namespace glasspiv {

// The PDF file's bytes. margin_mm < 0: default_margin_mm(). Throws InputError
// for an invalid spec or when cairo fails.
std::string target_pdf(const TargetSpec& spec, double margin_mm = -1);

// Writes target_pdf() atomically (util/atomic_file.h).
void write_target_pdf(const std::string& path, const TargetSpec& spec);

// PDF points per millimetre: 72 points to the inch.
constexpr double kPdfPointsPerMm = 72.0 / 25.4;

}  // namespace glasspiv
