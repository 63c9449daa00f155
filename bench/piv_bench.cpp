// piv_bench: PIV evaluation speed and accuracy (results in bench/RESULTS.md).
//  1. vectors per second per pass: 32 px windows, 50 % overlap, one undeformed
//     pass over a 1024 x 1024 px synthetic pair, on 1 and on N threads (default
//     2): wall time (median and best of the repetitions) and the process's CPU
//     time, which a loaded machine inflates less; then the correlation + peak
//     alone on one thread, batched as the evaluator does it and, for
//     comparison in the same run, one OpenCV 2-D DFT call per window (the
//     evaluator's scheme before the batching);
//  2. time versus error: passes, window sizes and deformation interpolations
//     on a 512 x 512 px pair of a rotation plus a uniform shift.
// usage: piv_bench [threads] [reps]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
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

// The correlator as it was before the batching, kept here as the reference
// the batched one is timed against: per window one real 2-D DFT call for each
// frame, mulSpectrums and one inverse 2-D call (mean subtraction as
// BatchCorrelator's, without masks).
class PerWindowDftCorrelator {
 public:
  explicit PerWindowDftCorrelator(int n) : n_(n) {
    forward_ = cv::hal::DFT2D::create(n, n, CV_32F, 1, 1, 0);
    inverse_ = cv::hal::DFT2D::create(n, n, CV_32F, 1, 1, cv::DFT_INVERSE | cv::DFT_REAL_OUTPUT);
    for (cv::Mat* m : {&a_, &b_, &fa_, &fb_, &product_, &plane_}) *m = cv::Mat::zeros(n, n, CV_32F);
  }
  const float* correlate(const float* a, const float* b, int stride) {
    const double ea = load(a, stride, a_), eb = load(b, stride, b_);
    forward_->apply(a_.data, a_.step, fa_.data, fa_.step);
    forward_->apply(b_.data, b_.step, fb_.data, fb_.step);
    cv::mulSpectrums(fb_, fa_, product_, 0, /*conjB=*/true);
    inverse_->apply(product_.data, product_.step, plane_.data, plane_.step);
    plane_ *= 1.0 / (static_cast<double>(n_) * n_ * std::sqrt(ea * eb));
    return plane_.ptr<float>();
  }

 private:
  double load(const float* src, int stride, cv::Mat& dst) const {
    double sum = 0, energy = 0;
    for (int y = 0; y < n_; ++y)
      for (int x = 0; x < n_; ++x) sum += src[y * stride + x];
    const float mean = static_cast<float>(sum / (n_ * n_));
    for (int y = 0; y < n_; ++y)
      for (int x = 0; x < n_; ++x) {
        const float d = src[y * stride + x] - mean;
        dst.at<float>(y, x) = d;
        energy += d * d;
      }
    return energy;
  }
  int n_;
  cv::Ptr<cv::hal::DFT2D> forward_, inverse_;
  cv::Mat a_, b_, fa_, fb_, product_, plane_;
};

double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

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
  std::printf("## 1. one pass, 32 px windows, 50 %% overlap, 1024 x 1024 px (63 x 63 = 3969 vectors), %d repetitions\n\n",
              reps);
  std::printf("| threads | s per pass (median) | vectors/s per pass (median) | vectors/s per pass (best) | "
              "CPU s per pass | vectors per CPU-second |\n|---|---|---|---|---|---|\n");
  for (int t : {1, threads}) {
    one.threads = t;
    std::vector<double> s, cpu;
    std::size_t n = 0;
    for (int r = 0; r < reps; ++r) {
      const double c0 = cpu_seconds();
      s.push_back(bench::seconds_of([&] { n = evaluate_piv(p.a, p.b, cv::Mat(), one).size(); }));
      cpu.push_back(cpu_seconds() - c0);
    }
    const double m = bench::median(s), best = *std::min_element(s.begin(), s.end()), c = bench::median(cpu);
    std::printf("| %d | %.4f | %.0f | %.0f | %.4f | %.0f |\n", t, m, n / m, n / best, c, n / c);
  }
  std::printf("\n| 1 thread, correlation + peak only | s per 3969 windows (median) | windows/s (median) | "
              "windows/s (best) | windows per CPU-second |\n|---|---|---|---|---|\n");
  const int stride = static_cast<int>(p.a.step1());
  auto time_windows = [&](const char* what, const auto& run_all) {
    std::vector<double> s, cpu;
    int windows = 0;
    for (int r = 0; r < reps; ++r) {
      const double c0 = cpu_seconds();
      s.push_back(bench::seconds_of([&] { windows = run_all(); }));
      cpu.push_back(cpu_seconds() - c0);
    }
    const double m = bench::median(s), best = *std::min_element(s.begin(), s.end());
    std::printf("| %s | %.4f | %.0f | %.0f | %.0f |\n", what, m, windows / m, windows / best, windows / bench::median(cpu));
  };
  BatchCorrelator batch(32, 16);
  time_windows("batched, 16 pairs per DFT call (the evaluator)", [&] {
    int windows = 0;
    for (int y = 0; y + 32 <= 1024; y += 16)
      for (int x = 0; x + 32 <= 1024;) {
        batch.clear();
        for (; x + 32 <= 1024 && !batch.full(); x += 16)
          batch.add(p.a.ptr<float>(y) + x, stride, nullptr, p.b.ptr<float>(y) + x, stride, nullptr);
        batch.correlate();
        for (int k = 0; k < batch.size(); ++k) windows += find_correlation_peak(batch.plane(k), 32).found;
      }
    return windows;
  });
  PerWindowDftCorrelator previous(32);
  time_windows("one 2-D DFT call per window (before)", [&] {
    int windows = 0;
    for (int y = 0; y + 32 <= 1024; y += 16)
      for (int x = 0; x + 32 <= 1024; x += 16)
        windows += find_correlation_peak(previous.correlate(p.a.ptr<float>(y) + x, p.b.ptr<float>(y) + x, stride), 32).found;
    return windows;
  });
  std::printf("\n");

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
