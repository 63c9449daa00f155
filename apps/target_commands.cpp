// glasspiv target print | show
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include <fmt/format.h>

#include "apps/cli_files.h"
#include "apps/commands.h"
#include "targets/speckle_plate.h"
#include "targets/target_image.h"
#include "targets/target_pdf.h"
#include "targets/target_spec.h"
#include "targets/target_yaml.h"
#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

struct PrintOptions {
  std::string spec, page, png;  // page: the -o file, SVG or PDF by its extension
  double dpi = 300;
};

void run_print(const PrintOptions& o) {
  if (o.page.empty() && o.png.empty())
    throw InputError("", "-o", "give -o BOARD.svg (or BOARD.pdf), --png BOARD.png or both");
  const std::string page_format = o.page.empty() ? "" : lower_extension(o.page);
  if (!o.page.empty() && page_format != ".svg" && page_format != ".pdf")
    throw InputError(o.page, "-o", "must end in .svg or .pdf");
  if (!o.png.empty() && lower_extension(o.png) != ".png") throw InputError(o.png, "--png", "must end in .png");
  if (!(o.dpi > 0) || o.dpi > 2400) throw InputError("", "--dpi", fmt::format("must be in (0, 2400], got {:.6g}", o.dpi));
  std::vector<OutputFile> outputs;
  if (!o.page.empty()) outputs.push_back({o.page, "-o"});
  if (!o.png.empty()) outputs.push_back({o.png, "--png"});
  check_outputs({o.spec}, outputs);
  const TargetSpec spec = read_target_yaml(o.spec);
  std::printf("%s\n", describe_target(spec).c_str());
  // Both drawn into their temporaries first; renamed only when both succeeded,
  // so a failure leaves neither (and no earlier file replaced).
  std::vector<AtomicFileWriter> writers;
  if (!o.page.empty()) {
    const std::string bytes = page_format == ".pdf" ? target_pdf(spec) : target_svg(spec);
    writers.push_back({o.page, [bytes, path = o.page](const std::string& tmp) {
                         std::ofstream out(tmp, std::ios::binary);
                         out << bytes;
                         out.flush();
                         if (!out) throw InputError(path, "", "write failed (disk full?)");
                       }});
  }
  if (!o.png.empty())
    writers.push_back({o.png, [&spec, dpi = o.dpi](const std::string& tmp) { write_target_png(tmp, spec, dpi); }});
  write_files_atomically(writers);
  if (!o.page.empty()) {
    const Eigen::Vector2d page = target_svg_size_mm(spec);
    std::printf("wrote %s: %.1f x %.1f mm page. Print at 100 %% scale (no \"fit to page\") and check that the bar "
                "under the board measures 100 mm.\n",
                o.page.c_str(), page.x(), page.y());
  }
  if (!o.png.empty()) {
    const Eigen::Vector2d board = board_size_mm(spec);
    const double margin = default_margin_mm(spec);
    std::printf("wrote %s at %g dpi (%.1f x %.1f mm with its margin; the resolution is stored in the PNG, which has "
                "no caption or scale bar: measure %s after printing)\n",
                o.png.c_str(), o.dpi, board.x() + 2 * margin, board.y() + 2 * margin,
                spec.kind == TargetKind::speckle ? "the plate" : "a square");
  }
}

void run_show(const std::string& path) {
  const TargetSpec spec = read_target_yaml(path);
  const Eigen::Vector2d size = board_size_mm(spec);
  std::printf("target '%s' (%s)\n", spec.name.c_str(), path.c_str());
  TargetSpec unnamed = spec;
  unnamed.name.clear();
  std::printf("  %s\n", describe_target(unnamed).c_str());
  std::printf("  pattern %g x %g mm (without margin); printed with a %g mm white margin\n", size.x(), size.y(),
              default_margin_mm(spec));
  if (spec.kind == TargetKind::speckle) {
    const SpeckleGrid g = speckle_grid(spec);
    std::printf("  %zu dots of %g mm, one in each cell of a %d x %d grid (cells %.17g x %.17g mm; pitch %.17g mm "
                "for fill %g, diameter / pitch %.17g)\n",
                g.dot_count(), spec.dot_diameter_mm, g.cols, g.rows, g.cell_width_mm, g.cell_height_mm, g.pitch_mm,
                spec.fill, g.diameter_over_pitch);
    std::printf("  no corners: a texture for photometric fitting, not for calib detect or align fiducials\n");
    return;
  }
  const std::size_t corners = board_corner_count(spec);
  int w = 0, h = 0;
  double spacing = 0;
  if (is_single_marker(spec.kind))
    std::printf("  4 corners: ids 0 to 3 = the top-left, top-right, bottom-right, bottom-left corner of the %s\n",
                spec.kind == TargetKind::apriltag ? "square libapriltag detects" : "black border");
  else if (corner_grid(spec, w, h, spacing))
    std::printf("  %zu corners: a %d x %d grid, %g mm apart, ids row by row from the top-left (id 0 at %g, %g mm)\n",
                corners, w, h, spacing, spacing, spacing);
  else
    std::printf("  %zu corners: 4 per tag (top-left, top-right, bottom-right, bottom-left), id = 4 * tag index + "
                "corner\n",
                corners);
  const std::vector<BoardMarker> markers = board_markers(spec);
  if (is_single_marker(spec.kind))
    std::printf("  %s %d of %s\n", spec.kind == TargetKind::apriltag ? "tag" : "marker", spec.first_id,
                spec.dictionary.c_str());
  else if (!markers.empty())
    std::printf("  %zu %s, ids %d to %d\n", markers.size(), spec.kind == TargetKind::aprilgrid ? "tags" : "markers",
                markers.front().id, markers.back().id);
  if (spec.kind == TargetKind::charuco) {
    if (spec.squares_y % 2 == 0) {
      const std::string corner = square_is_black(spec, 0, 0)
                                     ? std::string("black (OpenCV >= 4.6.0)")
                                     : fmt::format("white with marker {} (OpenCV < 4.6.0)", spec.first_id);
      std::printf("  %d rows (even): the %s layout, top-left square %s\n", spec.squares_y,
                  charuco_layout_name(spec.charuco_layout).c_str(), corner.c_str());
    } else {
      std::printf("  %d rows (odd): the opencv and legacy layouts are the same board\n", spec.squares_y);
    }
  }
}

}  // namespace

void register_target_commands(CLI::App& app) {
  CLI::App* target = app.add_subcommand("target", "Calibration targets: print a board, show a target spec");
  target->require_subcommand(1);

  auto print = std::make_shared<PrintOptions>();
  CLI::App* p = target->add_subcommand(
      "print", "Draw a target spec as an SVG or PDF at exact scale (caption and 100 mm check bar) and/or a PNG at "
               "--dpi");
  p->add_option("spec", print->spec, "Target spec YAML (docs/targets.md)")->required()->check(CLI::ExistingFile);
  p->add_option("-o,--output", print->page, "SVG or PDF to write, by its extension (exact scale, print at 100 %)");
  p->add_option("--png", print->png, "PNG to write as well (board and margin only)");
  p->add_option("--dpi", print->dpi, "Resolution of the PNG, dots per inch")->capture_default_str();
  p->callback([print] { run_print(*print); });

  auto show = std::make_shared<std::string>();
  CLI::App* s = target->add_subcommand("show", "Print a target spec: kind, size in mm, corners, markers, layout");
  s->add_option("spec", *show, "Target spec YAML")->required()->check(CLI::ExistingFile);
  s->callback([show] { run_show(*show); });
}

}  // namespace glasspiv
