// glasspiv calib detect | intrinsics | report run as a user runs them: bad input
// gives exit status 2 and one line on stderr naming the file and the field;
// no output ever replaces an input; no Ceres or glog line reaches stderr.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <sys/wait.h>

#include <nlohmann/json.hpp>

#include "sim/calibration_views.h"
#include "truth_cameras.h"
#include "targets/observations_io.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

struct CommandRun {
  int status = -1;
  std::string out, err;
};

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs glasspiv with `args` in `dir` (each argument single-quoted).
CommandRun glasspiv(const fs::path& dir, const std::vector<std::string>& args) {
  std::string command = "cd '" + dir.string() + "' && '" GLASSPIV_EXE "'";
  for (const std::string& a : args) command += " '" + a + "'";
  command += " > stdout.txt 2> stderr.txt";
  const int raw = std::system(command.c_str());
  CommandRun r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = slurp(dir / "stdout.txt");
  r.err = slurp(dir / "stderr.txt");
  return r;
}

int line_count(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

// Exit 2, one line on stderr that names `file` and `field`.
void expect_refused(const CommandRun& r, const std::string& file, const std::string& field) {
  EXPECT_EQ(r.status, 2) << r.out << r.err;
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(file + ":"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("field '" + field + "'"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("nan"), std::string::npos) << r.err;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("glasspiv_calib_commands_test_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

Observations synthetic_views(unsigned seed) {
  std::mt19937 rng(seed);
  const CameraModel truth = testing::truth_opencv5();
  return observe_board(truth, {}, plan_views(truth, {}, {}, rng), 0.1, rng);
}

const fs::path kPhotos = fs::path(GLASSPIV_SOURCE_DIR) / "data/calibration/opencv_left";

TEST(CalibCommands, OutputsNeverReplaceInputs) {
  const fs::path dir = fresh_dir("inputs");
  fs::copy_file(kPhotos / "target.yaml", dir / "t.yaml");
  fs::copy_file(kPhotos / "left01.jpg", dir / "left01.jpg");
  write_observations((dir / "obs.yaml").string(), synthetic_views(40));
  const std::string target = slurp(dir / "t.yaml"), obs = slurp(dir / "obs.yaml");

  expect_refused(glasspiv(dir, {"calib", "detect", "left01.jpg", "--target", "t.yaml", "-o", "t.yaml"}), "t.yaml",
                 "-o");
  expect_refused(glasspiv(dir, {"calib", "detect", "left01.jpg", "--target", "t.yaml", "-o", "x.yaml", "--vnl",
                                "left01.jpg"}),
                 "left01.jpg", "--vnl");
  expect_refused(glasspiv(dir, {"calib", "intrinsics", "obs.yaml", "-o", "obs.yaml"}), "obs.yaml", "-o");
  expect_refused(glasspiv(dir, {"calib", "intrinsics", "obs.yaml", "-o", "cam.yaml", "--report", "obs.yaml"}),
                 "obs.yaml", "--report");
  expect_refused(glasspiv(dir, {"calib", "intrinsics", "left01.jpg", "--target", "t.yaml", "-o", "cam.yaml",
                                "--observations-out", "t.yaml"}),
                 "t.yaml", "--observations-out");
  expect_refused(glasspiv(dir, {"calib", "report", "obs.yaml", "-o", "obs.yaml"}), "obs.yaml", "-o");
  // The initial camera: a first fit writes cam.yaml, a second must not replace it.
  const CommandRun first = glasspiv(dir, {"calib", "intrinsics", "obs.yaml", "-o", "cam.yaml", "--no-report"});
  ASSERT_EQ(first.status, 0) << first.err;
  const std::string camera = slurp(dir / "cam.yaml");
  expect_refused(glasspiv(dir, {"calib", "intrinsics", "obs.yaml", "--initial-camera", "cam.yaml", "-o", "cam.yaml"}),
                 "cam.yaml", "-o");
  // An overlay named like an input photo: photos a/left01.jpg and
  // ov/left01_corners.png with --overlay-dir ov.
  fs::create_directories(dir / "a");
  fs::create_directories(dir / "ov");
  fs::copy_file(kPhotos / "left01.jpg", dir / "a/left01.jpg");
  fs::copy_file(kPhotos / "left01.jpg", dir / "ov/left01_corners.png");
  const std::string photo = slurp(dir / "ov/left01_corners.png");
  for (const char* command : {"detect", "intrinsics"})
    expect_refused(glasspiv(dir, {"calib", command, "a/left01.jpg", "ov/left01_corners.png", "--target", "t.yaml",
                                  "-o", "out.yaml", "--overlay-dir", "ov"}),
                   "ov/left01_corners.png", "--overlay-dir");
  EXPECT_EQ(slurp(dir / "t.yaml"), target);
  EXPECT_EQ(slurp(dir / "obs.yaml"), obs);
  EXPECT_EQ(slurp(dir / "cam.yaml"), camera);
  EXPECT_EQ(slurp(dir / "ov/left01_corners.png"), photo);
  EXPECT_FALSE(fs::exists(dir / "out.yaml"));
}

TEST(CalibCommands, NumericOptionsAreChecked) {
  const fs::path dir = fresh_dir("options");
  write_observations((dir / "obs.yaml").string(), synthetic_views(41));
  for (const char* k : {"nan", "inf", "-inf", "-1", "0.5", "1e9", "4x"}) {
    const CommandRun r = glasspiv(dir, {"calib", "intrinsics", "obs.yaml", "-o", "cam.yaml", "--outlier-k", k});
    EXPECT_EQ(r.status, 2) << "--outlier-k " << k << ": " << r.err;
    EXPECT_NE(r.err.find("--outlier-k"), std::string::npos) << r.err;
    EXPECT_EQ(line_count(r.err), 1) << r.err;
  }
  for (const char* pitch : {"nan", "inf", "0", "-3"})
    for (const char* command : {"intrinsics", "report"}) {
      const CommandRun r = glasspiv(dir, {"calib", command, "obs.yaml", "-o", "cam.yaml", "--pixel-pitch-um", pitch});
      EXPECT_EQ(r.status, 2) << command << " --pixel-pitch-um " << pitch << ": " << r.err;
      EXPECT_NE(r.err.find("--pixel-pitch-um"), std::string::npos) << r.err;
    }
  EXPECT_FALSE(fs::exists(dir / "cam.yaml"));
  const CommandRun ok = glasspiv(dir, {"calib", "intrinsics", "obs.yaml", "-o", "cam.yaml", "--outlier-k", "0", "--no-report"});
  EXPECT_EQ(ok.status, 0) << ok.err;
}

// The issue's case (13 copies of one view), corners that fit no camera (the
// solver fails, Ceres logs), and a good set: errors name the observations file,
// nothing but the one error line reaches stderr, "nan" is never printed.
TEST(CalibCommands, FitErrorsNameTheFileAndCeresIsSilent) {
  const fs::path dir = fresh_dir("fit");
  Observations good = synthetic_views(42);
  Observations copies = good;
  copies.views.assign(13, good.views[0]);
  Observations mirrored = good;
  for (ViewObservations& v : mirrored.views)
    for (CornerObservation& c : v.corners)
      if (c.id % 2 == 0) c.pixel_px = Eigen::Vector2d(2047, 1535) - c.pixel_px;
  write_observations((dir / "good.yaml").string(), good);
  write_observations((dir / "copies.yaml").string(), copies);
  write_observations((dir / "mirrored.json").string(), mirrored);
  for (const std::string command : {"intrinsics", "report"}) {
    const std::string out = command == "intrinsics" ? "out.yaml" : "out";
    const CommandRun same = glasspiv(dir, {"calib", command, "copies.yaml", "-o", out});
    expect_refused(same, "copies.yaml", "views");
    EXPECT_NE(same.err.find("one board pose"), std::string::npos) << same.err;
    expect_refused(glasspiv(dir, {"calib", command, "mirrored.json", "-o", out}), "mirrored.json", "views");
  }
  const CommandRun ok = glasspiv(dir, {"calib", "intrinsics", "good.yaml", "-o", "cam.yaml"});
  EXPECT_EQ(ok.status, 0) << ok.err;
  EXPECT_EQ(ok.out.find("nan"), std::string::npos) << ok.out;
  EXPECT_EQ(ok.err.find("WARNING"), std::string::npos) << ok.err;
}

// "nan" or "inf" as a word: a figure printed without a value.
bool has_non_finite_figure(const std::string& text) {
  static const std::regex word(R"((^|[^A-Za-z_])(nan|-nan|inf|-inf)([^A-Za-z_]|$))", std::regex::icase);
  return std::regex_search(text, word);
}

// A lens whose distortion folds inside the image (k1 = -0.5 at fx = 1000 px:
// the largest distorted radius is 544 px, the image corners are 1101 px from
// the centre): the fitted model has no ray at the corners and the edges, as on
// a fisheye set. Every figure the user reads names those pixels instead of
// printing "nan": the command's output, report.html and metrics.json.
TEST(CalibCommands, PixelsWithoutARayAreNamedNotNan) {
  const fs::path dir = fresh_dir("fold");
  const CameraModel truth(1920, 1080, 1000, 1000, 959.5, 539.5, {-0.5, 0, 0, 0});
  ViewPlan plan;
  plan.min_fill = 0.25;
  plan.max_fill = 0.4;
  plan.centre_spread = 0.35;
  std::mt19937 rng(7);
  const Observations obs = observe_board(truth, {}, plan_views(truth, {}, plan, rng), 0.1, rng);
  write_observations((dir / "fold.yaml").string(), obs);
  const CommandRun run = glasspiv(dir, {"calib", "report", "fold.yaml", "-o", "rep", "--lens-model", "opencv4"});
  ASSERT_EQ(run.status, 0) << run.out << run.err;
  EXPECT_FALSE(has_non_finite_figure(run.out)) << run.out;
  EXPECT_NE(run.out.find("the fitted model has no ray at 4 of the 4 image corners: top-left, top-right, "
                         "bottom-left, bottom-right"),
            std::string::npos)
      << run.out;
  const std::string html = slurp(dir / "rep" / "report.html"), json_text = slurp(dir / "rep" / "metrics.json");
  EXPECT_FALSE(has_non_finite_figure(html));
  EXPECT_NE(html.find("no figure at 4 of the 4 corners: top-left (the fitted model has no ray through this pixel)"),
            std::string::npos);
  EXPECT_NE(html.find("samples have no figure (grey)"), std::string::npos);
  EXPECT_FALSE(has_non_finite_figure(json_text));
  const nlohmann::json metrics = nlohmann::json::parse(json_text);
  const nlohmann::json& u = metrics.at("projection_uncertainty_px");
  EXPECT_TRUE(u.at("centre").is_number());
  ASSERT_EQ(u.at("without_figure").size(), 4u);
  EXPECT_EQ(u.at("without_figure")[0].at("pixel"), "top-left");
  EXPECT_TRUE(u.at("corners").at("bottom-right").is_null());
  EXPECT_GT(u.at("map").at("samples_without_figure").get<int>(), 0);
  EXPECT_LT(u.at("map").at("samples_without_figure").get<int>(), u.at("map").at("samples").get<int>());
}

}  // namespace
}  // namespace glasspiv
