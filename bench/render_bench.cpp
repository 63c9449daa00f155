// render_bench: light-transport map of data/scenes/reactor.yaml (first camera)
// and the run-time-versus-error table of the forward render.
//   render_bench [--full] [--threads N] [--picture PATH]
// Headline figure: the camera scaled by 1/4 (fx, fy, cx, cy; 640 x 540 px) by
// default, the real 2560 x 2160 camera with --full. Never a crop or a pixel subset.
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "render/forward_render.h"
#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"
#include "render/transport_map.h"

using namespace glasspiv;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;  // Linux: KiB
}

float checker(double s_mm, double t_mm) {
  const long i = static_cast<long>(std::floor(s_mm / 10.0)) + static_cast<long>(std::floor(t_mm / 10.0));
  return (i & 1) ? 1.0f : 0.0f;
}

CameraModel scaled(const CameraModel& m, int k) {
  if (k == 1) return m;
  return CameraModel(m.width_px() / k, m.height_px() / k, m.fx_px() / k, m.fy_px() / k, (m.cx_px() + 0.5) / k - 0.5,
                     (m.cy_px() + 0.5) / k - 0.5, m.distortion());
}

}  // namespace

int main(int argc, char** argv) {
  bool full = false;
  int threads = 0;
  std::string picture;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--full")) full = true;
    else if (!std::strcmp(argv[i], "--threads") && i + 1 < argc) threads = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--picture") && i + 1 < argc) picture = argv[++i];
    else {
      std::fprintf(stderr, "usage: render_bench [--full] [--threads N] [--picture PATH]\n");
      return 2;
    }
  }
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const Scene scene = read_scene(GLASSPIV_SOURCE_DIR "/data/scenes/reactor.yaml");
  TraceSceneBuildInfo info;
  const TraceScene ts = build_trace_scene(scene, &info);
  const Camera& camera = scene.cameras.at(0).camera;
  const RigidTransform& pose = *camera.camera_from_world;
  const CameraModel cam = scaled(camera.model, full ? 1 : 4);
  std::printf("reactor.yaml: %zu solids (%d spheres), camera %s %dx%d%s, %d threads\n", ts.solids.size(),
              info.spheres, scene.cameras[0].name.c_str(), cam.width_px(), cam.height_px(),
              full ? " (real camera)" : " (real camera scaled by 1/4: fx, fy, cx, cy)", threads);

  // Headline: default TraceOptions (reflections on, min_weight 1e-6), 1 sample per pixel.
  {
    const TraceOptions options;
    const auto t0 = std::chrono::steady_clock::now();
    const TransportMap map = build_transport_map(ts, cam, pose, options, 1, threads);
    const double t = seconds_since(t0);
    const double mpix = map.pixel_count() / 1e6;
    std::printf("headline (reflections on, min_weight %.0e, 1 sample/px):\n", options.min_weight);
    std::printf("  time %.3f s, %.3f s per megapixel\n", t, t / mpix);
    std::printf("  camera rays/s %.3g, branches/s %.3g, branches per ray %.2f\n", map.stats.camera_rays / t,
                map.stats.branches_traced / t, double(map.stats.branches_traced) / map.stats.camera_rays);
    std::printf("  crossings per pixel %.3f, pixels with no solid hit %ld of %zu\n",
                double(map.crossing_count()) / map.pixel_count(), map.stats.pixels_without_solid_hit,
                map.pixel_count());
    std::printf("  map %.1f MiB, peak RSS %.1f MiB\n", map.memory_bytes() / 1048576.0, peak_rss_mib());
  }

  // Run time versus error, always on the 1/4 camera.
  const CameraModel small = scaled(camera.model, 4);
  struct Row {
    int k;
    double min_weight;
    bool reflections;
    double seconds = 0;
    double crossings_per_px = 0;
    cv::Mat image;
  };
  std::vector<Row> rows;
  for (int k : {1, 2})
    for (double mw : {1e-2, 1e-3, 1e-4})
      for (bool refl : {true, false}) rows.push_back({k, mw, refl, 0, 0, cv::Mat()});
  for (Row& r : rows) {
    TraceOptions options;
    options.min_weight = r.min_weight;
    options.reflections = r.reflections;
    const auto t0 = std::chrono::steady_clock::now();
    const TransportMap map = build_transport_map(ts, small, pose, options, r.k, threads);
    r.seconds = seconds_since(t0);
    r.crossings_per_px = double(map.crossing_count()) / map.pixel_count();
    r.image = forward_render(map, checker, scene.background.radiance);
  }
  const Row& ref = rows[10];
  std::printf("\nrun time vs error, %dx%d camera, checkerboard 10 mm (0/1), reference = %d samples/axis, "
              "min_weight %.0e, reflections %s:\n",
              small.width_px(), small.height_px(), ref.k, ref.min_weight, ref.reflections ? "on" : "off");
  std::printf("| samples/axis | min_weight | reflections | time (s) | crossings/px | RMS diff vs reference |\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (const Row& r : rows) {
    const double rms = cv::norm(r.image, ref.image, cv::NORM_L2) / std::sqrt(double(r.image.total()));
    std::printf("| %d | %.0e | %s | %.3f | %.3f | %.5f |\n", r.k, r.min_weight, r.reflections ? "on" : "off",
                r.seconds, r.crossings_per_px, rms);
  }
  std::printf("peak RSS %.1f MiB\n", peak_rss_mib());

  if (!picture.empty()) {
    double lo = 0, hi = 0;
    cv::minMaxLoc(ref.image, &lo, &hi);
    cv::Mat out;
    ref.image.convertTo(out, CV_8U, hi > lo ? 255.0 / (hi - lo) : 1.0, hi > lo ? -255.0 * lo / (hi - lo) : 0.0);
    if (!cv::imwrite(picture, out)) {
      std::fprintf(stderr, "render_bench: cannot write %s\n", picture.c_str());
      return 1;
    }
    std::printf("wrote %s (%dx%d, normalised from [%.4f, %.4f])\n", picture.c_str(), out.cols, out.rows, lo, hi);
  }
  return 0;
}
