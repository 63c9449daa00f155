#include "render/row_camera_rays.h"

#include <cstring>
#include <optional>
#include <stdexcept>

#include <gtest/gtest.h>

#include "render/trace_scene_builder.h"

namespace glasspiv {
namespace {

bool same_bits(const double* a, const double* b, int n) { return std::memcmp(a, b, sizeof(double) * n) == 0; }

// The row's rays, batched and interleaved, are pixel_camera_ray's, sample by
// sample and to the bit: for 1 to 3 samples per axis, a width that is not a
// multiple of the batch, and a folding lens whose outer pixels have no ray.
TEST(RowCameraRays, EqualPixelCameraRayToTheBit) {
  const RigidTransform pose = RigidTransform::from_rvec_tvec({0.1, -0.4, 0.02}, {3, -2, 600});
  const CameraModel lenses[] = {
      CameraModel(37, 9, 40, 40, 18.3, 4.1, {-0.12, 0.09, 2e-4, -1e-4}),
      CameraModel(29, 7, 30, 31, 14.1, 3.2, {-0.2, 0.05, 1e-3, -1e-3, 0.01, 0.1, -0.02, 0.005, 1e-3, 0, 0, 2e-4}),
      CameraModel(61, 5, 12, 12, 30.0, 2.0, {-0.5, 0, 0, 0, 0}),  // folds inside the row
      CameraModel(13, 3, 20, 20, 6.0, 1.0)};
  int missing = 0;
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
              EXPECT_TRUE(same_bits(batched->direction.data(), one->direction.data(), 3));
              EXPECT_TRUE(same_bits(batched->ddirection_dpixel.data(), one->ddirection_dpixel.data(), 6));
            }
        EXPECT_THROW(rays.next(), std::logic_error);  // the row has no more samples
      }
    }
  }
  EXPECT_GT(missing, 0);  // the folding lens's outer pixels were compared too
}

}  // namespace
}  // namespace glasspiv
