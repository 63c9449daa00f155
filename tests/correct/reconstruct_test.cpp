// Round trips through the example reactor: a known particle field on the sheet,
// rendered through the glass by the transport map (footprint-filtered texture,
// independent of the operator), then corrected.
#include "correct/reconstruct.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "correct/camera_resampler.h"
#include "correct/cell_mask.h"
#include "render/forward_render.h"
#include "tests/correct/test_scenes.h"

namespace glasspiv {
namespace {

struct Particle {
  double s_mm, t_mm;
};

// Gaussian particles (1/e^2 diameter) at uniform random places of the sheet.
struct ParticleField {
  std::vector<Particle> particles;
  double diameter_mm = 1;

  double at(double s, double t) const {
    const double r2 = 0.25 * diameter_mm * diameter_mm;
    double v = 0;
    for (const Particle& p : particles) {
      const double ds = s - p.s_mm, dt = t - p.t_mm;
      if (std::abs(ds) < 2 * diameter_mm && std::abs(dt) < 2 * diameter_mm) v += std::exp(-2 * (ds * ds + dt * dt) / r2);
    }
    return v;
  }
  // Point samples at the cell centres of a grid.
  std::vector<float> on(const SheetGrid& g) const {
    std::vector<float> v(g.cell_count(), 0.0f);
    const double reach = 2 * diameter_mm, r2 = 0.25 * diameter_mm * diameter_mm;
    for (const Particle& p : particles) {
      const int c0 = std::max(0, int(std::floor(g.col(p.s_mm - reach)))), c1 = std::min(g.cols - 1, int(std::ceil(g.col(p.s_mm + reach))));
      const int r0 = std::max(0, int(std::floor(g.row(p.t_mm + reach)))), r1 = std::min(g.rows - 1, int(std::ceil(g.row(p.t_mm - reach))));
      for (int r = r0; r <= r1; ++r)
        for (int c = c0; c <= c1; ++c) {
          const double ds = g.s_mm(c) - p.s_mm, dt = g.t_mm(r) - p.t_mm;
          v[static_cast<std::size_t>(r) * g.cols + c] += static_cast<float>(std::exp(-2 * (ds * ds + dt * dt) / r2));
        }
    }
    return v;
  }
};

ParticleField particles(const SheetPlane& sheet, double per_mm2, double diameter_mm, std::uint64_t seed) {
  ParticleField f;
  f.diameter_mm = diameter_mm;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> us(-0.5 * sheet.extent_s_mm, 0.5 * sheet.extent_s_mm),
      ut(-0.5 * sheet.extent_t_mm, 0.5 * sheet.extent_t_mm);
  const auto n = static_cast<long>(per_mm2 * sheet.extent_s_mm * sheet.extent_t_mm);
  for (long i = 0; i < n; ++i) f.particles.push_back({us(rng), ut(rng)});
  return f;
}

// Normalised cross-correlation of a and b over the valid cells.
double ncc(const std::vector<float>& a, const std::vector<float>& b, const std::vector<CellState>& states) {
  double sa = 0, sb = 0, n = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (states[i] == CellState::valid) {
      sa += a[i];
      sb += b[i];
      ++n;
    }
  const double ma = sa / n, mb = sb / n;
  double ab = 0, aa = 0, bb = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (states[i] == CellState::valid) {
      ab += (a[i] - ma) * (b[i] - mb);
      aa += (a[i] - ma) * (a[i] - ma);
      bb += (b[i] - mb) * (b[i] - mb);
    }
  return ab / std::sqrt(aa * bb);
}

double rms_error(const std::vector<float>& a, const std::vector<float>& truth, const std::vector<CellState>& states) {
  double s = 0, n = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (states[i] == CellState::valid) {
      s += double(a[i] - truth[i]) * (a[i] - truth[i]);
      ++n;
    }
  return std::sqrt(s / n);
}

// Mean distance (cells) between the intensity centroid of `l` in a window
// around each isolated particle whose window is all valid, and its true place.
double mean_centroid_error_px(const std::vector<float>& l, const ParticleField& f, const SheetGrid& g,
                              const std::vector<CellState>& states, int* counted) {
  const int half = static_cast<int>(std::ceil(f.diameter_mm / g.mm_per_px));
  double sum = 0;
  int n = 0;
  for (std::size_t k = 0; k < f.particles.size(); ++k) {
    const Particle& p = f.particles[k];
    bool isolated = true;
    for (std::size_t j = 0; j < f.particles.size() && isolated; ++j)
      isolated = j == k || std::hypot(f.particles[j].s_mm - p.s_mm, f.particles[j].t_mm - p.t_mm) > 3 * f.diameter_mm;
    if (!isolated) continue;
    const double x = g.col(p.s_mm), y = g.row(p.t_mm);
    const int cx = static_cast<int>(std::lround(x)), cy = static_cast<int>(std::lround(y));
    if (cx - half < 0 || cy - half < 0 || cx + half >= g.cols || cy + half >= g.rows) continue;
    bool ok = true;
    double w = 0, wx = 0, wy = 0;
    for (int r = cy - half; r <= cy + half && ok; ++r)
      for (int c = cx - half; c <= cx + half && ok; ++c) {
        const std::size_t i = static_cast<std::size_t>(r) * g.cols + c;
        ok = states[i] == CellState::valid;
        const double v = std::max(0.0f, l[i]);
        w += v;
        wx += v * c;
        wy += v * r;
      }
    if (!ok || w <= 0) continue;
    sum += std::hypot(wx / w - x, wy / w - y);
    ++n;
  }
  *counted = n;
  return n ? sum / n : 1e9;
}

// The texture for the forward render: the field sampled 4x finer than the grid.
SheetTexture fine_texture(const ParticleField& f, const SheetPlane& sheet, double mm_per_texel) {
  const SheetGrid fine = sheet_grid_covering(sheet, mm_per_texel);
  const std::vector<float> v = f.on(fine);
  return SheetTexture(v.data(), fine.rows, fine.cols, fine.mm_per_px);
}

TEST(Reconstruct, OneCameraRoundTripThroughTheReactor) {
  const SceneCameraSetup s = load_scene_camera("reactor.yaml", 4);
  const TransportMap map = build_transport_map(s.trace, s.camera, s.pose, TraceOptions{}, 1, 2);
  const TransportMap direct = glass_removed_map(s.trace, s.camera, s.pose, 1, 2);
  const double mm = median_footprint_mm(direct);  // the camera's own pixel on the sheet
  const SheetGrid grid = sheet_grid_covering(s.trace.sheet, mm);
  // PIV-like particles: 3 px images, 0.03 particles per px of the undistorted view.
  const ParticleField field = particles(s.trace.sheet, 0.03 / (mm * mm), 3 * mm, 7);
  const std::vector<float> image = forward_render_values(map, fine_texture(field, s.trace.sheet, mm / 4));

  const CorrectionOperator op = build_correction_operator(map, grid);
  const std::vector<CellState> states = classify_cells({{&op, 1.0}}, s.trace);
  const CellCounts counts = count_cells(states);
  const std::vector<float> l = back_projection({{&op, image.data()}}, states);
  // A camera's weight cancels in the normalisation (the general path against the one-camera one).
  const std::vector<float> weighted = back_projection({{&op, image.data(), 2.0}}, states);
  for (std::size_t i = 0; i < l.size(); ++i) ASSERT_NEAR(weighted[i], l[i], 1e-5f * (1 + std::abs(l[i])));
  const std::vector<float> truth = field.on(grid);
  // Centroids on a sparse field of the same particles: isolated ones.
  const ParticleField sparse = particles(s.trace.sheet, 0.003 / (mm * mm), 3 * mm, 8);
  const std::vector<float> sparse_image = forward_render_values(map, fine_texture(sparse, s.trace.sheet, mm / 4));
  int n = 0;
  const double centroid =
      mean_centroid_error_px(back_projection({{&op, sparse_image.data()}}, states), sparse, grid, states, &n);
  const double c = ncc(l, truth, states);
  std::printf("one camera: grid %dx%d at %.3f mm; valid %.1f%% of the fluid region (never seen %zu, few pixels %zu, "
              "low weight %zu, mostly reflected %zu cells); NCC %.4f; centroid error %.4f px over %d particles\n",
              grid.cols, grid.rows, mm, 100 * counts.valid_fraction_of_fluid(), counts.never_seen, counts.few_pixels,
              counts.low_weight, counts.mostly_reflected, c, centroid, n);
  EXPECT_GE(c, 0.95);
  EXPECT_LT(centroid, 0.1);
  EXPECT_GT(n, 50);
  // Least squares from the back-projection: a smaller residual and no worse a match.
  LeastSquaresReport rep;
  const std::vector<float> lsq = least_squares({{&op, image.data()}}, states, l, {}, &rep);
  const double c_lsq = ncc(lsq, truth, states);
  std::printf("least squares: %d iterations, residual RMS %.4g -> %.4g, NCC %.4f, RMS error %.4f (back-projection %.4f)\n",
              rep.iterations, rep.residual_start, rep.residual_end, c_lsq, rms_error(lsq, truth, states),
              rms_error(l, truth, states));
  EXPECT_LT(rep.residual_end, 0.5 * rep.residual_start);
  EXPECT_GE(c_lsq, c);
  EXPECT_GT(counts.valid_fraction_of_fluid(), 0.3);
}

// Five cameras around the reactor: together they see nearly all of the
// sheet's fluid region, and where one camera's pixels are lit through several
// paths (reflections) least squares explains the ghosts away.
TEST(Reconstruct, FiveCamerasFillTheRimsAndLeastSquaresRemovesGhosts) {
  constexpr int kBinning = 8, kCameras = 5;
  std::vector<SceneCameraSetup> setups;
  std::vector<TransportMap> maps;
  for (int k = 0; k < kCameras; ++k) {
    setups.push_back(load_scene_camera("reactor_5cams.yaml", kBinning, k));
    maps.push_back(build_transport_map(setups[k].trace, setups[k].camera, setups[k].pose, TraceOptions{}, 1, 2));
  }
  const TraceScene& trace = setups[0].trace;
  const double mm = median_footprint_mm(glass_removed_map(trace, setups[1].camera, setups[1].pose, 1, 2));
  const SheetGrid grid = sheet_grid_covering(trace.sheet, mm);
  const ParticleField field = particles(trace.sheet, 0.03 / (mm * mm), 3 * mm, 9);
  const SheetTexture texture = fine_texture(field, trace.sheet, mm / 4);
  std::vector<CorrectionOperator> ops;
  std::vector<std::vector<float>> images;
  std::vector<CameraOperator> cams;
  std::vector<CameraImage> views;
  for (int k = 0; k < kCameras; ++k) {
    ops.push_back(build_correction_operator(maps[k], grid));
    images.push_back(forward_render_values(maps[k], texture));
  }
  for (int k = 0; k < kCameras; ++k) {
    cams.push_back({&ops[k], 1.0});
    views.push_back({&ops[k], images[k].data()});
  }
  const std::vector<CellState> together = classify_cells(cams, trace);
  const CellCounts all = count_cells(together);
  const CellCounts centre = count_cells(classify_cells({cams[1]}, trace));
  std::printf("five cameras: valid %.1f%% of the fluid region (%.2f%% of what they see); the centre camera alone %.1f%%\n",
              100 * all.valid_fraction_of_fluid(), 100 * all.valid_fraction_of_seen(),
              100 * centre.valid_fraction_of_fluid());
  std::printf("  few pixels %zu, low weight %zu, mostly reflected %zu, never seen %zu, valid %zu cells\n", all.few_pixels, all.low_weight, all.mostly_reflected, all.never_seen, all.valid);
  EXPECT_GE(all.valid_fraction_of_seen(), 0.99);
  EXPECT_GT(all.valid_fraction_of_fluid(), centre.valid_fraction_of_fluid());

  const std::vector<float> truth = field.on(grid);
  const std::vector<float> acc = back_projection(views, together);
  LeastSquaresReport rep;
  const std::vector<float> lsq = least_squares(views, together, acc, {}, &rep);
  const double e_acc = rms_error(acc, truth, together), e_lsq = rms_error(lsq, truth, together);
  std::printf("accumulation RMS error %.4f, NCC %.4f; least squares (%d iterations) RMS error %.4f, NCC %.4f\n", e_acc,
              ncc(acc, truth, together), rep.iterations, e_lsq, ncc(lsq, truth, together));
  EXPECT_LT(e_lsq, 0.8 * e_acc);
}

}  // namespace
}  // namespace glasspiv
