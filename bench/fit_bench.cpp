// fit_bench: time and residual of glasspiv's intrinsic fit against
// cv::calibrateCamera and mrcal on the same synthetic corners.
//
//   fit_bench [runs]        (default 5: each timing is the best of `runs`)
//
// Two lenses (opencv5: 2048x1536, fx 2400, mild; opencv8: 2560x1600, fx 1500,
// strong rational), a 12x9-corner board of 20 mm squares, 20 views at tilts up
// to +-35 degrees, N(0, 0.1 px) noise per axis (seeded; the same data the fit
// tests use). The pixels are rounded to float first, so that OpenCV (which
// takes float corners) and the others see identical numbers.
//
// Rows: glasspiv fit_intrinsics with the outlier loop and the covariance off
// (what calibrateCamera does), then with its defaults (outlier loop and
// covariance on); cv::calibrateCamera (CALIB_RATIONAL_MODEL for opencv8); mrcal
// (python3-mrcal, if installed: the time spent inside mrcal.optimize, measured
// in python, all 3 passes of tests/calib/fit/mrcal_fit.py; seeding and python
// start-up excluded). Each first on
// one thread, then with the default threads (glasspiv num_threads = 0, OpenCV's
// default cv::setNumThreads; mrcal is single-threaded).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <thread>

#include <sys/utsname.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

#include "calib/fit/intrinsic_fit.h"
#include "calib/lens_maps.h"
#include "mrcal_peer.h"
#include "opencv_peer.h"
#include "sim/calibration_views.h"
#include "truth_cameras.h"

namespace {

using namespace glasspiv;

double best_seconds(int runs, const std::function<void()>& run) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < runs; ++i) {
    const auto start = std::chrono::steady_clock::now();
    run();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

struct Lens {
  const char* name;
  CameraModel truth;
};

struct Row {
  std::string implementation;
  std::string threads;
  double seconds;
  double rms_px;
  std::optional<CameraModel> camera;
};


void bench_lens(const Lens& lens, int runs) {
  const LensModel model = lens.truth.lens_model();
  SyntheticBoard board;
  std::mt19937 rng(2);
  const std::vector<RigidTransform> poses = plan_views(lens.truth, board, {}, rng);
  Observations obs = observe_board(lens.truth, board, poses, 0.1, rng);
  for (ViewObservations& v : obs.views)
    for (CornerObservation& c : v.corners)
      c.pixel_px = Eigen::Vector2d(static_cast<float>(c.pixel_px.x()), static_cast<float>(c.pixel_px.y()));

  std::vector<Row> rows;
  const int default_threads = cv::getNumThreads();
  IntrinsicFitOptions bare;
  bare.lens_model = model;
  bare.outlier_k = 0;
  bare.compute_uncertainty = false;
  IntrinsicFitOptions defaults;
  defaults.lens_model = model;
  for (int threads : {1, 0}) {
    for (const IntrinsicFitOptions* options : {&bare, &defaults}) {
      IntrinsicFitOptions o = *options;
      o.num_threads = threads;
      std::optional<IntrinsicFit> fit;
      const double t = best_seconds(runs, [&] { fit = fit_intrinsics(obs, o); });
      rows.push_back({options == &bare ? "glasspiv fit_intrinsics (no outlier loop, no covariance)"
                                       : "glasspiv fit_intrinsics (defaults: outlier loop, covariance)",
                      threads == 1 ? "1" : "default (" + std::to_string(std::thread::hardware_concurrency()) + ")", t,
                      fit->rms_px, fit->camera});
    }
    cv::setNumThreads(threads == 1 ? 1 : default_threads);
    CameraModel opencv = lens.truth;
    double rms = 0;
    const double t = best_seconds(runs, [&] { rms = testing::opencv_calibrate(obs, model, &opencv); });
    rows.push_back({"cv::calibrateCamera", threads == 1 ? "1" : "default (" + std::to_string(default_threads) + ")", t,
                    rms, opencv});
  }
  cv::setNumThreads(default_threads);

  std::string error;
  const std::string work = (std::filesystem::temp_directory_path() / "glasspiv_fit_bench").string();
  std::filesystem::create_directories(work);
  std::optional<testing::MrcalFit> mrcal;
  for (int i = 0; i < std::min(runs, 3); ++i) {
    auto fit = testing::run_mrcal_fit(obs, board, model, 1.1 * lens.truth.fx_px(), work, GLASSPIV_SOURCE_DIR, &error);
    if (!fit) break;
    if (!mrcal || fit->optimize_seconds < mrcal->optimize_seconds) mrcal = fit;
  }
  if (mrcal)
    rows.push_back({"mrcal.optimize (python3-mrcal, 3 passes, time in python)", "1", mrcal->optimize_seconds,
                    mrcal->rms_px, mrcal->camera});
  else
    std::printf("(%s: mrcal skipped: %s)\n", lens.name, error.c_str());

  // References: OpenCV's single-thread time and RMS; its model for the difference.
  const Row* opencv_row = nullptr;
  for (const Row& r : rows)
    if (r.implementation == "cv::calibrateCamera" && r.threads == "1") opencv_row = &r;
  for (const Row& r : rows) {
    const double diff = projection_difference(*opencv_row->camera, *r.camera, 1000, 32).rms_px;
    std::printf("| %-7s | %-62s | %-11s | %6.1f | %8.2fx | %.9f | %+.1e | %9.1e |\n", lens.name,
                r.implementation.c_str(), r.threads.c_str(), 1e3 * r.seconds, opencv_row->seconds / r.seconds, r.rms_px,
                r.rms_px - opencv_row->rms_px, diff);
  }
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 5;
  if (argc > 1) runs = std::atoi(argv[1]);
  if (runs <= 0) {
    std::fprintf(stderr, "usage: fit_bench [runs]\n");
    return 2;
  }
  utsname host{};
  uname(&host);
  std::printf("fit_bench: 20 views of a 12x9-corner board, 0.1 px noise; best of %d runs (mrcal: best of %d)\n", runs,
              std::min(runs, 3));
  std::printf("machine: %s %s, %u hardware threads; OpenCV %s; compiler %s\n", host.sysname, host.machine,
              std::thread::hardware_concurrency(), CV_VERSION, __VERSION__);
  std::printf(
      "vs OpenCV: cv::calibrateCamera's single-thread time / this row's time (> 1: faster); RMS: "
      "sqrt(mean |r|^2) over the corners, px; dRMS: minus OpenCV's RMS; diff: RMS projection difference to "
      "OpenCV's model over the image, px.\n\n");
  std::printf(
      "| lens    | implementation                                                 | threads     |     ms | "
      "vs OpenCV | RMS px      | dRMS px  | diff px   |\n");
  std::printf(
      "|---------|----------------------------------------------------------------|-------------|-------:|"
      "----------:|-------------|---------:|----------:|\n");
  const Lens lenses[] = {
      {"opencv5", testing::truth_opencv5()},
      {"opencv8", testing::truth_opencv8()},
  };
  for (const Lens& lens : lenses) bench_lens(lens, runs);
  return 0;
}
