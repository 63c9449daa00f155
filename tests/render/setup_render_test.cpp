// Setup render: a textured opaque rectangle shows albedo x texture, the
// background shows its radiance, lossless glass in front of a uniform
// background conserves it, and any thread count gives the same image.
#include <gtest/gtest.h>

#include "render/setup_render.h"
#include "render/trace_scene_builder.h"

namespace glasspiv {
namespace {

CameraModel camera() { return CameraModel(60, 40, 100, 100, 29.5, 19.5); }

TEST(SetupRender, TexturedRectangleAndBackground) {
  TraceScene scene;
  Rectangle r;
  r.centre_mm = Eigen::Vector3d(0, 0, 100);
  r.half_width_mm = 20;  // camera sees +-30 mm at 100 mm: the rectangle covers the middle
  r.half_height_mm = 10;
  scene.solids.push_back({r, TraceMaterial::opaque(0.5)});
  const std::vector<float> texels = {0.2f, 0.8f};  // 1 row, 2 columns: left 0.2, right 0.8
  const SheetTexture texture(texels.data(), 1, 2, 20.0);
  SetupLook look;
  look.background_radiance = 1;
  look.textures = {&texture};
  const std::vector<float> image = render_setup(scene, look, camera(), RigidTransform{}, TraceOptions{}, 1, 1);
  auto at = [&](int col, int row) { return image[static_cast<std::size_t>(row) * 60 + col]; };
  // Column c looks at x = (c - 29.5) mm at z = 100: texel centres at x = -10 (0.2) and +10 (0.8), bilinear between.
  EXPECT_FLOAT_EQ(at(29 - 10, 20), static_cast<float>(0.5 * texture.at(29 - 10 - 29.5, -(20 - 19.5))));
  EXPECT_NEAR(at(39, 19), 0.5 * texture.at(39 - 29.5, 0.5), 1e-6);
  EXPECT_NEAR(at(20, 19), 0.5 * 0.2, 0.5 * 0.6 * 0.5 / 20 + 1e-6);
  EXPECT_FLOAT_EQ(at(2, 2), 1.0f);    // beyond the rectangle: the background
  EXPECT_FLOAT_EQ(at(57, 37), 1.0f);
}

TEST(SetupRender, LosslessGlassConservesAUniformBackground) {
  TraceScene scene;
  scene.solids.push_back({Sphere{Eigen::Vector3d(0, 0, 80), 15}, TraceMaterial::glass(1.5)});
  SetupLook look;
  look.background_radiance = 1;
  TraceOptions options;
  options.min_weight = 1e-9;
  options.max_depth = 5000;  // grazing rays bounce inside the sphere with R -> 1 (whispering gallery)
  SetupRenderStats stats;
  const std::vector<float> a = render_setup(scene, look, camera(), RigidTransform{}, options, 2, 1, {}, &stats);
  for (float v : a) EXPECT_NEAR(v, 1.0, 1e-6);  // all weight ends in the background, but what the cut-off drops
  EXPECT_EQ(stats.camera_rays, 60 * 40 * 4);
  EXPECT_GT(stats.closed_form_rays, 0);
  const std::vector<float> b = render_setup(scene, look, camera(), RigidTransform{}, options, 2, 2);
  EXPECT_EQ(a, b);
}

}  // namespace
}  // namespace glasspiv
