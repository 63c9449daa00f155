#include "piv/vector_file.h"

#include <sstream>

#include <fmt/format.h>

#include "util/atomic_file.h"
#include "util/input_error.h"
#include "util/text_number.h"

namespace glasspiv {

std::string vector_file_text(const PivField& field, const std::vector<std::string>& comment_lines) {
  const InterrogationGrid& g = field.grid;
  std::string out = "# glasspiv piv vectors (docs/piv.md)\n";
  for (const std::string& line : comment_lines) out += "# " + line + "\n";
  out += fmt::format("# grid: {} x {} vectors (cols x rows), window {} px, step {} px\n", g.cols, g.rows, g.window_px,
                     g.step_px);
  out +=
      "# x_px y_px: window centre, (0, 0) = centre of the top-left pixel, x right, y down\n"
      "# u_px v_px: displacement of frame B relative to frame A, u along +x, v along +y (px)\n"
      "# flag: 0 valid, 1 replaced (median test), 2 invalid or masked (u v nan)\n"
      "# peak_ratio: highest / second correlation peak (1 = ambiguous), 0 where none\n"
      "# x_px y_px u_px v_px flag peak_ratio\n";
  for (std::size_t i = 0; i < field.size(); ++i)
    out += fmt::format("{} {} {} {} {} {}\n", format_number(field.x_px(i)), format_number(field.y_px(i)),
                       format_number(field.u_px[i]), format_number(field.v_px[i]), static_cast<int>(field.flags[i]),
                       format_number(field.peak_ratio[i]));
  return out;
}

std::string vector_file_vtk(const PivField& field, const std::string& title) {
  const InterrogationGrid& g = field.grid;
  std::string out = "# vtk DataFile Version 3.0\n";
  std::string t = title.substr(0, 255);
  for (char& c : t)
    if (c == '\n' || c == '\r') c = ' ';
  out += t + "\nASCII\nDATASET STRUCTURED_POINTS\n";
  out += fmt::format("DIMENSIONS {} {} 1\nORIGIN {} {} 0\nSPACING {} {} 1\nPOINT_DATA {}\n", g.cols, g.rows,
                     format_number(g.x_px(0)), format_number(g.y_px(0)), g.step_px, g.step_px, field.size());
  out += "VECTORS displacement_px double\n";
  for (std::size_t i = 0; i < field.size(); ++i) {
    const bool ok = field.flags[i] != VectorFlag::invalid;
    out += fmt::format("{} {} 0\n", format_number(ok ? field.u_px[i] : 0.0), format_number(ok ? field.v_px[i] : 0.0));
  }
  out += "SCALARS flag int 1\nLOOKUP_TABLE default\n";
  for (std::size_t i = 0; i < field.size(); ++i) out += fmt::format("{}\n", static_cast<int>(field.flags[i]));
  out += "SCALARS peak_ratio double 1\nLOOKUP_TABLE default\n";
  for (std::size_t i = 0; i < field.size(); ++i) out += format_number(field.peak_ratio[i]) + "\n";
  return out;
}

void write_vector_files(const std::string& text_path, const std::string& vtk_path, const PivField& field,
                        const std::vector<std::string>& comment_lines) {
  std::vector<AtomicFileWriter> writers;
  const std::string text = vector_file_text(field, comment_lines);
  auto write_string = [](const std::string& contents) {
    return [contents](const std::string& temporary) {
      std::FILE* f = std::fopen(temporary.c_str(), "wb");
      const bool ok = f && std::fwrite(contents.data(), 1, contents.size(), f) == contents.size();
      if (f && std::fclose(f) != 0) throw InputError(temporary, "", "cannot be written");
      if (!ok) throw InputError(temporary, "", "cannot be written");
    };
  };
  writers.emplace_back(text_path, write_string(text));
  if (!vtk_path.empty()) writers.emplace_back(vtk_path, write_string(vector_file_vtk(field, "glasspiv piv vectors")));
  write_files_atomically(writers);
}

std::vector<VectorRecord> read_vector_file(const std::string& path) {
  std::istringstream in(read_file(path));
  std::vector<VectorRecord> out;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::string w[7];
    int n = 0;
    while (n < 7 && words >> w[n]) ++n;
    const auto x = parse_number(w[0]), y = parse_number(w[1]), u = parse_number(w[2]), v = parse_number(w[3]),
               flag = parse_number(w[4]), ratio = parse_number(w[5]);
    if (n != 6 || !x || !y || !u || !v || !flag || !ratio || (*flag != 0 && *flag != 1 && *flag != 2))
      throw InputError(path, fmt::format("line {}", number), "not 'x_px y_px u_px v_px flag peak_ratio'");
    out.push_back({*x, *y, *u, *v, static_cast<int>(*flag), *ratio});
  }
  return out;
}

}  // namespace glasspiv
