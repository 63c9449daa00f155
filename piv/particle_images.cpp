#include "piv/particle_images.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace glasspiv {

void add_particle_image(cv::Mat& image, double x_px, double y_px, double peak_intensity, double diameter_px) {
  const double sigma = diameter_px / 4;
  const double k = 1 / (std::sqrt(2.0) * sigma);
  const int reach = static_cast<int>(std::ceil(4 * sigma + 1));
  const int x0 = std::max(0, static_cast<int>(std::floor(x_px)) - reach);
  const int x1 = std::min(image.cols - 1, static_cast<int>(std::floor(x_px)) + reach);
  const int y0 = std::max(0, static_cast<int>(std::floor(y_px)) - reach);
  const int y1 = std::min(image.rows - 1, static_cast<int>(std::floor(y_px)) + reach);
  if (x0 > x1 || y0 > y1) return;
  // The integral of exp(-t^2 / (2 sigma^2)) over a pixel [c - 1/2, c + 1/2] is
  // sqrt(pi / 2) sigma (erf((c + 1/2 - p) k) - erf((c - 1/2 - p) k)).
  const double scale = peak_intensity * M_PI / 2 * sigma * sigma;
  double ex[64], ey[64];
  if (x1 - x0 >= 64 || y1 - y0 >= 64) throw std::invalid_argument("add_particle_image: diameter too large");
  for (int x = x0; x <= x1; ++x) ex[x - x0] = std::erf((x + 0.5 - x_px) * k) - std::erf((x - 0.5 - x_px) * k);
  for (int y = y0; y <= y1; ++y) ey[y - y0] = std::erf((y + 0.5 - y_px) * k) - std::erf((y - 0.5 - y_px) * k);
  for (int y = y0; y <= y1; ++y) {
    float* row = image.ptr<float>(y);
    for (int x = x0; x <= x1; ++x) row[x] += static_cast<float>(scale * ex[x - x0] * ey[y - y0]);
  }
}

ParticleImagePair particle_image_pair(const ParticleImageOptions& o, const DisplacementField& displacement) {
  if (o.width_px < 1 || o.height_px < 1 || !(o.particles_per_pixel >= 0) || !(o.diameter_px > 0) ||
      !(o.diameter_px <= 24) || !(o.margin_px >= 0))
    throw std::invalid_argument("particle_image_pair: bad options");
  ParticleImagePair pair{cv::Mat::zeros(o.height_px, o.width_px, CV_32F), cv::Mat::zeros(o.height_px, o.width_px, CV_32F)};
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> ux(-o.margin_px - 0.5, o.width_px - 0.5 + o.margin_px);
  std::uniform_real_distribution<double> uy(-o.margin_px - 0.5, o.height_px - 0.5 + o.margin_px);
  std::uniform_real_distribution<double> intensity(0.5, 1.0);
  const double area = (o.width_px + 2 * o.margin_px) * (o.height_px + 2 * o.margin_px);
  const auto n = static_cast<long long>(std::llround(o.particles_per_pixel * area));
  for (long long i = 0; i < n; ++i) {
    const double mx = ux(rng), my = uy(rng), i0 = intensity(rng);
    const std::array<double, 2> d = displacement(mx, my);
    add_particle_image(pair.a, mx - 0.5 * d[0], my - 0.5 * d[1], i0, o.diameter_px);
    add_particle_image(pair.b, mx + 0.5 * d[0], my + 0.5 * d[1], i0, o.diameter_px);
  }
  if (o.noise_rms > 0) {
    std::normal_distribution<double> noise(0, o.noise_rms);
    for (cv::Mat* m : {&pair.a, &pair.b})
      for (int y = 0; y < m->rows; ++y)
        for (float* p = m->ptr<float>(y); p < m->ptr<float>(y) + m->cols; ++p) *p += static_cast<float>(noise(rng));
  }
  return pair;
}

}  // namespace glasspiv
