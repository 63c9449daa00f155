// Tests of the camera file readers and writers (calib/io/): exact round trips in
// every format at every lens model it holds, the four example files describing
// the same camera, mrcal's own C reader (and, when python3-mrcal is installed,
// mrcal's Python) on files we write and files mrcal writes, and one-line errors
// naming the file and the field for every kind of bad input.
#include "calib/io/camera_file.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "calib/io/davis_xml.h"
#include "calib/io/glasspiv_yaml.h"
#include "calib/io/mrcal_cameramodel.h"
#include "calib/io/opencv_yaml.h"
#include "util/atomic_file.h"
#include "tests/python_mrcal.h"
#include "util/input_error.h"

extern "C" {
#include <mrcal/mrcal.h>
}

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

const std::string kDataDir = std::string(GLASSPIV_SOURCE_DIR) + "/data/cameras/";
constexpr LensModel kAllModels[] = {LensModel::Pinhole, LensModel::OpenCV4,  LensModel::OpenCV5,
                                    LensModel::OpenCV8, LensModel::OpenCV12, LensModel::OpenCV14};
constexpr LensModel kMrcalModels[] = {LensModel::Pinhole, LensModel::OpenCV4, LensModel::OpenCV5, LensModel::OpenCV8,
                                      LensModel::OpenCV12};

double uniform(std::mt19937& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

// A camera with random full-precision values in the ranges of real lenses.
Camera random_camera(std::mt19937& rng, LensModel model, bool with_pose, bool with_pitch, const std::string& name) {
  const int width = std::uniform_int_distribution<int>(640, 6000)(rng);
  const int height = std::uniform_int_distribution<int>(480, 5000)(rng);
  const double fx = uniform(rng, 500, 20000);
  const double fy = fx * uniform(rng, 0.99, 1.01);
  std::vector<double> d(static_cast<int>(model), 0.0);
  const double ranges[] = {0.5, 0.3, 1e-3, 1e-3, 0.1, 0.05, 0.05, 0.05, 1e-3, 1e-3, 1e-3, 1e-3, 0.02, 0.02};
  for (std::size_t i = 0; i < d.size(); ++i) d[i] = uniform(rng, -ranges[i], ranges[i]);
  std::optional<RigidTransform> pose;
  if (with_pose)
    pose = RigidTransform::from_rvec_tvec({uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)},
                                          {uniform(rng, -500, 500), uniform(rng, -500, 500), uniform(rng, 300, 900)});
  std::optional<double> pitch;
  if (with_pitch) pitch = uniform(rng, 2, 10);
  return Camera{name,
                CameraModel(width, height, fx, fy, width / 2.0 + uniform(rng, -50, 50),
                            height / 2.0 + uniform(rng, -50, 50), d),
                pose, pitch};
}

double max_abs_difference(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) { return (a - b).cwiseAbs().maxCoeff(); }

// Every value of the model, compared bit for bit.
void expect_same_intrinsics(const CameraModel& a, const CameraModel& b) {
  EXPECT_EQ(a.width_px(), b.width_px());
  EXPECT_EQ(a.height_px(), b.height_px());
  EXPECT_EQ(a.lens_model(), b.lens_model());
  for (std::size_t i = 0; i < a.intrinsics().size(); ++i) EXPECT_EQ(a.intrinsics()[i], b.intrinsics()[i]) << "parameter " << i;
  EXPECT_TRUE(a == b);
}

void expect_same_pose(const std::optional<RigidTransform>& a, const std::optional<RigidTransform>& b,
                      double rotation_tolerance = 2e-15) {
  ASSERT_EQ(a.has_value(), b.has_value());
  if (!a) return;
  EXPECT_LE(max_abs_difference(a->rotation, b->rotation), rotation_tolerance);
  EXPECT_EQ(a->translation_mm.x(), b->translation_mm.x());
  EXPECT_EQ(a->translation_mm.y(), b->translation_mm.y());
  EXPECT_EQ(a->translation_mm.z(), b->translation_mm.z());
}

// Expects `f` to throw an InputError whose one-line message names the file and
// contains every one of `fragments` (the field, usually).
void expect_input_error(const std::function<void()>& f, const std::string& file,
                        const std::vector<std::string>& fragments) {
  try {
    f();
    ADD_FAILURE() << "no InputError thrown; expected one mentioning " << (fragments.empty() ? "" : fragments[0]);
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(e.file(), file) << message;
    EXPECT_NE(message.find(file), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
    for (const std::string& fragment : fragments)
      EXPECT_NE(message.find(fragment), std::string::npos) << "'" << fragment << "' missing from: " << message;
  }
}

// Pixels of world points through each camera's pose and model.
std::vector<Eigen::Vector2d> project_world(const Camera& camera, const std::vector<Eigen::Vector3d>& world) {
  std::vector<Eigen::Vector2d> pixels;
  for (const Eigen::Vector3d& p : world) {
    const Eigen::Vector3d in_camera = camera.camera_from_world ? camera.camera_from_world->apply(p) : p;
    const std::optional<Eigen::Vector2d> q = camera.model.project(in_camera);
    EXPECT_TRUE(q.has_value());
    pixels.push_back(q.value_or(Eigen::Vector2d::Constant(NAN)));
  }
  return pixels;
}

std::vector<Eigen::Vector3d> world_grid() {
  std::vector<Eigen::Vector3d> points;
  for (double z : {-20.0, 0.0, 20.0})
    for (double y = -60; y <= 60; y += 15)
      for (double x = -60; x <= 60; x += 15) points.emplace_back(x, y, z);
  return points;
}

class CameraFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("glasspiv-camera-file-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  // Writes `contents` to a file called `name` in the test's folder; returns its path.
  std::string put(const std::string& name, const std::string& contents) const {
    std::ofstream(file(name), std::ios::binary) << contents;
    return file(name);
  }
  fs::path dir_;
};

// ---------------------------------------------------------------- round trips

TEST(CameraFileRoundTrip, GlasspivYamlIsExactForEveryLensModel) {
  std::mt19937 rng(11);
  for (LensModel model : kAllModels) {
    for (int trial = 0; trial < 40; ++trial) {
      SCOPED_TRACE(lens_model_name(model) + " trial " + std::to_string(trial));
      const Camera camera = random_camera(rng, model, trial % 2 == 0, trial % 3 != 0, "cam" + std::to_string(trial));
      const std::string text = format_cameras({camera}, CameraFileFormat::Glasspiv, "cam.yaml");
      EXPECT_EQ(detect_format(text, "cam.yaml"), CameraFileFormat::Glasspiv);
      const std::vector<Camera> back = parse_cameras(text, CameraFileFormat::Glasspiv, "cam.yaml");
      ASSERT_EQ(back.size(), 1u);
      EXPECT_EQ(back[0].name, camera.name);
      expect_same_intrinsics(back[0].model, camera.model);
      EXPECT_EQ(back[0].pixel_pitch_um, camera.pixel_pitch_um);
      expect_same_pose(back[0].camera_from_world, camera.camera_from_world);
      if (!camera.camera_from_world) {  // the text itself is a fixed point
        EXPECT_EQ(format_cameras(back, CameraFileFormat::Glasspiv, "cam.yaml"), text);
      }
    }
  }
}

TEST(CameraFileRoundTrip, GlasspivYamlKeepsOddNames) {
  std::mt19937 rng(3);
  for (const std::string name : {"", "null", "true", "2", "cam 0: left", "quote\"back\\slash", "tab\there", "-x",
                                 "kamera_ü"}) {
    Camera camera = random_camera(rng, LensModel::OpenCV5, false, false, name);
    const std::string text = format_cameras({camera}, CameraFileFormat::Glasspiv, "odd.yaml");
    EXPECT_EQ(parse_cameras(text, CameraFileFormat::Glasspiv, "odd.yaml")[0].name, name) << text;
  }
}

// OpenCV's writer takes a text starting with a bracket or brace for a
// structure and leaves some texts unquoted: every name either reads back as
// itself (through glasspiv's reader and OpenCV's) or is refused by name.
TEST(CameraFileRoundTrip, OpenCVNamesReadBackOrAreRefused) {
  std::mt19937 rng(18);
  int refused = 0;
  for (const std::string name : {"}", "}a", "]", "{", "[x]", "null", "Null", "~", "true", "2", "cam 0: left",
                                 "quote\"back\\slash", "tab\there", "-x", "# not a comment", "kamera_\xc3\xbc"}) {
    SCOPED_TRACE(name);
    const Camera camera = random_camera(rng, LensModel::OpenCV5, false, false, name);
    try {
      const std::string text = format_cameras({camera}, CameraFileFormat::OpenCV, "odd.yaml");
      EXPECT_EQ(parse_cameras(text, CameraFileFormat::OpenCV, "odd.yaml")[0].name, name) << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("cannot store the camera name"), std::string::npos) << e.what();
      ++refused;
    }
  }
  EXPECT_GE(refused, 2);  // at least "[x]" and "null"
}

TEST(CameraFileRoundTrip, OpenCVYamlIsExactForEveryLensModel) {
  std::mt19937 rng(12);
  for (LensModel model : kAllModels) {
    for (int trial = 0; trial < 40; ++trial) {
      SCOPED_TRACE(lens_model_name(model) + " trial " + std::to_string(trial));
      const Camera camera = random_camera(rng, model, trial % 2 == 0, trial % 3 != 0, "cam" + std::to_string(trial));
      const std::string text = format_cameras({camera}, CameraFileFormat::OpenCV, "cam.yaml");
      EXPECT_EQ(detect_format(text, "cam.yaml"), CameraFileFormat::OpenCV);
      const std::vector<Camera> back = parse_cameras(text, CameraFileFormat::OpenCV, "cam.yaml");
      ASSERT_EQ(back.size(), 1u);
      EXPECT_EQ(back[0].name, camera.name);
      expect_same_intrinsics(back[0].model, camera.model);
      EXPECT_EQ(back[0].pixel_pitch_um, camera.pixel_pitch_um);
      expect_same_pose(back[0].camera_from_world, camera.camera_from_world);
    }
  }
}

TEST(CameraFileRoundTrip, MrcalIsExactForEveryLensModelItHas) {
  std::mt19937 rng(13);
  for (LensModel model : kMrcalModels) {
    for (int trial = 0; trial < 40; ++trial) {
      SCOPED_TRACE(lens_model_name(model) + " trial " + std::to_string(trial));
      const Camera camera = random_camera(rng, model, trial % 2 == 0, true, "whatever");
      const std::string text = format_cameras({camera}, CameraFileFormat::Mrcal, "setup/left.cameramodel");
      EXPECT_EQ(detect_format(text, "left.cameramodel"), CameraFileFormat::Mrcal);
      const std::vector<Camera> back = parse_cameras(text, CameraFileFormat::Mrcal, "setup/left.cameramodel");
      ASSERT_EQ(back.size(), 1u);
      EXPECT_EQ(back[0].name, "left");  // mrcal has no name: the file's stem
      expect_same_intrinsics(back[0].model, camera.model);
      EXPECT_FALSE(back[0].pixel_pitch_um.has_value());  // nor a pixel pitch
      expect_same_pose(back[0].camera_from_world, camera.camera_from_world);
    }
  }
}

TEST(CameraFileRoundTrip, DavisIsExactForTheModelsItHolds) {
  std::mt19937 rng(14);
  for (LensModel model : {LensModel::Pinhole, LensModel::OpenCV4, LensModel::OpenCV5, LensModel::OpenCV8}) {
    for (int trial = 0; trial < 150; ++trial) {
      SCOPED_TRACE(lens_model_name(model) + " trial " + std::to_string(trial));
      Camera camera = random_camera(rng, model, trial % 2 == 0, true, "camera1");
      std::vector<double> d = camera.model.distortion();
      for (std::size_t i = 4; i < d.size(); ++i) d[i] = 0;  // DaVis holds k1 k2 p1 p2 only
      const CameraModel& m = camera.model;
      camera.model = CameraModel(m.width_px(), m.height_px(), m.fx_px(), m.fy_px(), m.cx_px(), m.cy_px(), d);
      const std::string text = format_cameras({camera}, CameraFileFormat::Davis, "Calibration.xml");
      EXPECT_EQ(detect_format(text, "Calibration.xml"), CameraFileFormat::Davis);
      const std::vector<Camera> back = parse_cameras(text, CameraFileFormat::Davis, "Calibration.xml");
      ASSERT_EQ(back.size(), 1u);
      EXPECT_EQ(back[0].name, "camera1");
      // Read back as opencv4, with the same parameter block bit for bit.
      EXPECT_EQ(back[0].model.lens_model(), LensModel::OpenCV4);
      EXPECT_EQ(back[0].model.width_px(), m.width_px());
      EXPECT_EQ(back[0].model.height_px(), m.height_px());
      for (std::size_t i = 0; i < m.intrinsics().size(); ++i)
        EXPECT_EQ(back[0].model.intrinsics()[i], camera.model.intrinsics()[i]) << "parameter " << i;
      EXPECT_EQ(back[0].pixel_pitch_um, camera.pixel_pitch_um);
      expect_same_pose(back[0].camera_from_world, camera.camera_from_world);
    }
  }
}

TEST(CameraFileRoundTrip, DavisHoldsSeveralCamerasAndTheirNames) {
  std::mt19937 rng(15);
  std::vector<Camera> cameras = {random_camera(rng, LensModel::OpenCV4, true, true, "camera1"),
                                 random_camera(rng, LensModel::OpenCV4, true, true, "left"),
                                 random_camera(rng, LensModel::Pinhole, false, true, "camera3")};
  const std::string text = format_cameras(cameras, CameraFileFormat::Davis, "Calibration.xml");
  EXPECT_EQ(text.find("Name=\"camera"), std::string::npos) << "default names are not written";
  const std::vector<Camera> back = parse_cameras(text, CameraFileFormat::Davis, "Calibration.xml");
  ASSERT_EQ(back.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back[i].name, cameras[i].name);
    EXPECT_EQ(back[i].model.intrinsics(), cameras[i].model.intrinsics());
    expect_same_pose(back[i].camera_from_world, cameras[i].camera_from_world);
  }
}

// What OpenCV's calibration sample saves, written by cv::FileStorage itself
// (YAML and JSON): read exactly, though glasspiv reads it with yaml-cpp.
TEST(CameraFileRoundTrip, ReadsWhatFileStorageWritesAsYamlAndJson) {
  std::mt19937 rng(17);
  for (int format : {cv::FileStorage::FORMAT_YAML, cv::FileStorage::FORMAT_JSON}) {
    for (LensModel model : {LensModel::OpenCV5, LensModel::OpenCV8, LensModel::OpenCV14}) {
      SCOPED_TRACE((format == cv::FileStorage::FORMAT_JSON ? "JSON " : "YAML ") + lens_model_name(model));
      const Camera camera = random_camera(rng, model, true, false, "");
      const CameraModel& m = camera.model;
      const std::vector<double> d = m.distortion();
      cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | format);
      fs << "calibration_time" << "Thu Dec  3 2026";
      fs << "image_width" << m.width_px() << "image_height" << m.height_px();
      fs << "camera_matrix" << (cv::Mat_<double>(3, 3) << m.fx_px(), 0, m.cx_px(), 0, m.fy_px(), m.cy_px(), 0, 0, 1);
      fs << "distortion_coefficients" << cv::Mat(d, true).reshape(1, 1);
      fs << "avg_reprojection_error" << 0.25;
      const Eigen::Vector3d rvec = camera.camera_from_world->rvec();
      const Eigen::Vector3d& t = camera.camera_from_world->translation_mm;
      fs << "rvec" << (cv::Mat_<double>(3, 1) << rvec.x(), rvec.y(), rvec.z());
      fs << "tvec" << (cv::Mat_<double>(1, 3) << t.x(), t.y(), t.z());
      const std::string text = fs.releaseAndGetString();
      EXPECT_EQ(detect_format(text, "cam.yaml"), CameraFileFormat::OpenCV) << text;
      const std::vector<Camera> back = parse_cameras(text, CameraFileFormat::OpenCV, "cam.yaml");
      ASSERT_EQ(back.size(), 1u);
      expect_same_intrinsics(back[0].model, m);
      expect_same_pose(back[0].camera_from_world, camera.camera_from_world);
    }
  }
}

TEST(CameraFileRoundTrip, PixelPitchAndFocalLengthInMillimetresAgree) {
  std::mt19937 rng(16);
  for (int trial = 0; trial < 20; ++trial) {
    const Camera camera = random_camera(rng, LensModel::OpenCV5, false, true, "c");
    const std::string text = format_cameras({camera}, CameraFileFormat::Glasspiv, "c.yaml");
    EXPECT_NE(text.find("focal_length_mm:"), std::string::npos);
    // Reading accepts the mm values it wrote (they agree to 1e-12).
    EXPECT_NO_THROW(parse_cameras(text, CameraFileFormat::Glasspiv, "c.yaml"));
  }
}

// ---------------------------------------------------------------- example files

TEST(CameraFileExamples, TheFourExampleFilesAreTheSameCamera) {
  const Camera glasspiv = read_camera(kDataDir + "example.yaml");
  const Camera opencv = read_camera(kDataDir + "example_opencv.yaml");
  const Camera mrcal = read_camera(kDataDir + "example.cameramodel");
  const Camera davis = read_camera(kDataDir + "example_davis.xml");

  EXPECT_EQ(glasspiv.model.width_px(), 2560);
  EXPECT_EQ(glasspiv.model.height_px(), 2160);
  EXPECT_EQ(glasspiv.model.lens_model(), LensModel::OpenCV4);
  EXPECT_EQ(glasspiv.model.fx_px(), 50.0 / 0.0065);
  EXPECT_EQ(glasspiv.pixel_pitch_um, 6.5);
  ASSERT_TRUE(glasspiv.camera_from_world.has_value());
  // The camera looks at the world origin from 600 mm.
  EXPECT_NEAR((glasspiv.camera_from_world->inverse().translation_mm).norm(), 600.0, 1e-9);
  EXPECT_NEAR(glasspiv.camera_from_world->apply(Eigen::Vector3d::Zero()).head<2>().norm(), 0.0, 1e-9);

  for (const Camera* other : {&glasspiv, &opencv, &mrcal, &davis}) EXPECT_EQ(other->name, "example");
  for (const Camera* other : {&opencv, &mrcal, &davis}) {
    expect_same_intrinsics(other->model, glasspiv.model);
    expect_same_pose(other->camera_from_world, glasspiv.camera_from_world);
    const std::vector<Eigen::Vector2d> a = project_world(glasspiv, world_grid());
    const std::vector<Eigen::Vector2d> b = project_world(*other, world_grid());
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_TRUE(a[i].x() > 0 && a[i].x() < 2560 && a[i].y() > 0 && a[i].y() < 2160) << a[i].transpose();
      EXPECT_LE((a[i] - b[i]).norm(), 1e-9);
    }
  }
  EXPECT_EQ(davis.pixel_pitch_um, 6.5);
  EXPECT_EQ(opencv.pixel_pitch_um, 6.5);
}

TEST(CameraFileExamples, WideOpenCV8Loads) {
  const Camera wide = read_camera(kDataDir + "wide_opencv8.yaml");
  EXPECT_EQ(wide.model.lens_model(), LensModel::OpenCV8);
  EXPECT_EQ(wide.model.width_px(), 1280);
  EXPECT_EQ(wide.model.height_px(), 1024);
  EXPECT_EQ(wide.model.distortion()[0], -0.35);
  EXPECT_TRUE(wide.model.field_of_view().has_value());
}

TEST(CameraFileExamples, FormatsAreDetectedFromTheContents) {
  EXPECT_EQ(detect_format(read_file(kDataDir + "example.yaml"), "x"), CameraFileFormat::Glasspiv);
  EXPECT_EQ(detect_format(read_file(kDataDir + "wide_opencv8.yaml"), "x"), CameraFileFormat::Glasspiv);
  EXPECT_EQ(detect_format(read_file(kDataDir + "example_opencv.yaml"), "x"), CameraFileFormat::OpenCV);
  EXPECT_EQ(detect_format(read_file(kDataDir + "example.cameramodel"), "x"), CameraFileFormat::Mrcal);
  EXPECT_EQ(detect_format(read_file(kDataDir + "example_davis.xml"), "x"), CameraFileFormat::Davis);
  EXPECT_EQ(detect_format("<Calibration/>", "x"), CameraFileFormat::Davis);
  EXPECT_EQ(detect_format("# a comment\nimage_width: 3\ncamera_matrix: !!opencv-matrix\n", "x"),
            CameraFileFormat::OpenCV);
  EXPECT_EQ(detect_format("{\n  \"camera_matrix\": {}\n}", "x"), CameraFileFormat::OpenCV);  // FileStorage JSON
  EXPECT_EQ(detect_format("# mrcal\n\n  { 'lensmodel': 'LENSMODEL_PINHOLE' }", "x"), CameraFileFormat::Mrcal);
  expect_input_error([] { detect_format("hello: world\n", "notes.yaml"); }, "notes.yaml",
                     {"not a camera file glasspiv knows"});
  expect_input_error([] { detect_format("", "empty.yaml"); }, "empty.yaml", {"not a camera file"});
}

TEST(CameraFileExamples, FormatNamesAndExtensions) {
  for (CameraFileFormat f :
       {CameraFileFormat::Glasspiv, CameraFileFormat::OpenCV, CameraFileFormat::Mrcal, CameraFileFormat::Davis})
    EXPECT_EQ(format_from_name(format_name(f)), f);
  expect_input_error([] { format_from_name("matlab"); }, "", {"format", "matlab"});
  EXPECT_EQ(format_for_output_path("a/b.cameramodel"), CameraFileFormat::Mrcal);
  EXPECT_EQ(format_for_output_path("Calibration.XML"), CameraFileFormat::Davis);
  EXPECT_EQ(format_for_output_path("cam.yml"), CameraFileFormat::Glasspiv);
  EXPECT_EQ(format_for_output_path("cam.yaml"), CameraFileFormat::Glasspiv);
  expect_input_error([] { format_for_output_path("cam.txt"); }, "cam.txt", {".txt"});
}

// ---------------------------------------------------------------- files

TEST_F(CameraFileTest, WritesAtomicallyAndReadsBackEveryFormat) {
  std::mt19937 rng(21);
  const Camera camera = random_camera(rng, LensModel::OpenCV4, true, true, "camera1");
  const std::string names[] = {"c.yaml", "c.cameramodel", "c.xml"};
  for (const std::string& name : names) {
    write_cameras(file(name), {camera});
    const Camera back = read_camera(file(name));
    expect_same_intrinsics(back.model, camera.model);
  }
  write_cameras(file("opencv.yaml"), {camera}, CameraFileFormat::OpenCV);
  EXPECT_EQ(detect_format(read_file(file("opencv.yaml")), "x"), CameraFileFormat::OpenCV);
  expect_same_intrinsics(read_camera(file("opencv.yaml")).model, camera.model);
  // Only the four outputs: no temporary left behind.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 4);
}

TEST_F(CameraFileTest, ReadCameraPicksByName) {
  std::mt19937 rng(22);
  const std::vector<Camera> cameras = {random_camera(rng, LensModel::OpenCV4, true, true, "camera1"),
                                       random_camera(rng, LensModel::OpenCV4, true, true, "camera2")};
  const std::string path = file("Calibration.xml");
  write_cameras(path, cameras);
  EXPECT_EQ(read_cameras(path).size(), 2u);
  EXPECT_EQ(read_camera(path, "camera2").model.intrinsics(), cameras[1].model.intrinsics());
  EXPECT_EQ(read_camera(path, "2").name, "camera2");  // a DaVis identifier
  // The identifier finds a camera whatever its name.
  EXPECT_EQ(read_camera(kDataDir + "example_davis.xml", "1").name, "example");
  expect_input_error([&] { read_camera(path); }, path, {"holds 2 cameras", "'camera1' (CameraIdentifier 1)", "camera2"});
  expect_input_error([&] { read_camera(path, "camera7"); }, path, {"name", "camera7"});
}

TEST_F(CameraFileTest, MissingFileIsNamed) {
  const std::string path = file("nowhere/cam.yaml");
  expect_input_error([&] { read_cameras(path); }, path, {"does not exist"});
}

TEST_F(CameraFileTest, SingleCameraFormatsRefuseSeveral) {
  std::mt19937 rng(23);
  const std::vector<Camera> two = {random_camera(rng, LensModel::OpenCV4, false, true, "a"),
                                   random_camera(rng, LensModel::OpenCV4, false, true, "b")};
  for (CameraFileFormat f : {CameraFileFormat::Glasspiv, CameraFileFormat::OpenCV, CameraFileFormat::Mrcal})
    expect_input_error([&] { format_cameras(two, f, "out.file"); }, "out.file", {"one camera", "2"});
  expect_input_error([&] { write_cameras(file("none.yaml"), {}); }, file("none.yaml"), {"no camera"});
}

// ---------------------------------------------------------------- mrcal itself

TEST(CameraFileMrcal, MrcalsCReaderLoadsOurFilesExactly) {
  std::mt19937 rng(31);
  for (LensModel model : kMrcalModels) {
    for (int trial = 0; trial < 10; ++trial) {
      SCOPED_TRACE(lens_model_name(model) + " trial " + std::to_string(trial));
      const Camera camera = random_camera(rng, model, trial % 2 == 0, false, "m");
      const std::string text = format_cameras({camera}, CameraFileFormat::Mrcal, "m.cameramodel");
      const Camera ours = parse_cameras(text, CameraFileFormat::Mrcal, "m.cameramodel")[0];
      mrcal_cameramodel_t* theirs = mrcal_read_cameramodel_string(text.c_str(), static_cast<int>(text.size()));
      ASSERT_NE(theirs, nullptr) << text;
      char name[64];
      ASSERT_TRUE(mrcal_lensmodel_name(name, sizeof name, &theirs->lensmodel));
      const std::string expected_name = model == LensModel::Pinhole
                                            ? "LENSMODEL_PINHOLE"
                                            : "LENSMODEL_OPENCV" + std::to_string(static_cast<int>(model));
      EXPECT_EQ(std::string(name), expected_name);
      EXPECT_EQ(mrcal_lensmodel_num_params(&theirs->lensmodel), 4 + static_cast<int>(model));
      EXPECT_EQ(theirs->imagersize[0], static_cast<unsigned>(camera.model.width_px()));
      EXPECT_EQ(theirs->imagersize[1], static_cast<unsigned>(camera.model.height_px()));
      for (int i = 0; i < 4 + static_cast<int>(model); ++i) EXPECT_EQ(theirs->intrinsics[i], camera.model.intrinsics()[i]);
      // The extrinsics are the very numbers we wrote: rvec and tvec of camera_from_world.
      const Eigen::Vector3d rvec = ours.camera_from_world ? ours.camera_from_world->rvec() : Eigen::Vector3d::Zero();
      const Eigen::Vector3d rvec_written =
          camera.camera_from_world ? camera.camera_from_world->rvec() : Eigen::Vector3d::Zero();
      const Eigen::Vector3d tvec =
          camera.camera_from_world ? camera.camera_from_world->translation_mm : Eigen::Vector3d::Zero();
      for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(theirs->rt_cam_ref[i], rvec_written[i]);
        EXPECT_NEAR(theirs->rt_cam_ref[i], rvec[i], 1e-15);
        EXPECT_EQ(theirs->rt_cam_ref[3 + i], tvec[i]);
      }
      mrcal_free_cameramodel(&theirs);
    }
  }
}

TEST_F(CameraFileTest, WeReadWhatMrcalsCWriterWrites) {
  // mrcal's C writer keeps 6 decimals, so compare to that.
  const int n = 4 + 8;
  mrcal_cameramodel_t* model = static_cast<mrcal_cameramodel_t*>(
      std::calloc(1, sizeof(mrcal_cameramodel_t) + n * sizeof(double)));
  const double rt[6] = {0.1, -0.25, 0.05, 10.5, -3.25, 620.0};
  const double intrinsics[n] = {1450.25, 1449.75, 1015.5, 771.25, -0.21, 0.085, 3e-4, -2e-4, -0.012, 0.004, -0.002, 0.001};
  std::copy(rt, rt + 6, model->rt_cam_ref);
  std::copy(intrinsics, intrinsics + n, model->intrinsics);
  model->imagersize[0] = 2048;
  model->imagersize[1] = 1536;
  model->lensmodel.type = MRCAL_LENSMODEL_OPENCV8;
  const std::string path = file("from_mrcal.cameramodel");
  ASSERT_TRUE(mrcal_write_cameramodel_file(path.c_str(), model));
  std::free(model);
  const Camera camera = read_camera(path);
  EXPECT_EQ(camera.name, "from_mrcal");
  EXPECT_EQ(camera.model.lens_model(), LensModel::OpenCV8);
  EXPECT_EQ(camera.model.width_px(), 2048);
  for (int i = 0; i < n; ++i) EXPECT_NEAR(camera.model.intrinsics()[i], intrinsics[i], 1e-6);
  ASSERT_TRUE(camera.camera_from_world.has_value());
  const Eigen::Vector3d rvec = camera.camera_from_world->rvec();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(rvec[i], rt[i], 1e-6);
    EXPECT_NEAR(camera.camera_from_world->translation_mm[i], rt[3 + i], 1e-6);
  }
}

TEST(CameraFileMrcal, ReadsThePythonLiteralsMrcalFilesUse) {
  const std::string text = R"(# a model as mrcal-calibrate-cameras writes it, abridged
{
    'lensmodel':  "LENSMODEL_OPENCV4",   # double quotes work too
    # intrinsics are fx,fy,cx,cy,distortion0,distortion1,....
    'intrinsics': [ 1_000.5, 1000.25, 640, 480.0, -1.5e-1, +0.05, 1E-4, -0.0, ],
    'extrinsics': ( 0.0, 0.0, 0.0, 0.0, 0.0, 0.0 ),
    'imagersize': [ 1280, 960, ],
    'valid_intrinsics_region': [[0, 0], [1279, 0], [1279, 959], [0, 959], [0, 0]],
    'icam_intrinsics': 0,
    'optimization_inputs': b'H4sIAAAAAAAA/+y9B1hUx9c/fmcL' b'c3RhbmRhcmQ=\
more',
    'notes': {'nested': {'a': [1, 2, (3,)], 'b': None, 'c': True}, 3: 'int key'},
    'text': '''triple
quoted 'string' ''',
    'escapes': 'it\'s \\ fine',
}
)";
  const Camera camera = parse_cameras(text, CameraFileFormat::Mrcal, "abridged.cameramodel")[0];
  EXPECT_EQ(camera.model.lens_model(), LensModel::OpenCV4);
  EXPECT_EQ(camera.model.fx_px(), 1000.5);
  EXPECT_EQ(camera.model.cx_px(), 640.0);
  EXPECT_EQ(camera.model.distortion()[0], -0.15);
  EXPECT_EQ(camera.model.distortion()[1], 0.05);
  EXPECT_EQ(camera.model.distortion()[2], 1e-4);
  EXPECT_EQ(camera.model.width_px(), 1280);
  // All-zero extrinsics: the camera is mrcal's reference, no pose in a world.
  EXPECT_FALSE(camera.camera_from_world.has_value());
}

std::vector<Eigen::Vector2d> read_pixels(const std::string& path) {
  std::vector<Eigen::Vector2d> pixels;
  std::ifstream in(path);
  double u, v;
  while (in >> u >> v) pixels.emplace_back(u, v);
  return pixels;
}

TEST_F(CameraFileTest, MrcalPythonAgreesOnProjections) {
  const std::string python = testing::python_with_mrcal();
  if (python.empty()) GTEST_SKIP() << "python3 with mrcal (python3-mrcal) is not installed";

  Camera wide = read_camera(kDataDir + "wide_opencv8.yaml");
  wide.camera_from_world = RigidTransform::from_rvec_tvec({0.08, 0.35, -0.03}, {-5.0, 2.5, 450.0});
  const std::string ours = file("ours.cameramodel");
  write_cameras(ours, {wide});

  const std::vector<Eigen::Vector3d> points = world_grid();
  {
    std::ofstream out(file("points.txt"));
    out.precision(17);
    for (const Eigen::Vector3d& p : points) out << p.x() << " " << p.y() << " " << p.z() << "\n";
  }
  const std::string script = std::string(GLASSPIV_SOURCE_DIR) + "/tests/calib/mrcal_python_check.py";
  const std::string command = "'" + python + "' '" + script + "' '" + ours + "' '" + file("mrcal.cameramodel") +
                              "' '" + file("points.txt") + "' '" + file("ours.txt") + "' '" + file("mrcal.txt") + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;

  const std::vector<Eigen::Vector2d> mrcal_of_ours = read_pixels(file("ours.txt"));
  const std::vector<Eigen::Vector2d> ours_of_ours = project_world(wide, points);
  ASSERT_EQ(mrcal_of_ours.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) EXPECT_LE((mrcal_of_ours[i] - ours_of_ours[i]).norm(), 1e-9);

  const Camera theirs = read_camera(file("mrcal.cameramodel"));
  EXPECT_EQ(theirs.model.lens_model(), LensModel::OpenCV8);
  const std::vector<Eigen::Vector2d> mrcal_of_theirs = read_pixels(file("mrcal.txt"));
  const std::vector<Eigen::Vector2d> ours_of_theirs = project_world(theirs, points);
  ASSERT_EQ(mrcal_of_theirs.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) EXPECT_LE((mrcal_of_theirs[i] - ours_of_theirs[i]).norm(), 1e-9);
}

// ---------------------------------------------------------------- DaVis specifics

const char* const kDavisTwoMappers = R"(<?xml version="1.0" encoding="UTF-8"?>
<Calibration Version="3">
  <Header><Software>DaVis</Software></Header>
  <CoordinateMappers>
    <CoordinateMapper CameraIdentifier="1" Type="PinholeOpenCV">
      <CommonParameters>
        <OriginalImageSize Width="2560" Height="2160"/>
        <CorrectedImageSize Width="2560" Height="2160"/>
      </CommonParameters>
      <PinholeOpenCVParameters>
        <Camera>
          <InternalCameraParameters>
            <SensorPixelSizeMm Value="0.0065"/>
            <FocalLengthPixel x="50.1"/>
            <PrincipalPoint x="1280.5" y="1080.2"/>
            <RadialDistortion radialDistortionCoefficient1="-0.1" radialDistortionCoefficient2="0.05"/>
            <TangentialDistortion tangentialDistortionCoefficient1="1e-4" tangentialDistortionCoefficient2="-2e-4"/>
          </InternalCameraParameters>
          <ExternalCameraParameters>
            <TranslationMm Tx="10" Ty="-5" Tz="600"/>
            <RotationAngles Rx="0.1" Ry="-0.4" Rz="0.02"/>
          </ExternalCameraParameters>
        </Camera>
      </PinholeOpenCVParameters>
    </CoordinateMapper>
    <CoordinateMapper CameraIdentifier="2" Type="PinholeOpenCV">
      <CommonParameters><OriginalImageSize Width="2560" Height="2160"/></CommonParameters>
      <PinholeOpenCVParameters>
        <InternalCameraParameters>
          <SensorPixelSizeMm Value="0.0065"/>
          <FocalLengthPixel x="49.8" y="49.9"/>
          <PrincipalPoint x="1270" y="1090"/>
          <RadialDistortion radialDistortionCoefficient1="0" radialDistortionCoefficient2="0"/>
          <TangentialDistortion tangentialDistortionCoefficient1="0" tangentialDistortionCoefficient2="0"/>
        </InternalCameraParameters>
      </PinholeOpenCVParameters>
    </CoordinateMapper>
  </CoordinateMappers>
</Calibration>
)";

TEST(CameraFileDavis, ReadsWrappedMappers) {
  const std::vector<Camera> cameras = parse_cameras(kDavisTwoMappers, CameraFileFormat::Davis, "Calibration.xml");
  ASSERT_EQ(cameras.size(), 2u);
  EXPECT_EQ(cameras[0].name, "camera1");
  EXPECT_EQ(cameras[1].name, "camera2");
  EXPECT_NEAR(cameras[0].model.fx_px(), 50.1 / 0.0065, 1e-9);
  EXPECT_EQ(cameras[0].model.fy_px(), cameras[0].model.fx_px());  // no y: fy = fx
  EXPECT_NEAR(cameras[1].model.fy_px(), 49.9 / 0.0065, 1e-9);
  EXPECT_EQ(cameras[0].model.cx_px(), 1280.5);
  EXPECT_EQ(cameras[0].model.distortion(), (std::vector<double>{-0.1, 0.05, 1e-4, -2e-4}));
  EXPECT_EQ(cameras[0].pixel_pitch_um, 6.5);
  ASSERT_TRUE(cameras[0].camera_from_world.has_value());
  EXPECT_LE(max_abs_difference(cameras[0].camera_from_world->rotation, rotation_from_euler_zyx(0.1, -0.4, 0.02)), 0);
  EXPECT_EQ(cameras[0].camera_from_world->translation_mm, Eigen::Vector3d(10, -5, 600));
  EXPECT_FALSE(cameras[1].camera_from_world.has_value());
}

TEST(CameraFileDavis, RefusesWhatItCannotHold) {
  std::mt19937 rng(41);
  Camera camera = random_camera(rng, LensModel::OpenCV5, true, true, "camera1");
  expect_input_error([&] { format_cameras({camera}, CameraFileFormat::Davis, "out.xml"); }, "out.xml",
                     {"distortion_coefficients", "DaVis's PinholeOpenCV holds k1, k2, p1, p2 only", "k3 = "});
  camera = random_camera(rng, LensModel::OpenCV14, true, true, "camera1");
  expect_input_error([&] { format_cameras({camera}, CameraFileFormat::Davis, "out.xml"); }, "out.xml", {"k3 = "});
  std::vector<double> d = {-0.1, 0.05, 1e-4, 1e-4, 0, 0.01, 0, 0};
  camera.model = CameraModel(2000, 1000, 3000, 3000, 1000, 500, d);
  expect_input_error([&] { format_cameras({camera}, CameraFileFormat::Davis, "out.xml"); }, "out.xml", {"k4 = 0.01"});
  camera = random_camera(rng, LensModel::OpenCV4, true, false, "camera1");
  expect_input_error([&] { format_cameras({camera}, CameraFileFormat::Davis, "out.xml"); }, "out.xml",
                     {"pixel_pitch_um", "pixel pitch"});
}

// ---------------------------------------------------------------- rejections

struct BadInput {
  const char* description;
  CameraFileFormat format;
  std::string contents;
  std::vector<std::string> fragments;  // the field and what is wrong
};

const char* const kGoodGlasspiv = R"(glasspiv_camera: 1
name: cam0
image_size_px: [2560, 2160]
lens_model: opencv4
focal_length_px: [7692.3, 7692.3]
principal_point_px: [1290.5, 1070.25]
distortion_coefficients: [-0.12, 0.09, 2e-4, -1e-4]
pixel_pitch_um: 6.5
camera_from_world: {rvec: [0.1, -0.4, 0.02], tvec_mm: [0, 0, 600]}
)";

const char* const kGoodOpenCV = R"(%YAML:1.0
---
image_width: 640
image_height: 480
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 600., 0., 320., 0., 600., 240., 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [ -0.1, 0.01, 0., 0., 0. ]
avg_reprojection_error: 0.2
)";

const char* const kGoodMrcal = R"({
    'lensmodel':  'LENSMODEL_OPENCV4',
    'intrinsics': [ 600.0, 600.0, 320.0, 240.0, -0.1, 0.01, 0.0, 0.0,],
    'extrinsics': [ 0.1, 0.2, 0.3, 1.0, 2.0, 500.0,],
    'imagersize': [ 640, 480,],
}
)";

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

std::vector<BadInput> bad_inputs() {
  using F = CameraFileFormat;
  const std::string g = kGoodGlasspiv, o = kGoodOpenCV, m = kGoodMrcal, d = kDavisTwoMappers;
  return {
      // glasspiv YAML
      {"malformed YAML", F::Glasspiv, replace(g, "name: cam0", "name: [cam0"), {"line ", "YAML"}},
      {"unknown field", F::Glasspiv, replace(g, "name:", "nmae:"), {"field 'nmae'", "unknown field"}},
      {"unknown pose field", F::Glasspiv, replace(g, "tvec_mm:", "tvec:"), {"camera_from_world.tvec", "unknown"}},
      {"duplicate field", F::Glasspiv, g + "name: again\n", {"field 'name'", "twice"}},
      {"missing version", F::Glasspiv, replace(g, "glasspiv_camera: 1\n", ""), {"glasspiv_camera", "missing"}},
      {"future version", F::Glasspiv, replace(g, "glasspiv_camera: 1", "glasspiv_camera: 2"),
       {"glasspiv_camera", "version 2"}},
      {"missing focal length", F::Glasspiv, replace(g, "focal_length_px: [7692.3, 7692.3]\n", ""),
       {"focal_length_px", "missing"}},
      {"focal length of 3 values", F::Glasspiv, replace(g, "[7692.3, 7692.3]", "[7692.3, 7692.3, 1]"),
       {"focal_length_px", "2 values"}},
      {"NaN focal length", F::Glasspiv, replace(g, "[7692.3, 7692.3]", "[.nan, 7692.3]"),
       {"focal_length_px[0]", "finite"}},
      {"infinite coefficient", F::Glasspiv, replace(g, "-0.12", "-.inf"), {"distortion_coefficients[0]", "finite"}},
      {"text for a number", F::Glasspiv, replace(g, "1290.5", "abc"), {"principal_point_px[0]", "number"}},
      {"negative focal length", F::Glasspiv, replace(g, "[7692.3, 7692.3]", "[-7692.3, 7692.3]"), {"fx", "positive"}},
      {"zero width", F::Glasspiv, replace(g, "[2560, 2160]", "[0, 2160]"), {"image_size_px[0]", "positive"}},
      {"fractional height", F::Glasspiv, replace(g, "[2560, 2160]", "[2560, 2160.5]"), {"image_size_px[1]", "whole"}},
      {"negative pixel pitch", F::Glasspiv, replace(g, "6.5", "-6.5"), {"pixel_pitch_um", "positive"}},
      {"lens model disagrees with coefficients", F::Glasspiv, replace(g, "opencv4", "opencv5"),
       {"lens_model", "opencv5", "5", "has 4"}},
      {"unknown lens model", F::Glasspiv, replace(g, "opencv4", "fisheye"), {"lens_model", "fisheye"}},
      {"focal length in mm disagrees", F::Glasspiv, g + "focal_length_mm: [50.1, 50.0]\n",
       {"focal_length_mm", "disagrees"}},
      {"focal length in mm without pitch", F::Glasspiv,
       replace(g, "pixel_pitch_um: 6.5\n", "focal_length_mm: [50.0, 50.0]\n"), {"focal_length_mm", "pixel_pitch_um"}},
      {"not a mapping", F::Glasspiv, "- 1\n- 2\n", {"mapping"}},
      {"image 1e8 x 1e8", F::Glasspiv, replace(g, "[2560, 2160]", "[1e8, 1e8]"),
       {"image_size_px[0]", "line 3", "65536 px a side"}},
      {"image too many pixels", F::Glasspiv, replace(g, "[2560, 2160]", "[65536, 65536]"),
       {"image_size_px", "line 3", "1073741824 px"}},
      {"width past the int range", F::Glasspiv, replace(g, "[2560, 2160]", "[2147483648, 2160]"),
       {"image_size_px[0]", "65536 px a side"}},
      {"infinite pixel pitch", F::Glasspiv, replace(g, "6.5", ".inf"), {"pixel_pitch_um", "finite"}},
      {"absurd pixel pitch", F::Glasspiv, replace(g, "6.5", "1e308"), {"pixel_pitch_um", "at most 1000 um"}},
      {"duplicate pose field", F::Glasspiv, replace(g, "tvec_mm: [0, 0, 600]", "tvec_mm: [0, 0, 600], rvec: [0, 0, 0]"),
       {"camera_from_world.rvec", "twice"}},
      // OpenCV FileStorage YAML
      {"malformed OpenCV YAML", F::OpenCV, replace(o, "   rows: 3\n", "rows: 3\n"), {"line "}},
      {"missing image_width", F::OpenCV, replace(o, "image_width: 640\n", ""), {"field 'image_width'", "missing"}},
      {"missing image_height", F::OpenCV, replace(o, "image_height: 480\n", ""), {"field 'image_height'", "missing"}},
      {"fractional image_width", F::OpenCV, replace(o, "640", "640.5"), {"image_width", "whole"}},
      {"missing camera_matrix", F::OpenCV,
       replace(o, "camera_matrix:", "intrinsic_matrix:"), {"field 'camera_matrix'", "missing"}},
      {"camera matrix 2x2", F::OpenCV,
       replace(replace(o, "   rows: 3\n   cols: 3", "   rows: 2\n   cols: 2"), "600., 0., 320., 0., 600., 240., 0., 0., 1.",
               "600., 0., 0., 600."),
       {"camera_matrix", "3x3", "2x2"}},
      {"camera matrix with wrong element count", F::OpenCV, replace(o, "0., 0., 1. ]", "0., 0. ]"),
       {"camera_matrix"}},
      {"skew", F::OpenCV, replace(o, "600., 0., 320.", "600., 0.5, 320."), {"camera_matrix", "skew", "K(0,1) = 0.5"}},
      {"last row", F::OpenCV, replace(o, "0., 0., 1. ]", "0., 0., 2. ]"), {"camera_matrix", "(0, 0, 1)"}},
      {"NaN in the camera matrix", F::OpenCV, replace(o, "320.", ".nan"), {"camera_matrix", "finite"}},
      {"3 distortion coefficients", F::OpenCV,
       replace(replace(o, "   cols: 5", "   cols: 3"), "-0.1, 0.01, 0., 0., 0.", "-0.1, 0.01, 0."),
       {"distortion_coefficients", "3 coefficients"}},
      {"distortion as a matrix", F::OpenCV,
       replace(replace(o, "   rows: 1\n   cols: 5", "   rows: 5\n   cols: 5"), "-0.1, 0.01, 0., 0., 0.",
               "0,0,0,0,0, 0,0,0,0,0, 0,0,0,0,0, 0,0,0,0,0, 0,0,0,0,0"),
       {"distortion_coefficients", "1xN or Nx1"}},
      {"missing distortion", F::OpenCV,
       replace(o, "distortion_coefficients:", "dist_coeffs:"), {"distortion_coefficients", "missing"}},
      {"negative pixel pitch", F::OpenCV, o + "pixel_pitch_um: -6.5\n", {"pixel_pitch_um", "positive"}},
      {"rvec without tvec", F::OpenCV, o + "rvec: [0.1, 0.2, 0.3]\n", {"tvec", "missing"}},
      {"rvec of 2", F::OpenCV, o + "rvec: [0.1, 0.2]\ntvec: [1, 2, 3]\n", {"rvec", "3 elements"}},
      {"image_width past the int range", F::OpenCV, replace(o, "640", "2147483647"),
       {"image_width", "2147483647", "65536 px a side"}},
      {"image_width past the side limit", F::OpenCV, replace(o, "640", "65537"), {"image_width", "65536 px a side"}},
      {"image too many pixels", F::OpenCV, replace(replace(o, "640", "65536"), "480", "32768"),
       {"image_width", "65536 x 32768", "1073741824 px"}},
      {"negative image_height", F::OpenCV, replace(o, "480", "-480"), {"image_height", "positive"}},
      {"dt u saturating the camera matrix", F::OpenCV, replace(o, "dt: d", "dt: u"),
       {"camera_matrix.data[0]", "600", "does not fit dt 'u'", "0 to 255"}},
      {"dt i with a fraction", F::OpenCV, replace(replace(o, "dt: d", "dt: i"), "320.", "320.5"),
       {"camera_matrix.data[2]", "320.5", "dt 'i'", "whole numbers"}},
      {"three channels", F::OpenCV, replace(o, "dt: d", "dt: \"3d\""), {"camera_matrix", "one channel", "3d"}},
      {"unknown element type", F::OpenCV, replace(o, "dt: d", "dt: q"), {"camera_matrix.dt", "'q'"}},
      {"missing dt", F::OpenCV, replace(o, "   dt: d\n", ""), {"camera_matrix.dt", "missing"}},
      {"float overflow", F::OpenCV, replace(replace(o, "dt: d", "dt: f"), "320.", "1e39"),
       {"camera_matrix.data[2]", "dt 'f'"}},
      {"data count disagrees with rows x cols", F::OpenCV, replace(o, "   cols: 5", "   cols: 4"),
       {"distortion_coefficients", "4 elements", "data has 5"}},
      {"duplicate top-level key", F::OpenCV, o + "image_width: 1280\n", {"field 'image_width'", "twice"}},
      {"duplicate matrix key", F::OpenCV, replace(o, "   rows: 3\n", "   rows: 3\n   rows: 3\n"),
       {"camera_matrix.rows", "twice"}},
      {"infinite pixel pitch", F::OpenCV, o + "pixel_pitch_um: .inf\n", {"pixel_pitch_um", "finite"}},
      {"absurd pixel pitch", F::OpenCV, o + "pixel_pitch_um: 1e300\n", {"pixel_pitch_um", "at most 1000 um"}},
      {"infinite focal length", F::OpenCV, replace(o, "[ 600.,", "[ .inf,"), {"camera_matrix", "finite"}},
      {"deep flow nesting", F::OpenCV, o + "x: " + std::string(50000, '[') + std::string(50000, ']') + "\n",
       {"nested more than 64 levels", "line 16"}},
      {"deep flow nesting in a comment cannot hide", F::OpenCV,
       o + "x: [ # ]]]]\n" + std::string(70, '[') + std::string(71, ']') + "\n", {"nested more than 64 levels"}},
      {"deep dash nesting", F::OpenCV, [&] {
         std::string t = o + "x:\n";
         for (int i = 0; i < 200; ++i) t += "- ";
         return t + "1\n";
       }(), {"nested more than 64 levels"}},
      {"deep block nesting", F::OpenCV, [&] {
         std::string t = o;
         for (int i = 0; i < 200; ++i) t += std::string(static_cast<std::size_t>(i), ' ') + "k:\n";
         return t + std::string(200, ' ') + "k: 1\n";
       }(), {"nested more than 64 levels"}},
      {"a second document after an end marker", F::OpenCV, o + "...\nimage_width: 3\n", {"second YAML document"}},
      {"two documents on their marker lines", F::OpenCV, "--- {image_width: 640}\n--- {image_height: 480}\n",
       {"line 2", "second YAML document"}},
      {"billion laughs", F::OpenCV, [&] {
         std::string t = o + "l0: &l0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n";
         for (int i = 1; i < 12; ++i) {
           t += "l" + std::to_string(i) + ": &l" + std::to_string(i) + " [";
           for (int j = 0; j < 10; ++j) t += "*l" + std::to_string(i - 1) + ", ";
           t += "1]\n";
         }
         return t;
       }(), {"aliases"}},
      {"deep nesting through aliases", F::OpenCV, [&] {
         std::string t = o + "a0: &a0 [1]\n";
         for (int i = 1; i < 100; ++i)
           t += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [*a" + std::to_string(i - 1) + "]\n";
         return t;
       }(), {"aliases"}},  // the node budget or the depth bound, whichever trips first
      {"deep JSON nesting", F::OpenCV,
       "{\"camera_matrix\": 1, \"x\": " + std::string(50000, '[') + std::string(50000, ']') + "}",
       {"nested more than 64 levels"}},
      // mrcal .cameramodel
      {"malformed mrcal", F::Mrcal, replace(m, "'imagersize': [ 640, 480,],", "'imagersize': [ 640, 480,"),
       {"line 6", "unexpected character '}'"}},
      {"trailing text", F::Mrcal, m + "oops\n", {"line 7", "after the end"}},
      {"spline model", F::Mrcal,
       replace(m, "LENSMODEL_OPENCV4", "LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=30_Ny=18_fov_x_deg=100"),
       {"lensmodel", "LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=30_Ny=18_fov_x_deg=100",
        "cannot be represented by glasspiv's pinhole+OpenCV model"}},
      {"CAHVOR", F::Mrcal, replace(m, "LENSMODEL_OPENCV4", "LENSMODEL_CAHVOR"),
       {"lensmodel", "LENSMODEL_CAHVOR cannot be represented by glasspiv's pinhole+OpenCV model"}},
      {"wrong intrinsics count", F::Mrcal, replace(m, "LENSMODEL_OPENCV4", "LENSMODEL_OPENCV5"),
       {"field 'intrinsics'", "has 8 values", "9 numbers"}},
      {"NaN intrinsics", F::Mrcal, replace(m, "320.0", "nan"), {"intrinsics[2]", "finite"}},
      {"text intrinsics", F::Mrcal, replace(m, "320.0", "'320'"), {"intrinsics[2]", "number"}},
      {"missing imagersize", F::Mrcal, replace(m, "'imagersize'", "'imager_size'"), {"imagersize", "missing"}},
      {"negative imagersize", F::Mrcal, replace(m, "640, 480", "-640, 480"), {"imagersize[0]", "positive"}},
      {"short extrinsics", F::Mrcal, replace(m, "1.0, 2.0, 500.0,", "1.0, 2.0,"), {"extrinsics", "6 numbers"}},
      {"not a dict", F::Mrcal, "[1, 2, 3]", {"dict"}},
      {"deep nesting", F::Mrcal, std::string(100, '['), {"nested too deeply"}},
      {"unclosed string", F::Mrcal, replace(m, "'LENSMODEL_OPENCV4',", "'LENSMODEL_OPENCV4,"), {"line 2", "string"}},
      {"negative focal length", F::Mrcal, replace(m, "[ 600.0, 600.0,", "[ -600.0, 600.0,"), {"fx", "positive"}},
      {"imagersize past the int range", F::Mrcal, replace(m, "640, 480", "2147483647, 480"),
       {"imagersize[0]", "65536 px a side"}},
      {"imagersize too many pixels", F::Mrcal, replace(m, "640, 480", "40000, 40000"),
       {"imagersize", "40000 x 40000", "1073741824 px"}},
      {"duplicate key", F::Mrcal, replace(m, "'imagersize'", "'lensmodel': 'LENSMODEL_OPENCV4', 'imagersize'"),
       {"field 'lensmodel'", "line 5", "twice"}},
      {"duplicate key of a field glasspiv skips", F::Mrcal,
       replace(m, "'imagersize'", "'icam_intrinsics': 0, 'icam_intrinsics': 1, 'imagersize'"),
       {"icam_intrinsics", "twice"}},
      {"infinite intrinsics", F::Mrcal, replace(m, "600.0, 600.0", "600.0, -inf"), {"intrinsics[1]", "finite"}},
      // DaVis XML
      {"malformed XML", F::Davis, replace(d, "</Header>", "</Headr>"), {"line 3", "malformed XML"}},
      {"not DaVis", F::Davis, "<?xml version=\"1.0\"?><opencv_storage/>", {"<opencv_storage>"}},
      {"no mapper", F::Davis, "<Calibration/>", {"CoordinateMapper", "missing"}},
      {"polynomial mapper", F::Davis, replace(d, "CameraIdentifier=\"2\" Type=\"PinholeOpenCV\"",
                                              "CameraIdentifier=\"2\" Type=\"Polynomial3rdOrder\""),
       {"CoordinateMapper[CameraIdentifier=2]/Type", "Polynomial3rdOrder"}},
      {"negative pixel size", F::Davis, replace(d, "Value=\"0.0065\"", "Value=\"-0.0065\""),
       {"SensorPixelSizeMm.Value", "positive"}},
      {"NaN focal length", F::Davis, replace(d, "x=\"50.1\"", "x=\"nan\""), {"FocalLengthPixel.x", "finite"}},
      {"decimal comma", F::Davis, replace(d, "x=\"1280.5\"", "x=\"1280,5\""), {"PrincipalPoint.x", "decimal comma"}},
      {"missing principal point", F::Davis, replace(d, "<PrincipalPoint x=\"1280.5\" y=\"1080.2\"/>", ""),
       {"CoordinateMapper[CameraIdentifier=1]/PrincipalPoint", "missing"}},
      {"k3 in the file", F::Davis,
       replace(d, "radialDistortionCoefficient2=\"0.05\"",
               "radialDistortionCoefficient2=\"0.05\" radialDistortionCoefficient3=\"0.01\""),
       {"RadialDistortion.radialDistortionCoefficient3", "k1, k2, p1, p2 only"}},
      {"duplicate identifier", F::Davis, replace(d, "CameraIdentifier=\"2\"", "CameraIdentifier=\"1\""),
       {"CameraIdentifier", "twice"}},
      {"pixel size 1e308", F::Davis, replace(d, "Value=\"0.0065\"", "Value=\"1e308\""),
       {"SensorPixelSizeMm.Value", "1e308", "finite"}},
      {"pixel size of 2 mm", F::Davis, replace(d, "Value=\"0.0065\"", "Value=\"2\""),
       {"SensorPixelSizeMm.Value", "at most 1000 um"}},
      {"width past the int range", F::Davis, replace(d, "Width=\"2560\"", "Width=\"2147483647\""),
       {"OriginalImageSize.Width", "65536 px a side"}},
      {"image too many pixels", F::Davis,
       replace(replace(d, "Width=\"2560\"", "Width=\"65536\""), "Height=\"2160\"", "Height=\"65536\""),
       {"CoordinateMapper[CameraIdentifier=1]/OriginalImageSize", "1073741824 px"}},
      {"duplicate attribute", F::Davis, replace(d, "Value=\"0.0065\"", "Value=\"0.0065\" Value=\"0.1\""),
       {"SensorPixelSizeMm.Value", "attribute 'Value' appears twice", "line 13"}},
      {"duplicate attribute on any element", F::Davis,
       replace(d, "<Calibration Version=\"3\">", "<Calibration Version=\"3\" Version=\"4\">"),
       {"Calibration.Version", "twice"}},
      {"duplicate element", F::Davis,
       replace(d, "<PrincipalPoint x=\"1280.5\" y=\"1080.2\"/>",
               "<PrincipalPoint x=\"1280.5\" y=\"1080.2\"/><PrincipalPoint x=\"1.5\" y=\"1.2\"/>"),
       {"CoordinateMapper[CameraIdentifier=1]/PrincipalPoint", "appears twice"}},
      {"half a pose", F::Davis, replace(d, "<TranslationMm Tx=\"10\" Ty=\"-5\" Tz=\"600\"/>", ""),
       {"TranslationMm", "missing"}},
  };
}

TEST_F(CameraFileTest, BadInputGivesOneLineNamingFileAndField) {
  const char* extension[] = {".yaml", ".yaml", ".cameramodel", ".xml"};
  int index = 0;
  for (const BadInput& bad : bad_inputs()) {
    SCOPED_TRACE(bad.description);
    const std::string path =
        put("bad" + std::to_string(index++) + extension[static_cast<int>(bad.format)], bad.contents);
    // Through the parser, and through the file reader where the format is sniffed.
    expect_input_error([&] { parse_cameras(read_file(path), bad.format, path); }, path, bad.fragments);
    try {
      if (detect_format(bad.contents, path) == bad.format)
        expect_input_error([&] { read_cameras(path); }, path, bad.fragments);
    } catch (const InputError&) {
    }
  }
}

TEST(CameraFileRejections, TruncatedAndCorruptedFilesGiveInputErrorsOnly) {
  // Whatever the damage, a reader either reads the file or throws InputError
  // naming it; no other exception (yaml-cpp's, OpenCV's) gets through.
  std::mt19937 rng(53);
  for (const char* name : {"example.yaml", "example_opencv.yaml", "example.cameramodel", "example_davis.xml"}) {
    const std::string text = read_file(kDataDir + name);
    const CameraFileFormat format = detect_format(text, name);
    auto check = [&](const std::string& damaged, const std::string& what) {
      try {
        parse_cameras(damaged, format, name);
      } catch (const InputError& e) {
        EXPECT_EQ(e.file(), name) << what << ": " << e.what();
      } catch (const std::exception& e) {
        ADD_FAILURE() << name << " " << what << ": not an InputError: " << e.what();
      }
    };
    for (std::size_t length = 0; length < text.size(); length += 5) check(text.substr(0, length), "truncated");
    for (int trial = 0; trial < 150; ++trial) {
      std::string damaged = text;
      const std::size_t at = std::uniform_int_distribution<std::size_t>(0, text.size() - 1)(rng);
      damaged[at] = "{}[]<>:,'\"#-.e0 \n\t!&"[trial % 20];
      check(damaged, "corrupted at " + std::to_string(at));
    }
  }
}

TEST(CameraFileRejections, GoodInputsOfTheRejectionTestsParse) {
  EXPECT_NO_THROW(parse_cameras(kGoodGlasspiv, CameraFileFormat::Glasspiv, "g.yaml"));
  EXPECT_NO_THROW(parse_cameras(kGoodOpenCV, CameraFileFormat::OpenCV, "o.yaml"));
  EXPECT_NO_THROW(parse_cameras(kGoodMrcal, CameraFileFormat::Mrcal, "m.cameramodel"));
  EXPECT_NO_THROW(parse_cameras(kDavisTwoMappers, CameraFileFormat::Davis, "d.xml"));
  // OpenCV files without the %YAML header, as hand-written files often are.
  const std::string headerless = std::string(kGoodOpenCV).substr(std::string("%YAML:1.0\n---\n").size());
  const Camera camera = parse_cameras(headerless, CameraFileFormat::OpenCV, "o.yaml")[0];
  EXPECT_EQ(camera.model.lens_model(), LensModel::OpenCV5);
  EXPECT_EQ(camera.name, "o");
  // glasspiv: focal_length_mm alone defines the focal length.
  const std::string in_mm = replace(kGoodGlasspiv, "focal_length_px: [7692.3, 7692.3]", "focal_length_mm: [50, 50]");
  EXPECT_NEAR(parse_cameras(in_mm, CameraFileFormat::Glasspiv, "g.yaml")[0].model.fx_px(), 50 / 0.0065, 1e-9);
}

TEST(CameraFileRejections, InputsAtTheLimitsParse) {
  // The largest image: 65536 px a side, 2^30 px in all, in every format.
  const std::string g = replace(kGoodGlasspiv, "[2560, 2160]", "[65536, 16384]");
  EXPECT_EQ(parse_cameras(g, CameraFileFormat::Glasspiv, "g.yaml")[0].model.width_px(), 65536);
  const std::string o = replace(replace(kGoodOpenCV, "640", "16384"), "480", "65536");
  EXPECT_EQ(parse_cameras(o, CameraFileFormat::OpenCV, "o.yaml")[0].model.height_px(), 65536);
  const std::string m = replace(kGoodMrcal, "640, 480", "32768, 32768");
  EXPECT_EQ(parse_cameras(m, CameraFileFormat::Mrcal, "m.cameramodel")[0].model.width_px(), 32768);
  const std::string d = replace(kDavisTwoMappers, "Value=\"0.0065\"", "Value=\"1\"");
  EXPECT_EQ(*parse_cameras(d, CameraFileFormat::Davis, "d.xml")[0].pixel_pitch_um, 1000.0);
  // OpenCV nested 64 levels deep (the top-level mapping is one of them).
  std::string nested = std::string(kGoodOpenCV) + "x: " + std::string(63, '[') + std::string(63, ']') + "\n";
  EXPECT_NO_THROW(parse_cameras(nested, CameraFileFormat::OpenCV, "o.yaml"));
  nested = std::string(kGoodOpenCV) + "x: " + std::string(64, '[') + std::string(64, ']') + "\n";
  EXPECT_THROW(parse_cameras(nested, CameraFileFormat::OpenCV, "o.yaml"), InputError);
  // Brackets in a quoted text count as nesting but a few do no harm.
  // A document's end marker with nothing after it is a whole file.
  EXPECT_NO_THROW(parse_cameras(std::string(kGoodOpenCV) + "...\n", CameraFileFormat::OpenCV, "end.yaml"));
  EXPECT_NO_THROW(parse_cameras(std::string(kGoodOpenCV) + "camera_name: \"cam]]]]\"\n", CameraFileFormat::OpenCV,
                                "o.yaml"));
}

TEST(CameraFileRejections, OpenCVMatricesHonourTheirElementType) {
  // dt: f holds floats: the values are rounded as OpenCV rounds them.
  const std::string f = replace(replace(kGoodOpenCV, "dt: d", "dt: f"), "320.", "320.1");
  const Camera camera = parse_cameras(f, CameraFileFormat::OpenCV, "o.yaml")[0];
  EXPECT_EQ(camera.model.cx_px(), static_cast<double>(320.1f));
  EXPECT_NE(camera.model.cx_px(), 320.1);
  // Integer types take the values they can hold, exactly.
  const std::string w = replace(replace(kGoodOpenCV, "dt: d", "dt: w"), "600., 0., 320., 0., 600., 240., 0., 0., 1.",
                                "600, 0, 320, 0, 600, 240, 0, 0, 1");
  const Camera integers = parse_cameras(w, CameraFileFormat::OpenCV, "o.yaml")[0];
  EXPECT_EQ(integers.model.fx_px(), 600);
  EXPECT_EQ(integers.model.cy_px(), 240);
  // An empty distortion matrix (no distortion) stays accepted.
  const std::string empty =
      replace(replace(kGoodOpenCV, "   rows: 1\n   cols: 5", "   rows: 0\n   cols: 0"), "[ -0.1, 0.01, 0., 0., 0. ]",
              "[]");
  EXPECT_EQ(parse_cameras(empty, CameraFileFormat::OpenCV, "o.yaml")[0].model.lens_model(), LensModel::Pinhole);
}

TEST_F(CameraFileTest, DeeplyNestedOpenCVFileIsRefusedByEveryEntryPoint) {
  // 50,000 levels crashed OpenCV's recursive parser (SIGSEGV) in camera show,
  // camera convert and --initial-camera, which all read through read_camera.
  const std::string path =
      put("deep.yaml", std::string(kGoodOpenCV) + "x: " + std::string(50000, '[') + std::string(50000, ']') + "\n");
  expect_input_error([&] { read_cameras(path); }, path, {"nested more than 64 levels"});
  expect_input_error([&] { read_camera(path); }, path, {"nested more than 64 levels"});
}

TEST(CameraFileRejections, MrcalHasNoFourteenCoefficientModel) {
  std::mt19937 rng(51);
  const Camera camera = random_camera(rng, LensModel::OpenCV14, false, false, "tilted");
  expect_input_error([&] { format_cameras({camera}, CameraFileFormat::Mrcal, "tilted.cameramodel"); },
                     "tilted.cameramodel", {"lens_model", "opencv14", "mrcal has no 14-coefficient"});
}

TEST(CameraFileRejections, WritersRefuseNonFiniteValues) {
  std::mt19937 rng(52);
  Camera camera = random_camera(rng, LensModel::OpenCV4, true, true, "c");
  camera.camera_from_world->translation_mm.x() = NAN;
  for (CameraFileFormat f :
       {CameraFileFormat::Glasspiv, CameraFileFormat::OpenCV, CameraFileFormat::Mrcal, CameraFileFormat::Davis})
    expect_input_error([&] { format_cameras({camera}, f, "c.out"); }, "c.out", {"camera_from_world"});
  camera = random_camera(rng, LensModel::OpenCV4, false, false, "c");
  camera.pixel_pitch_um = -1;
  expect_input_error([&] { format_cameras({camera}, CameraFileFormat::Glasspiv, "c.out"); }, "c.out",
                     {"pixel_pitch_um"});
}

}  // namespace
}  // namespace glasspiv
