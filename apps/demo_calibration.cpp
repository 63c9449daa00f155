#include "apps/demo_calibration.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>

#include "apps/calibration_report.h"
#include "apps/photo_detection.h"
#include "calib/fit/calibration_diagnostics.h"
#include "calib/io/camera_file.h"
#include "calib/lens_maps.h"
#include "sim/calibration_views.h"
#include "sim/target_photo.h"
#include "targets/observations_io.h"
#include "targets/target_image.h"
#include "targets/target_yaml.h"
#include "util/atomic_file.h"
#include "util/input_error.h"
#include "util/progress_bar.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

// The session: 20 views (mrcal and OpenCV both advise many well-spread, tilted
// views), the board tilted up to 45 degrees (its distances: DemoCalibrationViews), and a sensor with
// shot noise (4000 e- at white) and 1 DN read noise. Fixed seeds: the demo is
// reproducible to the bit.
constexpr int kViews = 20;
constexpr double kMaxTiltDeg = 45;
constexpr std::uint32_t kPoseSeed = 2026;
constexpr double kBoardPxPerMm = 12;  // render finer than the photos' footprint of a board millimetre

}  // namespace

DemoCalibrationSummary run_calibration_demo(const std::string& folder, const std::string& truth_camera_path,
                                            const std::string& target_path, const DemoCalibrationViews& views) {
  const fs::path dir(folder);
  const Camera truth = read_camera(truth_camera_path);
  const TargetSpec spec = read_target_yaml(target_path);
  const TargetRender board = render_target(spec, kBoardPxPerMm, default_margin_mm(spec));
  const auto poses = calibration_view_poses(truth.model, board_size_mm(spec), kViews, views.near_mm, views.far_mm,
                                              kMaxTiltDeg, kPoseSeed);

  std::printf("   photographing the board from %d views...\n", kViews);
  std::vector<std::string> photos;
  {
    ProgressBar bar("photographing", poses.size());
    for (std::size_t v = 0; v < poses.size(); ++v) {
      SensorOptions sensor;
      sensor.photons_at_white = 4000;
      sensor.read_noise = 1.0;
      sensor.seed = static_cast<std::uint32_t>(100 + v);
      const cv::Mat photo = render_target_photo(truth.model, poses[v], board, sensor);
      const std::string path = (dir / "photos" / fmt::format("view_{:02d}.png", v)).string();
      write_file_atomically_with(path, [&](const std::string& temporary) {
        if (!cv::imwrite(temporary, photo)) throw InputError(path, "", "cannot write the photo");
      });
      photos.push_back(path);
      bar.advance();
    }
  }

  // From here on, exactly what `glasspiv calib intrinsics photos/ --target T` does.
  std::printf("   detecting the corners in the %zu photos...\n", photos.size());
  PhotoDetectionOptions detection;
  detection.quiet = true;
  const Observations observations = detect_in_photos(photos, spec, target_path, detection);
  write_observations((dir / "observations.yaml").string(), observations);
  std::printf("   fitting the intrinsics and cross-validating...\n");
  IntrinsicFitOptions options;
  options.lens_model = truth.model.lens_model();
  const IntrinsicFit fit = fit_intrinsics(observations, options);
  const CrossValidation cv = cross_validation(observations, options);
  // "session_truth" -> "session_fitted".
  std::string name = truth.name;
  if (name.size() > 6 && name.compare(name.size() - 6, 6, "_truth") == 0) name.resize(name.size() - 6);
  const Camera fitted{name + "_fitted", fit.camera, std::nullopt, truth.pixel_pitch_um};
  write_cameras((dir / (fitted.name + ".yaml")).string(), {fitted});
  std::printf("   writing the report...\n");
  const CalibrationReportFiles files =
      write_calibration_report((dir / "report").string(), {observations, options, fit, &cv, fitted.name,
                                                            truth.pixel_pitch_um, Camera{truth}});

  DemoCalibrationSummary s;
  s.rms_px = fit.rms_px;
  s.truth_difference_rms_px = projection_difference(truth.model, fit.camera, 1000.0, 16.0).rms_px;
  s.truth_difference_rotated_rms_px =
      projection_difference(truth.model, fit.camera, 1000.0, 16.0, implied_rotation(truth.model, fit.camera, 16.0))
          .rms_px;
  s.focal_error_rel = std::abs(fit.camera.fx_px() - truth.model.fx_px()) / truth.model.fx_px();
  s.principal_point_error_px = std::hypot(fit.camera.cx_px() - truth.model.cx_px(), fit.camera.cy_px() - truth.model.cy_px());
  s.report_html = files.html;
  s.fitted = fitted;
  return s;
}

}  // namespace glasspiv
