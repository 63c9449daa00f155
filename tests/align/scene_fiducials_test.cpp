// Fiducials in the scene: a target spec on a rectangle is drawn by the setup
// render where its corners are placed. The render is detected like a photo
// and the detected corners must lie where the camera projects the world corners.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

#include <opencv2/core.hpp>

#include "align/prepared_scene.h"
#include "align/scene_fiducials.h"
#include "render/scene_yaml.h"
#include "render/setup_render.h"
#include "targets/target_detect.h"
#include "tests/temp_dir.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

void write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

const char* kCharuco =
    "glasspiv_target: 1\nkind: charuco\nsquares: [7, 5]\nsquare_size_mm: 20\nmarker_size_mm: 15\n"
    "dictionary: DICT_5X5_100\nfirst_id: 0\n";

// A camera 450 mm from a board tilted by 25 degrees about the vertical axis.
std::string scene_text(const std::string& size_mm) {
  return "glasspiv_scene: 1\n"
         "solids:\n"
         "  - type: rectangle\n"
         "    centre_mm: [10, -5, 0]\n"
         "    size_mm: " + size_mm + "\n"
         "    normal: [0.4226182617, 0, -0.906307787]\n"
         "    up: [0, 1, 0]\n"
         "    texture: board.yaml\n"
         "sheet: {origin_mm: [0, 0, 10], s_axis: [1, 0, 0], t_axis: [0, 1, 0], extent_mm: [50, 50], thickness_mm: 1}\n"
         "background: {radiance: 0.3}\n"
         "cameras:\n"
         "  - name: cam\n"
         "    model: {image_size_px: [800, 600], lens_model: pinhole, focal_length_px: [1500, 1500],\n"
         "            principal_point_px: [401.3, 297.8]}\n"
         "    pose: {position_mm: [40, 30, -450], look_at_mm: [0, 0, 0], up: [0, 1, 0]}\n";
}

TEST(SceneFiducials, RenderedCornersLieWhereTheCameraProjectsThem) {
  TempDir dir("align_fiducials");
  write(dir.file("board.yaml"), kCharuco);
  write(dir.file("scene.yaml"), scene_text("[170, 130]"));
  const PreparedScene ps = prepare_scene(dir.file("scene.yaml"), "cam");
  const std::vector<SceneFiducial> fiducials = scene_fiducials(ps.scene);
  ASSERT_EQ(fiducials.size(), 1u);
  const SceneFiducial& f = fiducials[0];
  EXPECT_EQ(f.field, "solids[0]");
  EXPECT_EQ(f.corners_board.size(), 24u);

  SetupLook look;
  look.background_radiance = 0.3;
  look.textures = ps.textures_by_solid();
  const CameraModel& model = ps.camera().model;
  const std::vector<float> radiance =
      render_setup(ps.trace, look, model, *ps.camera().camera_from_world, TraceOptions{}, 4, 0);
  cv::Mat gray(model.height_px(), model.width_px(), CV_8UC1);
  for (int r = 0; r < gray.rows; ++r)
    for (int c = 0; c < gray.cols; ++c)
      gray.at<unsigned char>(r, c) =
          cv::saturate_cast<unsigned char>(255.0 * radiance[static_cast<std::size_t>(r) * gray.cols + c]);
  const ViewObservations seen = detect_target(gray, f.spec, "render");
  ASSERT_EQ(seen.corners.size(), 24u);
  // A placement error shows as a common offset of all corners: half a texel
  // (0.025 mm) would be 0.08 px here; the mean must stay below half that. The
  // scatter is the ChArUco detector's on a board tilted by 25 degrees (0.07 px
  // RMS also at 8 x 8 samples per pixel, so it is not the render's sampling).
  double sum2 = 0, worst = 0;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const CornerObservation& c : seen.corners) {
    const Eigen::Vector3d world = f.corner_world_mm(f.corners_board[static_cast<std::size_t>(c.id)]);
    const auto projected = model.project(ps.camera().camera_from_world->apply(world));
    ASSERT_TRUE(projected);
    const double d = (*projected - c.pixel_px).norm();
    mean += (c.pixel_px - *projected) / seen.corners.size();
    sum2 += d * d;
    worst = std::max(worst, d);
  }
  const double rms = std::sqrt(sum2 / seen.corners.size());
  EXPECT_LT(mean.norm(), 0.04) << mean.transpose();
  EXPECT_LT(rms, 0.1) << "worst " << worst;
  EXPECT_LT(worst, 0.25);
}

TEST(SceneFiducials, BoardFrameIsRightHandedOnTheRectangle) {
  TempDir dir("align_fiducials");
  write(dir.file("board.yaml"), kCharuco);
  write(dir.file("scene.yaml"), scene_text("[170, 130]"));
  const Scene scene = read_scene(dir.file("scene.yaml"));
  const SceneFiducial f = scene_fiducials(scene).at(0);
  const Eigen::Matrix3d& r = f.world_from_board.rotation;
  EXPECT_NEAR((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 0, 1e-12);
  EXPECT_NEAR(r.determinant(), 1, 1e-12);
  // Board z = -normal; the pattern's centre is the rectangle's centre to within half a texel.
  EXPECT_NEAR((r.col(2) + scene.rectangles[0].normal).norm(), 0, 1e-9);
  const Eigen::Vector3d centre = f.world_from_board.apply(Eigen::Vector3d(70, 50, 0));
  EXPECT_LT((centre - scene.rectangles[0].centre_mm).norm(), 0.5 / kTargetTexturePxPerMm);
}

// Alignment needs no sheet: a setup without one is prepared for it (and
// refused where a sheet is needed), and renders the same picture.
TEST(SceneFiducials, ASetupWithoutASheetIsPreparedForAlignment) {
  TempDir dir("align_fiducials");
  write(dir.file("board.yaml"), kCharuco);
  std::string text = scene_text("[170, 130]");
  const std::size_t at = text.find("sheet:");
  text.erase(at, text.find('\n', at) - at + 1);
  write(dir.file("scene.yaml"), text);
  EXPECT_THROW(prepare_scene(dir.file("scene.yaml"), "cam"), InputError);
  const PreparedScene ps = prepare_scene(dir.file("scene.yaml"), "cam", 4, SceneUse::setup_only);
  EXPECT_FALSE(ps.scene.sheet.has_value());
  write(dir.file("with_sheet.yaml"), scene_text("[170, 130]"));
  const PreparedScene with_sheet = prepare_scene(dir.file("with_sheet.yaml"), "cam", 4);
  SetupLook look;
  look.background_radiance = 0.3;
  look.textures = ps.textures_by_solid();
  const RigidTransform pose = *ps.camera().camera_from_world;
  const std::vector<float> a = render_setup(ps.trace, look, ps.camera().model, pose, TraceOptions{}, 1, 0);
  look.textures = with_sheet.textures_by_solid();
  const std::vector<float> b = render_setup(with_sheet.trace, look, with_sheet.camera().model, pose, TraceOptions{}, 1, 0);
  EXPECT_EQ(a, b);
}

// A speckle plate on a rectangle is drawn like any target texture, but it has
// no corners: it is no fiducial.
TEST(SceneFiducials, ASpecklePlateIsDrawnButIsNoFiducial) {
  TempDir dir("align_fiducials");
  const auto plate = [](int seed) {
    return "glasspiv_target: 1\nkind: speckle\nplate_size_mm: [140, 100]\ndot_diameter_mm: 1.5\nfill: 0.4\nseed: " +
           std::to_string(seed) + "\n";
  };
  std::vector<float> pictures[2];
  for (int seed : {1, 2}) {
    write(dir.file("board.yaml"), plate(seed));
    write(dir.file("scene.yaml"), scene_text("[170, 130]"));
    const PreparedScene ps = prepare_scene(dir.file("scene.yaml"), "cam", 1, SceneUse::setup_only);
    EXPECT_TRUE(scene_fiducials(ps.scene).empty());
    SetupLook look;
    look.background_radiance = 0.3;
    look.textures = ps.textures_by_solid();
    pictures[seed - 1] =
        render_setup(ps.trace, look, ps.camera().model, *ps.camera().camera_from_world, TraceOptions{}, 1, 0);
  }
  // Dots and paper: the picture's values spread; another seed, another picture.
  const auto [lo, hi] = std::minmax_element(pictures[0].begin(), pictures[0].end());
  EXPECT_LT(*lo, 0.15f);
  EXPECT_GT(*hi, 0.6f);
  EXPECT_NE(pictures[0], pictures[1]);
}

TEST(SceneFiducials, APatternLargerThanItsRectangleIsRefused) {
  TempDir dir("align_fiducials");
  write(dir.file("board.yaml"), kCharuco);
  write(dir.file("scene.yaml"), scene_text("[120, 130]"));
  const Scene scene = read_scene(dir.file("scene.yaml"));
  try {
    scene_fiducials(scene);
    FAIL() << "accepted a board that does not fit";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "solids[0].size_mm");
    EXPECT_NE(std::string(e.what()).find("does not fit"), std::string::npos) << e.what();
  }
}

TEST(SceneFiducials, TwoBoardsWithTheSameMarkersAreRefused) {
  TempDir dir("align_fiducials");
  write(dir.file("board.yaml"), kCharuco);
  std::string text = scene_text("[170, 130]");
  const std::string second =
      "  - type: rectangle\n    centre_mm: [0, 0, 300]\n    size_mm: [170, 130]\n    normal: [0, 0, -1]\n    up: [0, 1, 0]\n"
      "    texture: board.yaml\n";
  text.insert(text.find("sheet:"), second);
  write(dir.file("scene.yaml"), text);
  const Scene scene = read_scene(dir.file("scene.yaml"));
  try {
    scene_fiducials(scene);
    FAIL() << "accepted two boards with the same marker ids";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "solids[1]");
    EXPECT_NE(std::string(e.what()).find("solids[0]"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace glasspiv
