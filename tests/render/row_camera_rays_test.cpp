#include "render/row_camera_rays.h"

#include <algorithm>
#include <cstring>
#include <optional>
#include <stdexcept>

#include <gtest/gtest.h>

#include "render/trace_scene_builder.h"

namespace glasspiv {
namespace {

bool same_bits(const double* a, const double* b, int n) { return std::memcmp(a, b, sizeof(double) * n) == 0; }

// The row's rays, batched, interleaved and each batch started from the one
// before, are pixel_camera_ray's, sample by sample, to the unprojection's
// tolerance: the same origin to the bit, directions whose reprojections lie
// within 1e-10 px of the sample (what both converge to), differentials equal
// to 1e-6 relative (the lens Jacobian at points 1e-10 px apart, inverted; near
// the folding lens's fold it is nearly singular). For 1 to 3 samples per axis,
// a width that is not a multiple of the batch, and a folding lens whose outer
// pixels have no ray.
TEST(RowCameraRays, EqualPixelCameraRayToTheUnprojectionTolerance) {
  const RigidTransform pose = RigidTransform::from_rvec_tvec({0.1, -0.4, 0.02}, {3, -2, 600});
  const CameraModel lenses[] = {
      CameraModel(37, 9, 40, 40, 18.3, 4.1, {-0.12, 0.09, 2e-4, -1e-4}),
      CameraModel(29, 7, 30, 31, 14.1, 3.2, {-0.2, 0.05, 1e-3, -1e-3, 0.01, 0.1, -0.02, 0.005, 1e-3, 0, 0, 2e-4}),
      CameraModel(61, 5, 12, 12, 30.0, 2.0, {-0.5, 0, 0, 0, 0}),  // folds inside the row
      CameraModel(13, 3, 20, 20, 6.0, 1.0)};
  int missing = 0;
  double worst_px = 0, worst_differential = 0;
  for (const CameraModel& camera : lenses) {
    for (int k = 1; k <= 3; ++k) {
      for (int row = 0; row < camera.height_px(); ++row) {
        RowCameraRays rays(camera, pose, row, k);
        for (int col = 0; col < camera.width_px(); ++col)
          for (int sy = 0; sy < k; ++sy)
            for (int sx = 0; sx < k; ++sx) {
              const Eigen::Vector2d pixel(col + (sx + 0.5) / k - 0.5, row + (sy + 0.5) / k - 0.5);
              const std::optional<CameraRay> one = pixel_camera_ray(camera, pose, pixel);
              const std::optional<CameraRay>& batched = rays.next();
              ASSERT_EQ(batched.has_value(), one.has_value()) << col << " " << row;
              if (!one) {
                ++missing;
                continue;
              }
              EXPECT_TRUE(same_bits(batched->origin_mm.data(), one->origin_mm.data(), 3));
              const std::optional<Eigen::Vector2d> back = camera.project(pose.rotation * batched->direction);
              ASSERT_TRUE(back.has_value());
              worst_px = std::max(worst_px, (*back - pixel).norm());
              const double scale = one->ddirection_dpixel.norm();
              worst_differential =
                  std::max(worst_differential, (batched->ddirection_dpixel - one->ddirection_dpixel).norm() / scale);
            }
        EXPECT_THROW(rays.next(), std::logic_error);  // the row has no more samples
      }
    }
  }
  EXPECT_LT(worst_px, 1.1e-10);
  EXPECT_LT(worst_differential, 1e-6);
  EXPECT_GT(missing, 0);  // the folding lens's outer pixels were compared too
}

}  // namespace
}  // namespace glasspiv
