#pragma once
// PIV vector files. Text (what OpenPIV and PIVlab users read: whitespace
// columns, '#' comments, one vector per line, row-major from the top-left):
//
//   # glasspiv piv vectors (docs/piv.md)
//   # ...free comment lines (frames, windows)...
//   # grid: 63 x 47 vectors (cols x rows), window 32 px, step 16 px
//   # x_px y_px: window centre, (0, 0) = centre of the top-left pixel, x right, y down
//   # u_px v_px: displacement of frame B relative to frame A, u along +x, v along +y (px)
//   # flag: 0 valid, 1 replaced (median test), 2 invalid or masked (u v nan)
//   # peak_ratio: highest / second correlation peak (1 = ambiguous), 0 where none
//   # x_px y_px u_px v_px flag peak_ratio
//   15.5 15.5 2.25 -0.75 0 4.1
//
// Numbers are written as the shortest text that reads back exactly. VTK
// legacy ASCII (STRUCTURED_POINTS, for ParaView; no VTK library needed) holds
// the same field: VECTORS displacement_px (u, v, 0; invalid as 0, 0, 0),
// SCALARS flag and peak_ratio. Writes are atomic (util/atomic_file.h).
#include <string>
#include <vector>

#include "piv/piv_evaluate.h"

namespace glasspiv {

std::string vector_file_text(const PivField& field, const std::vector<std::string>& comment_lines = {});
std::string vector_file_vtk(const PivField& field, const std::string& title);

// Writes the text file and, if vtk_path is not empty, the VTK file, both or
// neither (util/atomic_file.h write_files_atomically). InputError naming the path on failure.
void write_vector_files(const std::string& text_path, const std::string& vtk_path, const PivField& field,
                        const std::vector<std::string>& comment_lines = {});

// One line of a vector file, as read back.
struct VectorRecord {
  double x_px = 0, y_px = 0, u_px = 0, v_px = 0;
  int flag = 0;
  double peak_ratio = 0;
};
// Reads a text vector file as written above; InputError naming the path and line otherwise.
std::vector<VectorRecord> read_vector_file(const std::string& path);

}  // namespace glasspiv
