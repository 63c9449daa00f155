// render_bench: the light-transport map of data/scenes/reactor.yaml and the
// run-time-versus-error table of the forward render; the reflection grid's
// error on the rendered image and on its correction onto the sheet.
//   render_bench [--size N] [--table-size M] [--threads N] [--picture PATH] [--no-table]
// Camera: the scene's camera resampled to N x N px (default 1000): the central
// square of its 2560 x 2160 sensor with fx, fy, cx, cy scaled by N / 2160, so
// the view is the real camera's, at 1 megapixel. Every pixel is traced.
#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <algorithm>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench_common.h"
#include "correct/camera_resampler.h"
#include "correct/cell_mask.h"
#include "correct/correction_defaults.h"
#include "correct/correction_operator.h"
#include "correct/reconstruct.h"
#include "correct/sheet_grid.h"
#include "render/forward_render.h"
#include "render/path_tracer.h"
#include "render/scene_yaml.h"
#include "render/sheet_pattern.h"
#include "render/trace_scene_builder.h"
#include "render/transport_map.h"
#include "util/image_file.h"
#include "util/stopwatch.h"

using namespace glasspiv;
using bench::peak_rss_mib;
using bench::square;

namespace {

double rms_difference(const std::vector<float>& a, const std::vector<float>& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
  return std::sqrt(sum / a.size());
}

// Forward render with one point sample per crossing (no footprint filter), for comparison.
std::vector<float> point_sampled(const TransportMap& map, const SheetTexture& tex) {
  return forward_render_values(map, [&](double s, double t) { return tex.at(s, t); });
}

// glasspiv correct's default correction of one camera: its own map (cut at
// 0.1, traced whole), back-projected onto a sheet grid at the camera's
// footprint with the glass removed; the checkerboard's truth per cell (the
// texture averaged over the cell).
struct Correction {
  SheetGrid grid;
  CorrectionOperator op;
  std::vector<CellState> states;
  std::vector<float> truth;

  Correction(const TraceScene& ts, const CameraModel& cam, const RigidTransform& pose, const SheetTexture& tex,
             int threads) {
    grid = sheet_grid_covering(ts.sheet, median_footprint_mm(glass_removed_map(ts, cam, pose, 1, threads)));
    op = build_correction_operator(build_transport_map(ts, cam, pose, correction_trace_options(), 1, threads), grid,
                                   OperatorOptions{}, threads);
    states = classify_cells({{&op, 1.0}}, ts);
    const Eigen::Matrix2d cell = Eigen::Vector2d(grid.mm_per_px, -grid.mm_per_px).asDiagonal();
    truth.resize(grid.cell_count());
    for (int r = 0; r < grid.rows; ++r)
      for (int c = 0; c < grid.cols; ++c)
        truth[static_cast<std::size_t>(r) * grid.cols + c] = tex.average(grid.s_mm(c), grid.t_mm(r), cell);
  }
  std::vector<float> correct(const std::vector<float>& image) const { return back_projection({{&op, image.data()}}, states); }
  // RMS of a - b over the valid cells.
  double rms(const std::vector<float>& a, const std::vector<float>& b) const {
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (states[i] == CellState::valid) {
        sum += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
        ++n;
      }
    return n ? std::sqrt(sum / n) : 0.0;
  }
};

// The reflection grid (TraceOptions::reflection_grid) against the same
// samples traced whole: run time, segments, and the error it adds to the
// rendered checkerboard (footprint filter) and to its correction onto the
// sheet; against `reference` too if given.
void grid_table(const TraceScene& ts, const CameraModel& cam, const RigidTransform& pose, const SheetTexture& tex,
                int threads, const std::vector<float>* reference) {
  const Correction correction(ts, cam, pose, tex, threads);
  std::printf("\nreflection grid, %dx%d camera, reflections on, min_weight 1e-2; errors of the rendered 5 mm "
              "checkerboard (0/1, footprint filter) against the same samples/axis traced whole%s; each image "
              "corrected (back-projection, glasspiv correct's default map cut at 0.1) onto a %dx%d sheet grid of "
              "%.3f mm, RMS over its %zu valid cells against the correction of the image traced whole and against "
              "the checkerboard itself:\n",
              cam.width_px(), cam.height_px(), reference ? " and against the reference above" : "", correction.grid.cols,
              correction.grid.rows, correction.grid.mm_per_px, count_cells(correction.states).valid);
  std::printf("| samples/axis | grid | levels | tolerance | whole samples | s per MP | branches/sample | subtrees interpolated/sample | "
              "samples interpolated whole | "
              "RMS vs traced whole | largest vs traced whole | light on the sheet vs traced whole |%s "
              "corrected: RMS vs traced whole | corrected: RMS vs checkerboard |\n",
              reference ? " RMS error |" : "");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|%s---|---|\n", reference ? "---|" : "");
  const double mp = cam.width_px() * double(cam.height_px()) / 1e6;
  for (int k : reference ? std::vector<int>{1, 2} : std::vector<int>{1}) {
    TransportMap whole;
    std::vector<float> whole_image, whole_corrected;
    double whole_light = 0;
    struct GridRow {
      int grid;
      double tolerance;
      bool whole = false;
      bool reflections = true;  // false: against the refraction-only map traced whole (the row before)
      int levels = 1;           // TraceOptions::reflection_grid_levels
    };
    for (const GridRow& g : {GridRow{1, 0}, GridRow{2, 0.05}, GridRow{2, 0.1}, GridRow{2, 0.25}, GridRow{4, 0.1},
                             GridRow{2, 0.05, true}, GridRow{2, 0.1, true}, GridRow{4, 0.1, true},
                             GridRow{2, 0.05, true, true, 2}, GridRow{2, 0.1, true, true, 2},
                             GridRow{1, 0, false, false}, GridRow{2, 0.1, true, false},
                             GridRow{2, 0.1, true, false, 2}}) {
      TraceOptions options;
      options.reflections = g.reflections;
      options.reflection_grid = g.grid;
      options.grid_whole_samples = g.whole;
      options.reflection_grid_levels = g.levels;
      if (g.grid > 1) options.reflection_grid_tolerance = g.tolerance;
      const Stopwatch clock;
      TransportMap map = build_transport_map(ts, cam, pose, options, k, threads);
      const double seconds = clock.seconds();
      const std::vector<float> image = forward_render_values(map, tex);
      const std::vector<float> corrected = correction.correct(image);
      double light = 0;
      for (float w : map.weight) light += w;
      if (g.grid == 1) {
        whole = std::move(map);
        whole_image = image;
        whole_corrected = corrected;
        whole_light = light;
      }
      const TransportMap& m = g.grid == 1 ? whole : map;
      double largest = 0;
      for (std::size_t i = 0; i < image.size(); ++i)
        largest = std::max(largest, std::abs(double(image[i]) - whole_image[i]));
      char tolerance[16] = "";
      if (g.grid > 1) std::snprintf(tolerance, sizeof tolerance, "%g", g.tolerance);
      const double samples = double(m.stats.camera_rays + m.stats.samples_interpolated);
      std::printf("| %d%s | %d | %d | %s | %s | %.3f | %.2f | %.2f | %.1f %% | %.2e | %.4f | %.5f |", k,
                  g.reflections ? "" : ", refraction only", g.grid, g.levels, tolerance, g.whole ? "yes" : "", seconds / mp, double(m.stats.branches_traced) / samples,
                  double(m.stats.subtrees_interpolated) / samples, 100.0 * m.stats.samples_interpolated / samples,
                  rms_difference(image, whole_image),
                  largest, light / whole_light);
      if (reference) {
        if (g.reflections)
          std::printf(" %.4f |", rms_difference(image, *reference));
        else
          std::printf(" - |");
      }
      std::printf(" %.2e | %.4f |\n", correction.rms(corrected, whole_corrected), correction.rms(corrected, correction.truth));
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  int size = 1000, table_size = 400, threads = 0;
  bool table = true;
  std::string picture;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--size") && i + 1 < argc) size = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--table-size") && i + 1 < argc) table_size = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--threads") && i + 1 < argc) threads = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--picture") && i + 1 < argc) picture = argv[++i];
    else if (!std::strcmp(argv[i], "--no-table")) table = false;
    else {
      std::fprintf(stderr, "usage: render_bench [--size N] [--table-size M] [--threads N] [--picture PATH] [--no-table]\n");
      return 2;
    }
  }
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const Scene scene = read_scene(GLASSPIV_SOURCE_DIR "/data/scenes/reactor.yaml");
  TraceSceneBuildInfo info;
  const TraceScene ts = build_trace_scene(scene, &info);
  const Camera& camera = scene.cameras.at(0).camera;
  const RigidTransform& pose = *camera.camera_from_world;
  const CameraModel cam = square(camera.model, size);
  std::printf("reactor.yaml: %zu solids (%d spheres), camera %s resampled to %dx%d, %d threads\n", ts.solids.size(),
              info.spheres, scene.cameras[0].name.c_str(), cam.width_px(), cam.height_px(), threads);

  // Headline: the map at 1 sample per pixel, three settings.
  struct Setting {
    const char* name;
    bool reflections;
    double min_weight;
    double min_weight_reflected = 0;
    int reflection_grid = 1;
    bool whole_samples = false;
  };
  std::printf("\n| setting | s per MP | camera rays traced/s | branches/sample | crossings/px | rays in closed form | map MiB |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const Setting& s : {Setting{"refraction only, min_weight 1e-2", false, 1e-2},
                           Setting{"reflections, min_weight 1e-2", true, 1e-2},
                           Setting{"reflections, min_weight 1e-2, reflected 3e-2", true, 1e-2, 3e-2},
                           Setting{"reflections, min_weight 1e-2, reflection grid 2", true, 1e-2, 0, 2},
                           Setting{"reflections, min_weight 1e-2, reflection grid 2, whole samples", true, 1e-2, 0, 2, true},
                           Setting{"refraction only, min_weight 1e-2, grid 2, whole samples", false, 1e-2, 0, 2, true},
                           Setting{"reflections, min_weight 1e-3", true, 1e-3}}) {
    TraceOptions options;
    options.reflections = s.reflections;
    options.min_weight = s.min_weight;
    options.min_weight_reflected = s.min_weight_reflected;
    options.reflection_grid = s.reflection_grid;
    options.grid_whole_samples = s.whole_samples;
    const Stopwatch clock;
    const TransportMap map = build_transport_map(ts, cam, pose, options, 1, threads);
    const double t = clock.seconds();
    std::printf("| %s | %.3f | %.3g | %.2f | %.3f | %.1f %% | %.1f |\n", s.name, t / (map.pixel_count() / 1e6),
                map.stats.camera_rays / t,
                double(map.stats.branches_traced) / double(map.stats.camera_rays + map.stats.samples_interpolated),
                double(map.crossing_count()) / map.pixel_count(),
                100.0 * map.stats.closed_form_rays / map.stats.camera_rays, map.memory_bytes() / 1048576.0);
  }
  std::printf("peak RSS %.1f MiB\n", peak_rss_mib());

  // Float storage vs the double tracer: the map stores s, t as float; the
  // tracer works in double. Largest difference on the sheet, in micrometres.
  {
    TraceOptions options;
    options.min_weight = 1e-2;
    const CameraModel small = square(camera.model, 200);
    const TransportMap map = build_transport_map(ts, small, pose, options, 1, threads);
    const auto index = make_scene_index(ts);
    TraceResult r;
    double worst_um = 0;
    std::size_t i = 0;
    for (int row = 0; row < small.height_px(); ++row)
      for (int col = 0; col < small.width_px(); ++col) {
        const auto ray = pixel_camera_ray(small, pose, Eigen::Vector2d(col, row));
        if (!ray) continue;
        trace_ray(ts, *index, *ray, options, &r);
        for (const SheetCrossing& c : r.crossings) {
          worst_um = std::max({worst_um, 1e3 * std::abs(c.s_mm - map.s_mm[i]), 1e3 * std::abs(c.t_mm - map.t_mm[i])});
          ++i;
        }
      }
    std::printf("\nfloat map vs double tracer: largest |s, t| difference on the sheet %.4f um over %zu crossings\n",
                worst_um, i);
  }

  // A 5 mm checkerboard on the sheet: what the error columns render.
  const SheetPicture checker = checkerboard_picture(ts.sheet.extent_s_mm, ts.sheet.extent_t_mm, 5.0);
  const SheetTexture tex(checker.values.data(), checker.rows, checker.cols, checker.mm_per_texel);
  grid_table(ts, cam, pose, tex, threads, nullptr);

  if (!table) return 0;
  // Run time versus error on a smaller camera: a 5 mm checkerboard on the sheet,
  // RMS difference of the rendered image to the reference (4 x 4 samples,
  // min_weight 1e-4, reflections on), with the footprint filter and without.
  const CameraModel tcam = square(camera.model, table_size);
  struct Row {
    int k;
    double min_weight;
    bool reflections;
    double min_weight_reflected = 0;
    double seconds = 0, crossings_per_px = 0, rms_filtered = 0, rms_point = 0;
  };
  TraceOptions ref_options;
  ref_options.min_weight = 1e-4;
  const TransportMap ref_map = build_transport_map(ts, tcam, pose, ref_options, 4, threads);
  const std::vector<float> ref = forward_render_values(ref_map, tex);
  std::vector<Row> rows;
  for (int k : {1, 2, 3})
    for (double mw : {1e-1, 1e-2, 1e-3})
      for (bool refl : {true, false}) rows.push_back({k, mw, refl});
  // Ghosts cut sooner than the light that was never reflected.
  for (int k : {1, 2})
    for (double mwr : {0.02, 0.03, 0.05}) rows.push_back({k, 1e-2, true, mwr});
  for (Row& r : rows) {
    TraceOptions options;
    options.min_weight = r.min_weight;
    options.reflections = r.reflections;
    options.min_weight_reflected = r.min_weight_reflected;
    const Stopwatch clock;
    const TransportMap map = build_transport_map(ts, tcam, pose, options, r.k, threads);
    r.seconds = clock.seconds();
    r.crossings_per_px = double(map.crossing_count()) / map.pixel_count();
    r.rms_filtered = rms_difference(forward_render_values(map, tex), ref);
    r.rms_point = rms_difference(point_sampled(map, tex), ref);
  }
  std::printf("\nrun time vs error, %dx%d camera, 5 mm checkerboard (0/1), reference 4x4 samples, min_weight 1e-4, "
              "reflections on:\n",
              tcam.width_px(), tcam.height_px());
  std::printf("| samples/axis | min_weight | reflections (min_weight_reflected) | s per MP | crossings/px | "
              "RMS error, footprint filter | RMS error, point samples |\n|---|---|---|---|---|---|---|\n");
  for (const Row& r : rows) {
    char reflections[32];
    std::snprintf(reflections, sizeof reflections, r.min_weight_reflected > 0 ? "on (%g)" : r.reflections ? "on" : "off",
                  r.min_weight_reflected);
    std::printf("| %d | %.0e | %s | %.3f | %.3f | %.4f | %.4f |\n", r.k, r.min_weight, reflections,
                r.seconds / (tcam.width_px() * double(tcam.height_px()) / 1e6), r.crossings_per_px, r.rms_filtered,
                r.rms_point);
  }
  std::printf("peak RSS %.1f MiB\n", peak_rss_mib());

  // The reflection grid at the table's size, against the reference too.
  grid_table(ts, tcam, pose, tex, threads, &ref);
  std::printf("peak RSS %.1f MiB\n", peak_rss_mib());

  if (!picture.empty()) {
    std::vector<float> img = ref;
    write_gray_image(picture, img.data(), tcam.width_px(), tcam.height_px(), PixelFormat::uint8);
    std::printf("wrote %s\n", picture.c_str());
  }
  return 0;
}
