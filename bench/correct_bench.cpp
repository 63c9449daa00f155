// correct_bench: the correction of data/scenes/reactor.yaml (correct/): the
// operator, back-projection, least squares and a series of frames, timed
// against cv::remap of the same frame, the correction's run-time-versus-error
// table and the mask thresholds' measurement (results in bench/RESULTS.md).
//   correct_bench [--size N] [--table-size M] [--frames F] [--threads T] [--reps R] [--quick]
//                 [--no-table] [--no-series]
// Camera: the scene's camera resampled to N x N px (default 1000), as
// render_bench: the central square of its 2560 x 2160 sensor with fx, fy, cx,
// cy scaled by N / 2160. Map: default TraceOptions (min_weight 1e-2,
// reflections on), 1 sample per pixel. Sheet grid: the median footprint of the
// glass-removed camera (the camera's own pixel on the sheet). Sections 5 and 6
// (the tables) run on an M x M camera (default M = N). All figures of a run
// are measured in that run; fast timings are the median of R repeats (default
// 7) taken in interleaved rounds (the first round discarded), so that ratios
// hold on a loaded machine. --quick: N = 400, 20 frames, 3 repeats. The series
// writes F 16-bit TIFFs (default 200) to a temporary folder under /tmp and
// removes it. Progress on stderr, tables on stdout.
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "bench/bench_common.h"
#include "correct/back_projector.h"
#include "correct/camera_resampler.h"
#include "correct/cell_mask.h"
#include "correct/correction_operator.h"
#include "correct/reconstruct.h"
#include "correct/series.h"
#include "correct/sheet_grid.h"
#include "render/forward_render.h"
#include "render/path_tracer.h"
#include "render/scene_yaml.h"
#include "render/sheet_texture.h"
#include "render/trace_scene_builder.h"
#include "render/transport_map.h"
#include "sim/sheet_particles.h"
#include "util/image_file.h"
#include "util/stopwatch.h"

using namespace glasspiv;
using bench::median;
using bench::peak_rss_mib;
using bench::seconds_of;
using bench::square;
namespace fs = std::filesystem;

namespace {

double mib(std::size_t bytes) { return bytes / 1048576.0; }

// A markdown table printed with aligned columns: text left, figures right.
class Table {
 public:
  explicit Table(std::vector<std::string> header) : header_(std::move(header)) {}
  void add(std::vector<std::string> row) { rows_.push_back(std::move(row)); }
  void print() const {
    std::vector<std::size_t> w(header_.size(), 3);
    for (std::size_t c = 0; c < header_.size(); ++c) w[c] = std::max(w[c], header_[c].size());
    for (const auto& r : rows_)
      for (std::size_t c = 0; c < r.size() && c < w.size(); ++c) w[c] = std::max(w[c], r[c].size());
    auto line = [&](const std::vector<std::string>& r, bool head) {
      std::string s = "|";
      for (std::size_t c = 0; c < w.size(); ++c) {
        const std::string& v = c < r.size() ? r[c] : std::string();
        const bool left = head || c == 0 || !numeric(v);
        const std::string pad(w[c] - v.size(), ' ');
        s += " " + (left ? v + pad : pad + v) + " |";
      }
      std::printf("%s\n", s.c_str());
    };
    line(header_, true);
    std::string sep = "|";
    for (std::size_t c = 0; c < w.size(); ++c) sep += std::string(w[c] + 2, '-') + "|";
    std::printf("%s\n", sep.c_str());
    for (const auto& r : rows_) line(r, false);
  }

 private:
  static bool numeric(const std::string& v) {
    return !v.empty() && (std::isdigit(static_cast<unsigned char>(v[0])) || v[0] == '-' || v[0] == '+' || v[0] == '.');
  }
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> rows_;
};

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// ---------------------------------------------------------------------------
// The round trip of tests/correct/reconstruct_test.cpp: Gaussian particles on
// the sheet, rendered through the map with the footprint-filtered texture
// lookup (independent of the operator), then corrected.

bool is_valid(CellState s) { return s == CellState::valid; }

double ncc(const std::vector<float>& a, const std::vector<float>& b, const std::vector<CellState>& states) {
  return ncc_where(a, b, valid_cells(states));
}

template <typename A, typename B>
double rms_error(const std::vector<A>& a, const std::vector<B>& truth, const std::vector<CellState>& states) {
  double s = 0, n = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (is_valid(states[i])) {
      s += (double(a[i]) - double(truth[i])) * (double(a[i]) - double(truth[i]));
      ++n;
    }
  return n ? std::sqrt(s / n) : 0.0;
}

double mean_centroid_error_cells(const std::vector<float>& l, const SheetParticles& f, const SheetGrid& g,
                                 const std::vector<CellState>& states, int* counted) {
  return glasspiv::mean_centroid_error_cells(l, f, g, valid_cells(states), counted);
}

// The back-projection in double straight from the map's crossings, each
// crossing one bilinear splat at its centre (what build_correction_operator
// does with footprint_filter = false, there stored in float32).
std::vector<double> double_back_projection(const TransportMap& map, const SheetGrid& g, const float* image,
                                           const std::vector<CellState>& states) {
  std::vector<double> sum(g.cell_count(), 0.0), weight(g.cell_count(), 0.0);
  for (std::size_t p = 0; p < map.pixel_count(); ++p)
    for (std::uint32_t i = map.pixel_offsets[p]; i < map.pixel_offsets[p + 1]; ++i) {
      const double x = g.col(map.s_mm[i]), y = g.row(map.t_mm[i]);
      const double fx0 = std::floor(x), fy0 = std::floor(y);
      if (!(fx0 >= -1 && fy0 >= -1 && fx0 < g.cols && fy0 < g.rows)) continue;
      const int x0 = static_cast<int>(fx0), y0 = static_cast<int>(fy0);
      const double ax = x - fx0, ay = y - fy0, w = map.weight[i];
      const double k[4] = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
      for (int j = 0; j < 4; ++j) {
        const int cx = x0 + (j & 1), cy = y0 + (j >> 1);
        if (k[j] <= 0 || cx < 0 || cy < 0 || cx >= g.cols || cy >= g.rows) continue;
        const std::size_t c = static_cast<std::size_t>(cy) * g.cols + cx;
        sum[c] += w * k[j] * image[p];
        weight[c] += w * k[j];
      }
    }
  std::vector<double> l(g.cell_count(), 0.0);
  for (std::size_t c = 0; c < l.size(); ++c)
    if (is_valid(states[c]) && weight[c] > 0) l[c] = sum[c] / weight[c];
  return l;
}

struct Setup {
  int n = 0;
  std::optional<CameraModel> cam;
  TransportMap map, direct;
  double map_seconds = 0, footprint_mm = 0;
  SheetGrid grid;
};

Setup make_setup(const TraceScene& ts, const CameraModel& model, const RigidTransform& pose, int n, int threads) {
  Setup s;
  s.n = n;
  s.cam = square(model, n);
  std::fprintf(stderr, "tracing the map %dx%d ...\n", n, n);
  const Stopwatch clock;
  s.map = build_transport_map(ts, *s.cam, pose, TraceOptions{}, 1, threads);
  s.map_seconds = clock.seconds();
  s.direct = glass_removed_map(ts, *s.cam, pose, 1, threads);
  s.footprint_mm = median_footprint_mm(s.direct);
  s.grid = sheet_grid_covering(ts.sheet, s.footprint_mm);
  return s;
}

struct Frame {
  GrayImage in;
  std::vector<float> out;
};

}  // namespace

int main(int argc, char** argv) {
  int size = 1000, table_size = -1, threads = 0, frames = 200, reps = 7;
  bool table = true, series = true;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--size") && i + 1 < argc) size = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--table-size") && i + 1 < argc) table_size = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--threads") && i + 1 < argc) threads = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--frames") && i + 1 < argc) frames = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--quick")) {
      size = 400;
      frames = 20;
      reps = 3;
    } else if (!std::strcmp(argv[i], "--no-table")) table = false;
    else if (!std::strcmp(argv[i], "--no-series")) series = false;
    else {
      std::fprintf(stderr,
                   "usage: correct_bench [--size N] [--table-size M] [--frames F] [--threads T] [--reps R] [--quick] "
                   "[--no-table] [--no-series]\n");
      return 2;
    }
  }
  if (size < 16 || frames < 1 || reps < 1) {
    std::fprintf(stderr, "correct_bench: --size >= 16, --frames >= 1, --reps >= 1\n");
    return 2;
  }
  if (table_size <= 0) table_size = size;
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));

  const Scene scene = read_scene(GLASSPIV_SOURCE_DIR "/data/scenes/reactor.yaml");
  const TraceScene ts = build_trace_scene(scene);
  const Camera& camera = scene.cameras.at(0).camera;
  const RigidTransform& pose = *camera.camera_from_world;

  // ---- 1. Setup ------------------------------------------------------------
  Setup su = make_setup(ts, camera.model, pose, size, threads);
  const TransportMap& map = su.map;
  const SheetGrid& grid = su.grid;
  const double mp = map.pixel_count() / 1e6;
  std::fprintf(stderr, "building the operator (%dx%d cells) ...\n", grid.cols, grid.rows);
  CorrectionOperator op;
  std::vector<double> t_build;
  for (int r = 0; r < std::max(1, std::min(reps, 3)); ++r) {
    const Stopwatch clock;
    op = build_correction_operator(map, grid, OperatorOptions{}, threads);
    t_build.push_back(clock.seconds());
  }
  const double rss_after_build = peak_rss_mib();
  const std::vector<CellState> states = classify_cells({{&op, 1.0}}, ts);
  const CellCounts counts = count_cells(states);
  const Stopwatch resampler_clock;
  const CorrectionOperator direct_op = build_correction_operator(su.direct, grid, OperatorOptions{}, threads);
  const CameraResampler resampler = make_camera_resampler(direct_op, states);
  const double resampler_seconds = resampler_clock.seconds();
  std::size_t pixels_valid = 0, pixels_on_sheet = 0;
  for (std::uint8_t v : resampler.pixel_valid) pixels_valid += v != 0;
  for (std::size_t p = 0; p < su.direct.pixel_count(); ++p)
    pixels_on_sheet += su.direct.pixel_offsets[p + 1] > su.direct.pixel_offsets[p];
  const std::size_t resampler_bytes = (resampler.pixel_offsets.size() + resampler.cell.size()) * 4 +
                                      resampler.value.size() * 4 + resampler.pixel_valid.size();

  std::printf("correct_bench: reactor.yaml, camera %s resampled to %dx%d, %d threads (cv::getNumThreads %d), "
              "median of %d repeats per timing\n",
              scene.cameras[0].name.c_str(), size, size, threads, cv::getNumThreads(), reps);
  std::printf("\n### 1. Setup\n\n");
  Table t1({"item", "value"});
  t1.add({"map: traced (default TraceOptions: min_weight 1e-2, reflections on, 1 sample/px)", fmt("%.2f s", su.map_seconds)});
  t1.add({"map: crossings/pixel", fmt("%.3f", double(map.crossing_count()) / map.pixel_count())});
  t1.add({"map: memory", fmt("%.1f MiB", mib(map.memory_bytes()))});
  t1.add({"sheet grid: median footprint of the glass-removed camera", fmt("%.4f mm", su.footprint_mm)});
  t1.add({"sheet grid: cells", std::to_string(grid.cols) + " x " + std::to_string(grid.rows)});
  t1.add({"operator: entries", fmt("%.0f", double(op.entry_count()))});
  t1.add({"operator: entries/pixel", fmt("%.2f", double(op.entry_count()) / op.pixel_count())});
  t1.add({"operator: memory (both CSR directions)", fmt("%.1f MiB", mib(op.memory_bytes()))});
  t1.add({"cells valid (default MaskOptions), of the fluid region", fmt("%.1f %%", 100 * counts.valid_fraction_of_fluid())});
  t1.add({"glass-removed operator + camera resampler: built", fmt("%.2f s", resampler_seconds)});
  t1.add({"camera resampler: memory", fmt("%.1f MiB", mib(resampler_bytes))});
  t1.add({"camera pixels that see the sheet (glass removed)", fmt("%.1f %%", 100.0 * pixels_on_sheet / su.direct.pixel_count())});
  t1.add({"camera pixels valid after correction", fmt("%.1f %%", 100.0 * pixels_valid / resampler.pixel_valid.size())});
  t1.print();

  // The frame: a particle field rendered through the glass (reconstruct_test's round trip).
  const double mm = su.footprint_mm;
  std::fprintf(stderr, "rendering the particle frames ...\n");
  const SheetParticles field = random_sheet_particles(ts.sheet, 0.03 / (mm * mm), 3 * mm, 7);
  const SheetTexture fine = field.texture(ts.sheet, mm / 4);
  const std::vector<float> image = forward_render_values(map, fine);
  const std::vector<float> truth = field.on(grid);
  const SheetTexture on_grid(truth.data(), grid.rows, grid.cols, grid.mm_per_px);

  // ---- 2. Speed per frame --------------------------------------------------
  std::fprintf(stderr, "timing per-frame passes ...\n");
  cv::Mat src(size, size, CV_32F), dst;
  std::copy(image.begin(), image.end(), src.ptr<float>(0));
  // The remap floor: a smooth warp of a few pixels (a lens undistortion's size), precomputed maps.
  cv::Mat map32(size, size, CV_32FC2), map16a, map16b;
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < size; ++c) {
      const double u = double(c) / size - 0.5, v = double(r) / size - 0.5, k = 0.05 * (u * u + v * v);
      map32.at<cv::Vec2f>(r, c) = cv::Vec2f(float(c + k * u * size), float(r + k * v * size));
    }
  cv::convertMaps(map32, cv::noArray(), map16a, map16b, CV_16SC2);
  std::vector<float> corrected(map.pixel_count()), forward(map.pixel_count()), l;
  std::vector<float> forward_peer;
  // Prepared once per series: the entries of the cells the output reads, divided by their weight.
  const std::vector<std::uint8_t> read_cells = cells_read_by(resampler, op.grid.cell_count());
  const BackProjector for_camera = make_back_projector({{&op, 1.0}}, states, &read_cells);
  const BackProjector for_sheet = make_back_projector({{&op, 1.0}}, states);
  std::fprintf(stderr, "back projectors: %zu entries for the camera grid, %zu for the sheet grid (operator %zu)\n",
               for_camera.value.size(), for_sheet.value.size(), op.entry_count());
  std::vector<float> lp(op.grid.cell_count(), 0.0f);
  std::vector<double> t_remap32, t_remap16, t_correct, t_bp, t_resample, t_fwd, t_fwd_peer, t_correct_plain, t_bp_plain;
  for (int r = 0; r < reps + 1; ++r) {  // round 0 warms up
    const double a = seconds_of([&] { cv::remap(src, dst, map32, cv::noArray(), cv::INTER_LINEAR); });
    const double b = seconds_of([&] { cv::remap(src, dst, map16a, map16b, cv::INTER_LINEAR); });
    const double c = seconds_of([&] {
      apply_back_projector(for_camera, image.data(), lp.data());
      resample_to_camera(resampler, lp.data(), corrected.data());
    });
    const double d = seconds_of([&] { apply_back_projector(for_sheet, image.data(), lp.data()); });
    const double c0 = seconds_of([&] {
      l = back_projection({{&op, image.data()}}, states);
      resample_to_camera(resampler, l.data(), corrected.data());
    });
    const double d0 = seconds_of([&] { l = back_projection({{&op, image.data()}}, states); });
    const double e = seconds_of([&] { resample_to_camera(resampler, l.data(), corrected.data()); });
    const double f = seconds_of([&] { apply_forward(op, truth.data(), 0.0, forward.data()); });
    const double g = seconds_of([&] { forward_peer = forward_render_values(map, on_grid); });
    if (r == 0) continue;
    t_remap32.push_back(a);
    t_remap16.push_back(b);
    t_correct.push_back(c);
    t_bp.push_back(d);
    t_correct_plain.push_back(c0);
    t_bp_plain.push_back(d0);
    t_resample.push_back(e);
    t_fwd.push_back(f);
    t_fwd_peer.push_back(g);
  }
  const double remap32 = median(t_remap32), remap16 = median(t_remap16), floor_s = std::min(remap32, remap16);
  double fwd_diff = 0, fwd_ref = 0;
  for (std::size_t p = 0; p < forward.size(); ++p) {
    fwd_diff += double(forward[p] - forward_peer[p]) * (forward[p] - forward_peer[p]);
    fwd_ref += double(forward_peer[p]) * forward_peer[p];
  }

  // (d) is t_build; (e) least squares from the back-projection.
  std::fprintf(stderr, "timing least squares ...\n");
  const std::vector<float> bp = back_projection({{&op, image.data()}}, states);
  std::vector<double> t_lsq;
  LeastSquaresReport rep;
  std::vector<float> lsq;
  for (int r = 0; r < std::max(1, std::min(reps, 3)); ++r)
    t_lsq.push_back(seconds_of([&] { lsq = least_squares({{&op, image.data()}}, states, bp, {}, &rep); }));

  // (f) the published way: a map traced for every frame, then the same correction.
  std::fprintf(stderr, "timing re-tracing per frame ...\n");
  std::vector<double> t_retrace{su.map_seconds}, t_correct_f;
  for (int r = 0; r < std::max(1, std::min(reps, 3)) - 1; ++r) {
    t_retrace.push_back(seconds_of([&] {
      const TransportMap m = build_transport_map(ts, *su.cam, pose, TraceOptions{}, 1, threads);
      (void)m;
    }));
    t_correct_f.push_back(seconds_of([&] {
      apply_back_projector(for_camera, image.data(), lp.data());
      resample_to_camera(resampler, lp.data(), corrected.data());
    }));
  }
  for (double t : t_correct) t_correct_f.push_back(t);

  const double k1000 = 1.0 / mp;  // per 1000 x 1000 frame (figures scale with the pixel count)
  auto ms = [&](double s) { return fmt("%.2f", 1e3 * s * k1000); };
  auto ratio = [&](double s) { return fmt("%.2fx", s / floor_s); };
  std::printf("\n### 2. Speed per frame (ms per 1000x1000 frame%s; ratio to the faster cv::remap)\n\n",
              size == 1000 ? "" : ", scaled from the measured size by the pixel count");
  Table t2({"step", "ms/frame", "vs remap"});
  t2.add({"cv::remap INTER_LINEAR, CV_32FC2 map (float frame)", ms(remap32), ratio(remap32)});
  t2.add({"cv::remap INTER_LINEAR, CV_16SC2 map (float frame)", ms(remap16), ratio(remap16)});
  t2.add({"(a) correct onto the camera grid: prepared back projector + resample_to_camera", ms(median(t_correct)),
          ratio(median(t_correct))});
  t2.add({"    the same with back_projection (all entries, not prepared)", ms(median(t_correct_plain)),
          ratio(median(t_correct_plain))});
  t2.add({"(b) onto the sheet grid only: prepared back projector (valid cells)", ms(median(t_bp)), ratio(median(t_bp))});
  t2.add({"    the same with back_projection (all entries, not prepared)", ms(median(t_bp_plain)),
          ratio(median(t_bp_plain))});
  t2.add({"    resample_to_camera only", ms(median(t_resample)), ratio(median(t_resample))});
  t2.add({"(c) forward through the operator: apply_forward", ms(median(t_fwd)), ratio(median(t_fwd))});
  t2.add({"(c) forward_render_values(map, SheetTexture) (footprint-filtered)", ms(median(t_fwd_peer)),
          ratio(median(t_fwd_peer))});
  t2.print();
  std::printf("remap floor used: %.2f ms at %dx%d (%s); apply_forward vs forward_render_values: RMS difference %.2e "
              "of the image's RMS\n",
              1e3 * floor_s, size, size, remap16 < remap32 ? "CV_16SC2" : "CV_32FC2",
              std::sqrt(fwd_diff / std::max(1e-300, fwd_ref)));
  std::printf("\n");
  Table t2b({"step", "figure"});
  t2b.add({"(d) operator build from the map (median of " + std::to_string(t_build.size()) + ")",
           fmt("%.3f s/MP", median(t_build) / mp) + fmt(" (%.2f s)", median(t_build))});
  t2b.add({"(e) least squares, default options, from the back-projection",
           std::to_string(rep.iterations) + " iterations" + (rep.converged ? ", converged" : ", NOT converged") +
               fmt(", %.2f s", median(t_lsq)) + fmt(" (%.0f x remap)", median(t_lsq) / floor_s)});
  t2b.add({"(e) least squares: residual RMS start -> end",
           fmt("%.4g", rep.residual_start) + fmt(" -> %.4g", rep.residual_end) +
               fmt(" (|K^T r| ratio %.2g)", rep.gradient_ratio)});
  t2b.add({"(e) error vs truth: back-projection / least squares",
           fmt("NCC %.4f", ncc(bp, truth, states)) + fmt(" / %.4f", ncc(lsq, truth, states)) +
               fmt("; RMS %.4f", rms_error(bp, truth, states)) + fmt(" / %.4f", rms_error(lsq, truth, states))});
  const double retrace = median(t_retrace), corr = median(t_correct_f);
  t2b.add({"(f) published way: re-trace the map per frame + correct", fmt("%.3f s/frame", (retrace + corr) * k1000)});
  t2b.add({"(f) ours: cached operator, correct", fmt("%.2f ms/frame", 1e3 * corr * k1000)});
  t2b.add({"(f) ratio published / ours", fmt("%.0fx", (retrace + corr) / corr)});
  t2b.print();

  // ---- 3. Series --------------------------------------------------------------
  if (series) {
    std::fprintf(stderr, "series of %d frames ...\n", frames);
    char tmpl[] = "/tmp/correct_bench.XXXXXX";
    if (!mkdtemp(tmpl)) {
      std::perror("mkdtemp");
      return 1;
    }
    const fs::path dir(tmpl);
    try {
      fs::create_directories(dir / "in");
      fs::create_directories(dir / "out");
      auto in_path = [&](std::size_t i) { return (dir / "in" / (std::to_string(i) + ".tif")).string(); };
      auto out_path = [&](std::size_t i) { return (dir / "out" / (std::to_string(i) + ".tif")).string(); };
      const int distinct = std::min(frames, 8);
      std::vector<std::vector<float>> inputs;
      for (int k = 0; k < distinct; ++k) {
        const SheetParticles f = random_sheet_particles(ts.sheet, 0.03 / (mm * mm), 3 * mm, 100 + k);
        const std::vector<float> sheet = f.on(grid);
        std::vector<float> img(map.pixel_count());
        apply_forward(op, sheet.data(), 0.0, img.data());
        for (float& v : img) v *= 0.5f;  // headroom below the 16-bit clip
        inputs.push_back(std::move(img));
      }
      for (int i = 0; i < frames; ++i)
        write_gray_image(in_path(i), inputs[i % distinct].data(), size, size, PixelFormat::uint16);
      std::vector<std::size_t> idx(frames);
      for (int i = 0; i < frames; ++i) idx[i] = i;
      auto read = [&](std::size_t i) {
        Frame f;
        f.in = read_gray_image(in_path(i));
        return f;
      };
      auto write = [&](std::size_t i, const Frame& f) {
        write_gray_image(out_path(i), f.out.data(), size, size, PixelFormat::uint16);
      };
      std::vector<double> fps_io, fps_ours;
      const int rounds = std::max(1, std::min(reps, 3));
      for (int r = 0; r < rounds; ++r) {
        const SeriesStats io = run_series<Frame>(
            idx, {}, read, [](std::size_t, Frame& f) { f.out = std::move(f.in.values); }, write);
        const SeriesStats ours = run_series<Frame>(
            idx, {}, read,
            [&](std::size_t, Frame& f) {
              std::vector<float> sheet(op.grid.cell_count(), 0.0f);
              apply_back_projector(for_camera, f.in.values.data(), sheet.data());
              f.out.resize(map.pixel_count());
              resample_to_camera(resampler, sheet.data(), f.out.data());
            },
            write);
        fps_io.push_back(io.corrected / io.seconds);
        fps_ours.push_back(ours.corrected / ours.seconds);
        std::fprintf(stderr, "  round %d: read+write %.1f frames/s, corrected %.1f frames/s\n", r + 1, fps_io.back(),
                     fps_ours.back());
      }
      std::printf("\n### 3. Series: %d frames of %dx%d, 16-bit TIFF in and out, run_series (median of %d rounds)\n\n",
                  frames, size, size, rounds);
      Table t3({"series", "frames/s", "ms/frame", "vs read+write"});
      const double a = median(fps_io), b = median(fps_ours);
      t3.add({"read + write only (identity correct step)", fmt("%.1f", a), fmt("%.2f", 1e3 / a), "1.00x"});
      t3.add({"read + prepared back projector + resample_to_camera + write", fmt("%.1f", b), fmt("%.2f", 1e3 / b),
              fmt("%.2fx", a / b)});
      t3.print();
    } catch (...) {
      fs::remove_all(dir);
      throw;
    }
    fs::remove_all(dir);
  }

  // ---- 4. Memory ----------------------------------------------------------------
  std::printf("\n### 4. Memory\n\n");
  Table t4({"item", "MiB"});
  t4.add({"peak RSS after the map and the operator builds (getrusage ru_maxrss)", fmt("%.1f", rss_after_build)});
  t4.add({"transport map (arrays)", fmt("%.1f", mib(map.memory_bytes()))});
  t4.add({"correction operator (both directions)", fmt("%.1f", mib(op.memory_bytes()))});
  t4.add({"camera resampler", fmt("%.1f", mib(resampler_bytes))});
  t4.add({"peak RSS at this point of the run", fmt("%.1f", peak_rss_mib())});
  t4.print();

  if (!table) return 0;

  // ---- 5. Run time versus error -------------------------------------------------
  std::optional<Setup> tsu_own;
  const Setup* tsp = &su;
  if (table_size != size) {
    tsu_own = make_setup(ts, camera.model, pose, table_size, threads);
    tsp = &*tsu_own;
  }
  const Setup& tsu = *tsp;
  const double tmm = tsu.footprint_mm;
  const SheetParticles tfield = table_size == size ? field : random_sheet_particles(ts.sheet, 0.03 / (tmm * tmm), 3 * tmm, 7);
  const SheetParticles sparse = random_sheet_particles(ts.sheet, 0.003 / (tmm * tmm), 3 * tmm, 8);
  std::fprintf(stderr, "table: rendering the frames (%dx%d) ...\n", table_size, table_size);
  const std::vector<float> timage =
      table_size == size ? image : forward_render_values(tsu.map, tfield.texture(ts.sheet, tmm / 4));
  const std::vector<float> simage = forward_render_values(tsu.map, sparse.texture(ts.sheet, tmm / 4));
  const int treps = std::max(1, std::min(reps, 5));
  auto centroid = [](double e, int n) { return n ? fmt("%.4f", e) + " (" + std::to_string(n) + ")" : std::string("n/a (0)"); };
  Table t5({"pitch", "footprint filter", "taps_by_weight", "values", "build s", "entries/px", "correct ms/frame",
            "valid cells", "NCC", "RMS", "centroid err px (particles)", "RMS diff to double centre-only ref"});
  for (double pitch : {0.5, 1.0, 2.0}) {
    const SheetGrid g = sheet_grid_covering(ts.sheet, pitch * tmm);
    const std::vector<float> gtruth = tfield.on(g);
    struct Variant {
      bool filter, by_weight;
      CorrectionOperator op;
      double build = 0;
      std::vector<CellState> states;
      std::vector<float> l;
      std::vector<double> times;
    };
    std::vector<Variant> vs(3);
    vs[0].filter = false;                          // centre only (also the float side of the storage error)
    vs[1].filter = vs[1].by_weight = true;         // the default
    vs[2].filter = true;                           // every crossing the full tap count
    for (Variant& v : vs) {
      std::fprintf(stderr, "table: pitch %.1fx, filter %d, taps_by_weight %d: build ...\n", pitch, v.filter, v.by_weight);
      OperatorOptions o;
      o.footprint_filter = v.filter;
      o.taps_by_weight = v.by_weight;
      v.build = seconds_of([&] { v.op = build_correction_operator(tsu.map, g, o, threads); });
      v.states = classify_cells({{&v.op, 1.0}}, ts);
    }
    // The double reference (centre-only splats, straight from the map) on the filter-off row's cells.
    const std::vector<CellState>& ref_states = vs[0].states;
    std::vector<double> ref, ref_times;
    std::fprintf(stderr, "table: pitch %.1fx, timing (interleaved) ...\n", pitch);
    for (int r = 0; r < treps + 1; ++r) {  // round 0 warms up
      for (Variant& v : vs) {
        const double t = seconds_of([&] { v.l = back_projection({{&v.op, timage.data()}}, v.states); });
        if (r) v.times.push_back(t);
      }
      if (r < 3) {
        const double t = seconds_of([&] { ref = double_back_projection(tsu.map, g, timage.data(), ref_states); });
        if (r) ref_times.push_back(t);
      }
    }
    {
      const std::vector<float> rf(ref.begin(), ref.end());
      const std::vector<double> sd = double_back_projection(tsu.map, g, simage.data(), ref_states);
      int rn = 0;
      const double rcen = mean_centroid_error_cells(std::vector<float>(sd.begin(), sd.end()), sparse, g, ref_states, &rn) * pitch;
      t5.add({fmt("%.1fx", pitch) + fmt(" (%.3f mm)", g.mm_per_px), "off (centre only)", "-",
              "double (bench, from the map)", "-",
              fmt("%.2f", double(tsu.map.crossing_count()) / tsu.map.pixel_count()) + " crossings",
              fmt("%.2f", 1e3 * median(ref_times) * 1e6 / tsu.map.pixel_count()) + " (1 thread)",
              std::to_string(count_cells(ref_states).valid), fmt("%.4f", ncc(rf, gtruth, ref_states)),
              fmt("%.4f", rms_error(ref, gtruth, ref_states)), centroid(rcen, rn), "0"});
    }
    for (Variant& v : vs) {
      int nc = 0;
      const double cen =
          mean_centroid_error_cells(back_projection({{&v.op, simage.data()}}, v.states), sparse, g, v.states, &nc) * pitch;
      std::string vs_ref;
      if (!v.filter) {
        // The float32 storage error: the float operator (filter off) against the double reference.
        double worst = 0;
        for (std::size_t c = 0; c < ref.size(); ++c)
          if (is_valid(ref_states[c])) worst = std::max(worst, std::abs(double(v.l[c]) - ref[c]));
        vs_ref = fmt("%.2e", rms_error(v.l, ref, ref_states)) + fmt(" (max %.1e)", worst);
      } else {
        // Against the double centre-only reference: the footprint filter's change (plus storage).
        vs_ref = fmt("%.2e", rms_error(v.l, ref, ref_states));
      }
      t5.add({fmt("%.1fx", pitch) + fmt(" (%.3f mm)", g.mm_per_px), v.filter ? "on" : "off (centre only)",
              v.filter ? (v.by_weight ? "on" : "off") : "-", "float32 (operator)", fmt("%.3f", v.build),
              fmt("%.2f", double(v.op.entry_count()) / v.op.pixel_count()),
              fmt("%.2f", 1e3 * median(v.times) * 1e6 / tsu.map.pixel_count()), std::to_string(count_cells(v.states).valid),
              fmt("%.4f", ncc(v.l, gtruth, v.states)), fmt("%.4f", rms_error(v.l, gtruth, v.states)), centroid(cen, nc),
              vs_ref});
    }
  }
  std::printf("\n### 5. Run time versus error, %dx%d camera (particles 3 px, 0.03 per px, rendered with "
              "forward_render_values at 1/4 px texels; errors on each row's valid cells against the field's point "
              "samples at the cell centres; correct = back_projection, ms per 1000x1000 frame; centroid error in "
              "camera px (cells x pitch), sparse field 0.003 per px)\n\n",
              table_size, table_size);
  t5.print();

  // ---- 6. The mask thresholds -------------------------------------------------
  std::fprintf(stderr, "mask thresholds: operator at 1x, thresholds 0 ...\n");
  const CorrectionOperator mop = table_size == size ? CorrectionOperator{} : build_correction_operator(tsu.map, tsu.grid, {}, threads);
  const CorrectionOperator& mo = table_size == size ? op : mop;
  MaskOptions zero;
  zero.min_mean_weight = 0;
  zero.min_pixels_per_cell = 0;
  const std::vector<CellState> st0 = classify_cells({{&mo, 1.0}}, ts, zero);
  const std::vector<CellState> stdef = classify_cells({{&mo, 1.0}}, ts);
  const std::vector<float> mtruth = tfield.on(tsu.grid);
  const std::vector<float> bp0 = back_projection({{&mo, timage.data()}}, st0);
  LeastSquaresReport rep0;
  std::fprintf(stderr, "mask thresholds: least squares on all seen cells ...\n");
  const std::vector<float> lsq0 = least_squares({{&mo, timage.data()}}, st0, bp0, {}, &rep0);
  // Per bin: RMS error and NCC of both reconstructions against the truth.
  struct Moments {
    double n = 0, a = 0, b = 0, aa = 0, bb = 0, ab = 0;
    void add(double x, double y) {
      ++n;
      a += x;
      b += y;
      aa += x * x;
      bb += y * y;
      ab += x * y;
    }
    double rms() const { return std::sqrt((aa - 2 * ab + bb) / n); }
    double ncc() const {
      const double va = aa - a * a / n, vb = bb - b * b / n;
      return (ab - a * b / n) / std::sqrt(va * vb);
    }
  };
  struct Bin {
    double lo, hi;
    std::size_t cells = 0, valid_by_default = 0;
    double se_truth = 0;
    Moments bp, lsq;
  };
  auto bin_cells = [&](const std::vector<double>& edges, const std::function<double(std::size_t)>& key, bool no_direct_bin) {
    std::vector<Bin> bins;
    for (std::size_t k = 0; k + 1 < edges.size(); ++k) {
      bins.emplace_back();
      bins.back().lo = edges[k];
      bins.back().hi = edges[k + 1];
    }
    Bin none;
    none.lo = none.hi = -1;
    for (std::size_t c = 0; c < st0.size(); ++c) {
      if (!is_valid(st0[c])) continue;
      Bin* b = nullptr;
      if (no_direct_bin && mo.cell_direct_pixels[c] <= 0) b = &none;
      else {
        const double x = key(c);
        for (Bin& bb : bins)
          if (x >= bb.lo && x < bb.hi) b = &bb;
      }
      if (!b) continue;
      ++b->cells;
      b->valid_by_default += is_valid(stdef[c]);
      b->bp.add(bp0[c], mtruth[c]);
      b->lsq.add(lsq0[c], mtruth[c]);
      b->se_truth += double(mtruth[c]) * mtruth[c];
    }
    if (no_direct_bin) bins.push_back(none);
    return bins;
  };
  auto print_bins = [&](const char* what, const std::vector<Bin>& bins) {
    Table t({what, "cells", "valid by default", "truth RMS", "RMS back-proj.", "RMS least sq.", "NCC back-proj.",
             "NCC least sq."});
    for (const Bin& b : bins) {
      const std::string range = b.lo < 0 ? "no direct pixel (reflections only)"
                                          : fmt("%.2g", b.lo) + " - " + (std::isinf(b.hi) ? "inf" : fmt("%.2g", b.hi));
      const double n = std::max<double>(1, b.cells);
      const bool some = b.cells > 1;
      t.add({range, std::to_string(b.cells), b.cells ? fmt("%.0f %%", 100.0 * b.valid_by_default / n) : "-",
             some ? fmt("%.4f", std::sqrt(b.se_truth / n)) : "-", some ? fmt("%.4f", b.bp.rms()) : "-",
             some ? fmt("%.4f", b.lsq.rms()) : "-", some ? fmt("%.3f", b.bp.ncc()) : "-",
             some ? fmt("%.3f", b.lsq.ncc()) : "-"});
    }
    t.print();
  };
  const double inf = INFINITY;
  const CellCounts c0 = count_cells(st0), cdef = count_cells(stdef);
  std::printf("\n### 6. Mask thresholds (MaskOptions 0, 0: every seen cell outside the solids reconstructed, %zu cells; "
              "the defaults keep %zu; %dx%d camera, 1x grid; least squares %d iterations%s; errors against the "
              "particle field per cell bin; bins with fewer than 2 cells not evaluated)\n\n",
              c0.valid, cdef.valid, table_size, table_size, rep0.iterations, rep0.converged ? ", converged" : ", not converged");
  print_bins("mean weight per direct pixel (cell_weight / cell_direct_pixels)",
             bin_cells({0, 0.02, 0.05, 0.1, 0.2, 0.4, 0.6, inf},
                       [&](std::size_t c) { return double(mo.cell_weight[c]) / mo.cell_direct_pixels[c]; }, true));
  std::printf("\n");
  print_bins("camera pixels per cell (cell_pixels)",
             bin_cells({0, 0.1, 0.25, 0.5, 1, inf}, [&](std::size_t c) { return double(mo.cell_pixels[c]); }, false));
  std::printf("\n");
  print_bins("direct camera pixels per cell (cell_direct_pixels; the mostly_reflected test)",
             bin_cells({0, 1e-30, 0.1, 0.25, 0.5, 1, inf}, [&](std::size_t c) { return double(mo.cell_direct_pixels[c]); },
                       false));
  std::printf("peak RSS %.1f MiB\n", peak_rss_mib());
  return 0;
}
