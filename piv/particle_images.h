#pragma once
// Synthetic PIV recordings with a known displacement field, the ground truth
// of the piv tests and benchmark (the standard test of Raffel et al., 3rd ed.,
// sec. 6.1, and of the PIV Challenge's synthetic cases).
//
// Particles are placed uniformly at random (std::mt19937_64 from a seed) over
// the image and a margin around it, so particles enter and leave; each gets a
// peak intensity uniform in [0.5, 1]. A particle whose mid-point between the
// exposures is m appears at m - d(m)/2 in frame A and m + d(m)/2 in frame B,
// d the displacement of frame B relative to frame A (u along +x, v along +y,
// px), so a linear field is sampled exactly at every window centre. Particle
// images are Gaussians I0 exp(-8 r^2 / D^2) (D the 1/e^2 diameter, sigma =
// D/4) integrated exactly over each pixel's area (a product of erf
// differences), as a fill factor of 1 records them. Pixel (0, 0) is centred on
// (0, 0) (docs/conventions.md). No I/O.
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include <opencv2/core.hpp>

namespace glasspiv {

struct ParticleImageOptions {
  int width_px = 256, height_px = 256;
  double particles_per_pixel = 0.05;  // over the image and the margin
  double diameter_px = 2.5;           // 1/e^2 diameter of a particle image
  double margin_px = 16;              // beyond every border
  double noise_rms = 0;               // additive Gaussian noise per pixel (peak intensities are 0.5 .. 1)
  std::uint64_t seed = 1;
};

// (u_px, v_px) of frame B relative to frame A at a point (x_px, y_px).
using DisplacementField = std::function<std::array<double, 2>(double x_px, double y_px)>;

struct ParticleImagePair {
  cv::Mat a, b;  // CV_32F, height x width
};

ParticleImagePair particle_image_pair(const ParticleImageOptions& options, const DisplacementField& displacement);

// Adds the pixel-integrated Gaussian of one particle at (x_px, y_px) to image (CV_32F).
void add_particle_image(cv::Mat& image, double x_px, double y_px, double peak_intensity, double diameter_px);

}  // namespace glasspiv
