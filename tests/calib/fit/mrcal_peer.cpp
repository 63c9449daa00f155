#include "mrcal_peer.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace glasspiv::testing {

std::optional<MrcalFit> run_mrcal_fit(const Observations& observations, const SyntheticBoard& board,
                                      LensModel lens_model, double focal_estimate_px, const std::string& work_dir,
                                      const std::string& source_dir, std::string* error) {
  const std::string python = python_with_mrcal();
  if (python.empty()) {
    *error = "python3 with mrcal (python3-mrcal) is not installed";
    return std::nullopt;
  }
  std::string model_name = lens_model_name(lens_model);
  for (char& ch : model_name) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  const std::string in_path = work_dir + "/mrcal_in.json", out_path = work_dir + "/mrcal_out.txt";
  {
    std::ofstream out(in_path);
    out.precision(17);
    out << "{\"width\": " << observations.image_width_px << ", \"height\": " << observations.image_height_px
        << ", \"lensmodel\": \"LENSMODEL_" << model_name << "\", \"board_cols\": " << board.cols
        << ", \"board_rows\": " << board.rows << ", \"spacing_mm\": " << board.spacing_mm
        << ", \"focal_estimate_px\": " << focal_estimate_px << ", \"views\": [";
    for (std::size_t v = 0; v < observations.views.size(); ++v) {
      out << (v ? ",\n[" : "\n[");
      const auto& corners = observations.views[v].corners;
      for (std::size_t c = 0; c < corners.size(); ++c)
        out << (c ? ", [" : "[") << std::lround(corners[c].board_point_mm.x() / board.spacing_mm) << ", "
            << std::lround(corners[c].board_point_mm.y() / board.spacing_mm) << ", " << corners[c].pixel_px.x() << ", "
            << corners[c].pixel_px.y() << "]";
      out << "]";
    }
    out << "]}\n";
  }
  const std::string command =
      "'" + python + "' '" + source_dir + "/tests/calib/fit/mrcal_fit.py' '" + in_path + "' '" + out_path + "'";
  if (std::system(command.c_str()) != 0) {
    *error = "failed: " + command;
    return std::nullopt;
  }
  std::ifstream in(out_path);
  std::string line;
  std::getline(in, line);
  std::istringstream values(line);
  std::vector<double> intrinsics;
  for (double x; values >> x;) intrinsics.push_back(x);
  double rms = NAN, seconds = NAN;
  in >> rms >> seconds;
  if (intrinsics.size() != 4u + static_cast<unsigned>(lens_model) || !std::isfinite(rms)) {
    *error = "unreadable output " + out_path;
    return std::nullopt;
  }
  MrcalFit fit{CameraModel(observations.image_width_px, observations.image_height_px, intrinsics[0], intrinsics[1],
                           intrinsics[2], intrinsics[3], std::vector<double>(intrinsics.begin() + 4, intrinsics.end())),
               rms, seconds};
  return fit;
}

}  // namespace glasspiv::testing
