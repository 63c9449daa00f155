#include "targets/target_pdf.h"

#include <cairo-pdf.h>
#include <cairo.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "targets/target_image.h"
#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

cairo_status_t append_to_string(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

void check(cairo_status_t status, const char* what) {
  if (status != CAIRO_STATUS_SUCCESS)
    throw InputError("", "", std::string("PDF drawing failed (cairo, ") + what + "): " + cairo_status_to_string(status));
}

// One path for all rectangles: neighbouring cells of a marker then fill
// without the hairline seams separate fills leave in anti-aliasing viewers.
void fill_rects(cairo_t* cr, const std::vector<BoardRect>& rects) {
  for (const BoardRect& r : rects) cairo_rectangle(cr, r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
  cairo_fill(cr);
}

// One path of circles (arcs), filled by the non-zero rule: where dots overlap
// their union is black.
void fill_discs(cairo_t* cr, const std::vector<BoardDisc>& discs) {
  if (discs.empty()) return;
  for (const BoardDisc& d : discs) {
    cairo_new_sub_path(cr);
    cairo_arc(cr, d.x, d.y, d.radius, 0, 6.283185307179586);  // a full turn
    cairo_close_path(cr);
  }
  cairo_set_fill_rule(cr, CAIRO_FILL_RULE_WINDING);
  cairo_fill(cr);
}

// Caption text as printed: control characters (from a spec's name) as spaces.
std::string printable(std::string text) {
  for (char& c : text)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  return text;
}

}  // namespace

std::string target_pdf(const TargetSpec& spec, double margin_mm) {
  const TargetPage page = target_page(spec, margin_mm);
  std::string pdf;
  {
    const std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface(
        cairo_pdf_surface_create_for_stream(append_to_string, &pdf, page.size_mm.x() * kPdfPointsPerMm,
                                            page.size_mm.y() * kPdfPointsPerMm),
        cairo_surface_destroy);
    check(cairo_surface_status(surface.get()), "surface");
    cairo_pdf_surface_set_metadata(surface.get(), CAIRO_PDF_METADATA_TITLE, printable(page.title).c_str());
    cairo_pdf_surface_set_metadata(surface.get(), CAIRO_PDF_METADATA_CREATOR, "glasspiv target print");
    {
      const std::unique_ptr<cairo_t, decltype(&cairo_destroy)> context(cairo_create(surface.get()), cairo_destroy);
      cairo_t* cr = context.get();
      cairo_scale(cr, kPdfPointsPerMm, kPdfPointsPerMm);  // user units: mm
      cairo_set_source_rgb(cr, 1, 1, 1);
      cairo_paint(cr);
      cairo_set_source_rgb(cr, 0, 0, 0);
      fill_rects(cr, page.pattern);
      fill_discs(cr, page.discs);
      fill_rects(cr, page.scale_bar);
      cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
      cairo_set_font_size(cr, page.font_size_mm);
      for (const TargetPageText& line : page.caption) {
        cairo_move_to(cr, line.x_mm, line.baseline_mm);
        cairo_show_text(cr, printable(line.text).c_str());
      }
      cairo_show_page(cr);
      check(cairo_status(cr), "drawing");
    }
    cairo_surface_finish(surface.get());
    check(cairo_surface_status(surface.get()), "writing");
  }
  return pdf;
}

void write_target_pdf(const std::string& path, const TargetSpec& spec) {
  write_file_atomically(path, target_pdf(spec));
}

}  // namespace glasspiv
