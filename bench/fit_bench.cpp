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
// default cv::setNumThreads; mrcal is single-threaded). For opencv8 also, on one
// thread: glasspiv's multi-start (calib/fit/multi_start.h, the winning start
// named) and cv::calibrateCamera run to convergence (1000 iterations, 1e-15).
//
// Then the projection uncertainty's cost on the default fit (its state
// covariance comes with the fit): one pixel, and the report's map (samples
// about max(w, h) / 48 px apart), for mrcal's board-frames method and the
// intrinsics-only one, with the centre's 1-sigma at infinity.
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

#include "calib/fit/calibration_diagnostics.h"
#include "calib/fit/intrinsic_fit.h"
#include "calib/fit/multi_start.h"
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


struct UncertaintyRow {
  std::string lens, method;
  double centre_px = 0, pixel_us = 0, map_ms = 0;
  int samples = 0;
};

// The uncertainty's cost on `fit`, single thread (the computation has no threads).
std::vector<UncertaintyRow> bench_uncertainty(const char* lens, const IntrinsicFit& fit, int runs) {
  std::vector<UncertaintyRow> out;
  const Eigen::Vector2d centre((fit.camera.width_px() - 1) / 2.0, (fit.camera.height_px() - 1) / 2.0);
  const double step = std::max(fit.camera.width_px(), fit.camera.height_px()) / 48.0;
  for (const UncertaintyMethod method : {UncertaintyMethod::board_frames, UncertaintyMethod::intrinsics_only}) {
    UncertaintyRow r{lens, uncertainty_method_name(method)};
    constexpr int kPixels = 200;
    r.pixel_us = 1e6 / kPixels * best_seconds(runs, [&] {
                   for (int i = 0; i < kPixels; ++i) r.centre_px = projection_uncertainty_at(fit, centre, kAtInfinity, method);
                 });
    GridValues map;
    r.map_ms = 1e3 * best_seconds(runs, [&] { map = projection_uncertainty(fit, kAtInfinity, step, method); });
    r.samples = map.grid.size();
    out.push_back(r);
  }
  return out;
}

std::vector<UncertaintyRow> bench_lens(const Lens& lens, int runs) {
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
  std::optional<IntrinsicFit> default_fit;
  for (int threads : {1, 0}) {
    for (const IntrinsicFitOptions* options : {&bare, &defaults}) {
      IntrinsicFitOptions o = *options;
      o.num_threads = threads;
      std::optional<IntrinsicFit> fit;
      const double t = best_seconds(runs, [&] { fit = fit_intrinsics(obs, o); });
      if (options == &defaults && threads == 1) default_fit = fit;
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
  // Rich models: the multi-start (calib/fit/multi_start.h) against
  // cv::calibrateCamera run to convergence (1000 iterations, 1e-15), one thread.
  if (is_rich_lens_model(model)) {
    IntrinsicFitOptions o = bare;
    o.num_threads = 1;
    std::optional<MultiStartFit> multi;
    const double t = best_seconds(runs, [&] { multi = fit_intrinsics_multi_start(obs, o); });
    rows.push_back({"glasspiv multi-start, no outlier loop (won: " + multi->starts[multi->winner].name + ")", "1", t,
                    multi->fit.rms_px, multi->fit.camera});
    cv::setNumThreads(1);
    CameraModel opencv = lens.truth;
    double rms = 0;
    const cv::TermCriteria tight(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 1000, 1e-15);
    const double t_tight = best_seconds(runs, [&] { rms = testing::opencv_calibrate(obs, model, &opencv, nullptr, tight); });
    rows.push_back({"cv::calibrateCamera to convergence (1000 iterations, 1e-15)", "1", t_tight, rms, opencv});
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
  return bench_uncertainty(lens.name, *default_fit, runs);
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
  std::vector<UncertaintyRow> uncertainty;
  for (const Lens& lens : lenses)
    for (const UncertaintyRow& r : bench_lens(lens, runs)) uncertainty.push_back(r);
  std::printf(
      "\nprojection uncertainty on the default fit, at infinity, single thread: one pixel, and the report's map\n\n"
      "| lens    | method          | centre 1-sigma px | one pixel us | map ms | map samples |\n"
      "|---------|-----------------|------------------:|-------------:|-------:|------------:|\n");
  for (const UncertaintyRow& r : uncertainty)
    std::printf("| %-7s | %-15s | %17.4f | %12.1f | %6.1f | %11d |\n", r.lens.c_str(), r.method.c_str(), r.centre_px,
                r.pixel_us, r.map_ms, r.samples);
  return 0;
}
