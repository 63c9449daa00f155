#pragma once
// What a calibration sees: per view (one photo), the detected target corners,
// each with its id, its pixel and its point on the board. Produced by
// targets/ detection (or by synthesis), consumed by the intrinsic fit.
#include <string>
#include <vector>

#include <Eigen/Core>

namespace glasspiv {

struct CornerObservation {
  int id = 0;                                                 // corner id on the board
  Eigen::Vector2d pixel_px = Eigen::Vector2d::Zero();         // glasspiv pixel convention
  Eigen::Vector3d board_point_mm = Eigen::Vector3d::Zero();   // board frame, z = 0 on the board
};

struct ViewObservations {
  std::string source;  // the photo it came from (or a synthetic view's name)
  std::vector<CornerObservation> corners;
};

struct Observations {
  int image_width_px = 0, image_height_px = 0;  // all views share one sensor
  std::string target_name;
  std::vector<ViewObservations> views;

  std::size_t corner_count() const {
    std::size_t n = 0;
    for (const auto& v : views) n += v.corners.size();
    return n;
  }
};

}  // namespace glasspiv
