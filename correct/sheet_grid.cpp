#include "correct/sheet_grid.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <yaml-cpp/yaml.h>

#include "util/text_number.h"

namespace glasspiv {

SheetGrid sheet_grid_covering(const SheetPlane& sheet, double mm_per_px) {
  if (!(mm_per_px > 0) || !std::isfinite(mm_per_px))
    throw std::invalid_argument("sheet grid: mm per pixel must be finite and positive");
  // The same count as render/sheet_pattern.h pictures of the sheet, so one at this pitch lies on the grid.
  const double cols = std::ceil(sheet.extent_s_mm / mm_per_px), rows = std::ceil(sheet.extent_t_mm / mm_per_px);
  if (!(cols * rows <= static_cast<double>(kMaxSheetGridCells)))
    throw std::invalid_argument("sheet grid: " + format_number(cols) + " x " + format_number(rows) +
                                " cells exceed the limit of " + std::to_string(kMaxSheetGridCells) +
                                " (choose a larger mm per pixel)");
  SheetGrid g;
  g.cols = std::max(1, static_cast<int>(cols));
  g.rows = std::max(1, static_cast<int>(rows));
  g.mm_per_px = mm_per_px;
  g.s0_mm = -0.5 * (g.cols - 1) * mm_per_px;
  g.t0_mm = 0.5 * (g.rows - 1) * mm_per_px;
  return g;
}

SheetGridPlacement sheet_grid_placement(const SheetGrid& grid, const SheetPlane& sheet) {
  return {sheet.origin_mm + grid.s0_mm * sheet.s_axis + grid.t0_mm * sheet.t_axis, grid.mm_per_px * sheet.s_axis,
          -grid.mm_per_px * sheet.t_axis};
}

std::string sheet_grid_yaml(const SheetGrid& grid, const SheetPlane& sheet, const std::string& scene_path) {
  const SheetGridPlacement w = sheet_grid_placement(grid, sheet);
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  const auto vector = [&out](const Eigen::Vector3d& v) {
    out << YAML::Flow << YAML::BeginSeq << v.x() << v.y() << v.z() << YAML::EndSeq;
  };
  out << YAML::BeginMap;
  out << YAML::Key << "glasspiv_sheet_grid" << YAML::Value << 1;
  out << YAML::Key << "scene" << YAML::Value << YAML::DoubleQuoted << scene_path;
  out << YAML::Key << "cols" << YAML::Value << grid.cols;
  out << YAML::Key << "rows" << YAML::Value << grid.rows;
  out << YAML::Key << "mm_per_px" << YAML::Value << grid.mm_per_px;
  out << YAML::Key << "s0_mm" << YAML::Value << grid.s0_mm;
  out << YAML::Key << "t0_mm" << YAML::Value << grid.t0_mm;
  out << YAML::Key << "cell00_centre_mm" << YAML::Value;
  vector(w.cell00_centre_mm);
  out << YAML::Key << "col_step_mm" << YAML::Value;
  vector(w.col_step_mm);
  out << YAML::Key << "row_step_mm" << YAML::Value;
  vector(w.row_step_mm);
  out << YAML::EndMap;
  if (!out.good()) throw std::invalid_argument("sheet_grid_yaml: " + out.GetLastError());
  return std::string("# glasspiv sheet grid (docs/correction.md): image column c, row r is the sheet point\n"
                     "# s = s0_mm + c * mm_per_px, t = t0_mm - r * mm_per_px, in the world\n"
                     "# cell00_centre_mm + c * col_step_mm + r * row_step_mm.\n") +
         out.c_str() + "\n";
}

}  // namespace glasspiv
