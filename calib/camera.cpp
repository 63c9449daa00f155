#include "calib/camera.h"

#include <cmath>

#include "util/input_error.h"

namespace glasspiv {
namespace {
double pixel_pitch_mm(double pixel_pitch_um) {
  if (!(std::isfinite(pixel_pitch_um) && pixel_pitch_um > 0))
    throw InputError("", "pixel_pitch_um", "must be a positive, finite pixel size in micrometres");
  return pixel_pitch_um * 1e-3;
}
}  // namespace

DavisStyleIntrinsics to_davis_style(const CameraModel& model, double pixel_pitch_um) {
  const double pitch_mm = pixel_pitch_mm(pixel_pitch_um);
  return {model.fx_px() * pitch_mm, model.fy_px() * pitch_mm, pixel_pitch_um, model.cx_px(), model.cy_px()};
}

void from_davis_style(const DavisStyleIntrinsics& davis, double* fx_px, double* fy_px, double* cx_px,
                      double* cy_px) {
  const double pitch_mm = pixel_pitch_mm(davis.pixel_pitch_um);
  *fx_px = davis.focal_length_x_mm / pitch_mm;
  *fy_px = davis.focal_length_y_mm / pitch_mm;
  *cx_px = davis.principal_point_x_px;
  *cy_px = davis.principal_point_y_px;
}

}  // namespace glasspiv
