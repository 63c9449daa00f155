// piv_bench: PIV evaluation speed and accuracy (results in bench/RESULTS.md).
//  1. vectors per second per pass: 32 px windows, 50 % overlap, one undeformed
//     pass over a 1024 x 1024 px synthetic pair, on 1 and on N threads (default
//     2), and the correlation + peak alone on one thread;
//  2. time versus error: passes, window sizes and deformation interpolations
//     on a 512 x 512 px pair of a rotation plus a uniform shift.
// usage: piv_bench [threads] [reps]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "piv/cross_correlation.h"
#include "piv/particle_images.h"
#include "piv/piv_evaluate.h"
#include "piv/subpixel_peak.h"

using namespace glasspiv;

namespace {

struct Score {
  double rms = 0, bias = 0;
  int valid = 0;
};

Score score(const PivField& f, const DisplacementField& truth) {
  Score s;
  double s2 = 0, su = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (f.flags[i] != VectorFlag::valid) continue;
    const auto d = truth(f.x_px(i), f.y_px(i));
    const double eu = f.u_px[i] - d[0], ev = f.v_px[i] - d[1];
    s2 += eu * eu + ev * ev;
    su += 0.5 * (eu + ev);
    ++s.valid;
  }
  s.rms = std::sqrt(s2 / (2.0 * s.valid));
  s.bias = su / s.valid;
  return s;
}

std::string windows_text(const std::vector<int>& w) {
  std::string t;
  for (int n : w) t += (t.empty() ? "" : " -> ") + std::to_string(n);
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  const int threads = argc > 1 ? std::atoi(argv[1]) : 2;
  const int reps = argc > 2 ? std::atoi(argv[2]) : 5;

  // 1. Throughput of one pass.
  ParticleImageOptions big;
  big.width_px = big.height_px = 1024;
  big.seed = 1;
  const DisplacementField shift = [](double, double) { return std::array<double, 2>{2.3, -1.7}; };
  const ParticleImagePair p = particle_image_pair(big, shift);
  PivOptions one;
  one.window_px = {32};
  std::printf("## 1. one pass, 32 px windows, 50 %% overlap, 1024 x 1024 px (63 x 63 = 3969 vectors), median of %d\n\n",
              reps);
  std::printf("| threads | s per pass | vectors/s per pass |\n|---|---|---|\n");
  for (int t : {1, threads}) {
    one.threads = t;
    std::vector<double> s;
    std::size_t n = 0;
    for (int r = 0; r < reps; ++r) s.push_back(bench::seconds_of([&] { n = evaluate_piv(p.a, p.b, cv::Mat(), one).size(); }));
    const double m = bench::median(s);
    std::printf("| %d | %.4f | %.0f |\n", t, m, n / m);
  }
  {
    WindowCorrelator c(32);
    const int stride = static_cast<int>(p.a.step1());
    std::vector<double> s;
    int windows = 0;
    for (int r = 0; r < reps; ++r)
      s.push_back(bench::seconds_of([&] {
        windows = 0;
        for (int y = 0; y + 32 <= 1024; y += 16)
          for (int x = 0; x + 32 <= 1024; x += 16) {
            c.correlate(p.a.ptr<float>(y) + x, stride, nullptr, p.b.ptr<float>(y) + x, stride, nullptr);
            windows += find_correlation_peak(c).found;
          }
      }));
    const double m = bench::median(s);
    std::printf("| 1, correlation + peak only | %.4f | %.0f |\n\n", m, windows / m);
  }

  // 2. Time versus error.
  ParticleImageOptions mid;
  mid.width_px = mid.height_px = 512;
  mid.seed = 2;
  const double omega = 0.01, c = 255.5;
  const DisplacementField flow = [=](double x, double y) {
    return std::array<double, 2>{2.3 - omega * (y - c), 1.7 + omega * (x - c)};
  };
  const ParticleImagePair q = particle_image_pair(mid, flow);
  struct Case {
    std::vector<int> windows;
    DeformInterpolation interpolation;
  };
  const std::vector<Case> cases{
      {{32}, DeformInterpolation::bspline5},         {{64, 32}, DeformInterpolation::bilinear},
      {{64, 32}, DeformInterpolation::bicubic},      {{64, 32}, DeformInterpolation::bspline3},
      {{64, 32}, DeformInterpolation::bspline5},     {{64, 32, 32}, DeformInterpolation::bspline5},
      {{64, 32, 16}, DeformInterpolation::bspline5}, {{32, 16}, DeformInterpolation::bspline5},
  };
  std::printf("## 2. 512 x 512 px, rotation 0.01 rad + shift (2.3, 1.7) px (up to 4.9 px), 50 %% overlap, "
              "%d threads, median of %d\n\n", threads, reps);
  std::printf("| windows (px) | deformation | vectors | s | RMS error (px) | bias (px) |\n|---|---|---|---|---|---|\n");
  for (const Case& k : cases) {
    PivOptions o;
    o.window_px = k.windows;
    o.interpolation = k.interpolation;
    o.threads = threads;
    PivField f;
    std::vector<double> s;
    for (int r = 0; r < reps; ++r) s.push_back(bench::seconds_of([&] { f = evaluate_piv(q.a, q.b, cv::Mat(), o); }));
    const Score e = score(f, flow);
    std::printf("| %s | %s | %d / %zu | %.4f | %.4f | %+.4f |\n", windows_text(k.windows).c_str(),
                k.windows.size() > 1 ? deform_interpolation_name(k.interpolation) : "none (one pass)", e.valid, f.size(),
                bench::median(s), e.rms, e.bias);
  }
  std::printf("\npeak RSS %.0f MiB\n", bench::peak_rss_mib());
  return 0;
}
