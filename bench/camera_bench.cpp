// camera_bench: throughput of glasspiv's camera model against OpenCV and mrcal,
// with the accuracy each reaches in the same run.
//
//   camera_bench [points]        (default 1000000)
//
// For an OpenCV5 and an OpenCV8 lens, `points` pixels are drawn uniformly over
// the image (seeded); their camera-frame points come from glasspiv's unprojection
// at random depths. Projection: CameraModel::project in a loop, one
// cv::projectPoints call, one mrcal_project call (no gradients); the error column
// is the largest difference to CameraModel::project. Unprojection:
// CameraModel::unproject in a loop, one cv::undistortPoints call (default
// criteria, then COUNT+EPS 100 / 1e-12), one mrcal_unproject call; the error
// column is the largest pixel -> ray -> pixel round-trip error (reprojected with
// CameraModel::project, which agrees with cv::projectPoints to ~1e-12 px).
// Every timing is the best of 3 runs; everything runs on one thread.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <sys/utsname.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

#include "calib/camera_model.h"

extern "C" {
#include <mrcal/mrcal.h>
}

namespace {

using glasspiv::CameraModel;

template <typename F>
double best_of_3_seconds(F&& run) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    const auto start = std::chrono::steady_clock::now();
    run();
    const auto stop = std::chrono::steady_clock::now();
    best = std::min(best, std::chrono::duration<double>(stop - start).count());
  }
  return best;
}

struct Lens {
  const char* name;
  CameraModel model;
  mrcal_lensmodel_type_t mrcal_type;
};

struct Row {
  std::string operation, implementation;
  double seconds;
  double max_error_px;
  long failures;
};

void print_row(const Lens& lens, const Row& row, double reference_seconds, long n) {
  char error[32];
  if (std::isfinite(row.max_error_px))
    std::snprintf(error, sizeof error, "%.2e", row.max_error_px);
  else
    std::snprintf(error, sizeof error, "inf");
  std::printf("| %-7s | %-9s | %-50s | %8.2f | %8.2fx | %12s | %8ld |\n", lens.name, row.operation.c_str(),
              row.implementation.c_str(), n / row.seconds / 1e6, reference_seconds / row.seconds, error, row.failures);
}

std::vector<double> mrcal_intrinsics(const CameraModel& m) {
  std::vector<double> intrinsics = {m.fx_px(), m.fy_px(), m.cx_px(), m.cy_px()};
  for (double k : m.distortion()) intrinsics.push_back(k);
  return intrinsics;
}

// Largest |project(n) - pixel| over all points whose ray is valid; `failures`
// counts the rest.
double round_trip_error(const CameraModel& m, const std::vector<cv::Point2d>& pixels,
                        const std::vector<Eigen::Vector3d>& rays, long* failures) {
  double worst = 0;
  *failures = 0;
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const auto back = rays[i].allFinite() ? m.project(rays[i]) : std::nullopt;
    if (!back) {
      ++*failures;
      continue;
    }
    const double error = std::hypot(back->x() - pixels[i].x, back->y() - pixels[i].y);
    worst = std::max(worst, std::isfinite(error) ? error : std::numeric_limits<double>::infinity());
  }
  return worst;
}

void bench_lens(const Lens& lens, long n) {
  const CameraModel& m = lens.model;
  const cv::Matx33d k(m.fx_px(), 0, m.cx_px(), 0, m.fy_px(), m.cy_px(), 0, 0, 1);
  const std::vector<double> distortion = m.distortion();
  mrcal_lensmodel_t mrcal_lens{};
  mrcal_lens.type = lens.mrcal_type;
  const std::vector<double> intrinsics = mrcal_intrinsics(m);

  // Inputs: pixels over the whole sensor and camera-frame points behind them.
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> u(-0.5, m.width_px() - 0.5), v(-0.5, m.height_px() - 0.5),
      depth(100.0, 5000.0);
  std::vector<cv::Point2d> pixels(n);
  std::vector<Eigen::Vector3d> points(n);
  std::vector<cv::Point3d> points_cv(n);
  std::vector<mrcal_point3_t> points_mrcal(n);
  std::vector<mrcal_point2_t> pixels_mrcal(n);
  for (long i = 0; i < n; ++i) {
    pixels[i] = {u(rng), v(rng)};
    const glasspiv::UnprojectResult r = m.unproject({pixels[i].x, pixels[i].y});
    if (!r.ok()) {
      std::fprintf(stderr, "camera_bench: pixel (%g, %g) of %s does not unproject\n", pixels[i].x, pixels[i].y,
                   lens.name);
      std::exit(1);
    }
    const double z = depth(rng);
    points[i] = Eigen::Vector3d(r.normalized.x() * z, r.normalized.y() * z, z);
    points_cv[i] = {points[i].x(), points[i].y(), points[i].z()};
    points_mrcal[i] = {{points[i].x(), points[i].y(), points[i].z()}};
    pixels_mrcal[i] = {{pixels[i].x, pixels[i].y}};
  }

  // --- projection
  std::vector<Eigen::Vector2d> projected(n);
  const double t_ours = best_of_3_seconds([&] {
    for (long i = 0; i < n; ++i) projected[i] = *m.project(points[i]);
  });
  std::vector<cv::Point2d> projected_cv;
  const double t_cv = best_of_3_seconds(
      [&] { cv::projectPoints(points_cv, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), k, distortion, projected_cv); });
  std::vector<mrcal_point2_t> projected_mrcal(n);
  bool mrcal_ok = true;
  const double t_mrcal = best_of_3_seconds([&] {
    mrcal_ok = mrcal_project(projected_mrcal.data(), nullptr, nullptr, points_mrcal.data(), static_cast<int>(n),
                             &mrcal_lens, intrinsics.data());
  });
  double diff_cv = 0, diff_mrcal = mrcal_ok ? 0 : std::numeric_limits<double>::infinity();
  for (long i = 0; i < n; ++i) {
    diff_cv = std::max(diff_cv, std::hypot(projected_cv[i].x - projected[i].x(), projected_cv[i].y - projected[i].y()));
    diff_mrcal = std::max(diff_mrcal, std::hypot(projected_mrcal[i].x - projected[i].x(),
                                                 projected_mrcal[i].y - projected[i].y()));
  }
  double diff_truth = 0;  // against the pixels the points were made from
  for (long i = 0; i < n; ++i)
    diff_truth = std::max(diff_truth, std::hypot(projected[i].x() - pixels[i].x, projected[i].y() - pixels[i].y));
  print_row(lens, {"project", "glasspiv CameraModel::project (loop)", t_ours, diff_truth, 0}, t_cv, n);
  print_row(lens, {"project", "cv::projectPoints (one call)", t_cv, diff_cv, 0}, t_cv, n);
  print_row(lens, {"project", "mrcal_project (one call, no gradients)", t_mrcal, diff_mrcal, 0}, t_cv, n);

  // --- unprojection
  const auto ray_of = [](const glasspiv::UnprojectResult& r) {
    return r.ok() ? Eigen::Vector3d(r.normalized.x(), r.normalized.y(), 1.0)
                  : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  };
  std::vector<Eigen::Vector3d> rays(n);
  const double t_unproject = best_of_3_seconds([&] {
    for (long i = 0; i < n; ++i) rays[i] = ray_of(m.unproject({pixels[i].x, pixels[i].y}));
  });
  long failures_ours = 0;
  const double error_ours = round_trip_error(m, pixels, rays, &failures_ours);
  // The same in batches (the transport map's camera rays): equal to the bit.
  std::vector<Eigen::Vector2d> pixels_eigen(n);
  for (long i = 0; i < n; ++i) pixels_eigen[i] = Eigen::Vector2d(pixels[i].x, pixels[i].y);
  std::vector<glasspiv::UnprojectResult> batch(n);
  const double t_unproject_batch = best_of_3_seconds(
      [&] { m.unproject_batch(pixels_eigen.data(), static_cast<int>(n), batch.data()); });
  std::vector<Eigen::Vector3d> batch_rays(n);
  for (long i = 0; i < n; ++i) batch_rays[i] = ray_of(batch[i]);
  long failures_batch = 0;
  const double error_batch = round_trip_error(m, pixels, batch_rays, &failures_batch);

  const auto opencv_unproject = [&](const cv::TermCriteria* criteria, double* seconds, long* failures) {
    std::vector<cv::Point2d> normalized;
    *seconds = best_of_3_seconds([&] {
      if (criteria)
        cv::undistortPoints(pixels, normalized, k, distortion, cv::noArray(), cv::noArray(), *criteria);
      else
        cv::undistortPoints(pixels, normalized, k, distortion);
    });
    std::vector<Eigen::Vector3d> cv_rays(n);
    for (long i = 0; i < n; ++i) cv_rays[i] = Eigen::Vector3d(normalized[i].x, normalized[i].y, 1.0);
    return round_trip_error(m, pixels, cv_rays, failures);
  };
  double t_cv_default, t_cv_tight;
  long failures_cv_default, failures_cv_tight;
  const double error_cv_default = opencv_unproject(nullptr, &t_cv_default, &failures_cv_default);
  const cv::TermCriteria tight(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12);
  const double error_cv_tight = opencv_unproject(&tight, &t_cv_tight, &failures_cv_tight);

  std::vector<mrcal_point3_t> v_mrcal(n);
  bool unproject_ok = true;
  const double t_mrcal_unproject = best_of_3_seconds([&] {
    unproject_ok = mrcal_unproject(v_mrcal.data(), pixels_mrcal.data(), static_cast<int>(n), &mrcal_lens,
                                   intrinsics.data());
  });
  std::vector<Eigen::Vector3d> mrcal_rays(n);
  for (long i = 0; i < n; ++i) mrcal_rays[i] = Eigen::Vector3d(v_mrcal[i].x, v_mrcal[i].y, v_mrcal[i].z);
  long failures_mrcal = 0;
  double error_mrcal = round_trip_error(m, pixels, mrcal_rays, &failures_mrcal);
  if (!unproject_ok) error_mrcal = std::numeric_limits<double>::infinity();

  print_row(lens, {"unproject", "glasspiv CameraModel::unproject (loop)", t_unproject, error_ours, failures_ours},
            t_cv_default, n);
  print_row(lens, {"unproject", "glasspiv CameraModel::unproject_batch", t_unproject_batch, error_batch, failures_batch},
            t_cv_default, n);
  print_row(lens, {"unproject", "cv::undistortPoints (default: 5 iterations)", t_cv_default, error_cv_default,
                   failures_cv_default},
            t_cv_default, n);
  print_row(lens, {"unproject", "cv::undistortPoints (COUNT+EPS, 100, 1e-12)", t_cv_tight, error_cv_tight,
                   failures_cv_tight},
            t_cv_default, n);
  print_row(lens, {"unproject", "mrcal_unproject (one call)", t_mrcal_unproject, error_mrcal, failures_mrcal},
            t_cv_default, n);
}

}  // namespace

int main(int argc, char** argv) {
  long n = 1000000;
  if (argc > 1) n = std::atol(argv[1]);
  if (n <= 0 || n > std::numeric_limits<int>::max()) {
    std::fprintf(stderr, "usage: camera_bench [points]\n");
    return 2;
  }
  cv::setNumThreads(1);
  utsname host{};
  uname(&host);
  std::printf("camera_bench: %ld points per lens, best of 3 runs, single thread\n", n);
  std::printf("machine: %s %s, %u hardware threads (std::thread::hardware_concurrency); OpenCV %s; compiler %s\n",
              host.sysname, host.machine, std::thread::hardware_concurrency(), CV_VERSION, __VERSION__);
  std::printf("Mpts/s: million points per second; vs OpenCV: speed relative to cv::projectPoints (project) or "
              "cv::undistortPoints with default criteria (unproject); max error: projection rows give the largest "
              "difference to CameraModel::project (glasspiv's row: to the pixels the points were made from), "
              "unprojection rows the largest pixel -> ray -> pixel round trip; failures: rays not returned.\n\n");
  std::printf("| lens    | operation | implementation                                     |   Mpts/s | vs OpenCV | max error px | failures |\n");
  std::printf("|---------|-----------|----------------------------------------------------|---------:|----------:|-------------:|---------:|\n");
  const Lens lenses[] = {
      {"opencv5", CameraModel(2048, 1536, 1800, 1801, 1035.5, 760.5, {-0.12, 0.05, 2e-4, -1e-4, -0.01}),
       MRCAL_LENSMODEL_OPENCV5},
      {"opencv8",
       CameraModel(2560, 1600, 2000, 2002, 1259.5, 808.5, {-0.25, 0.08, 3e-4, -2e-4, -0.01, 0.15, -0.02, 0.005}),
       MRCAL_LENSMODEL_OPENCV8},
  };
  for (const Lens& lens : lenses) bench_lens(lens, n);
  return 0;
}
