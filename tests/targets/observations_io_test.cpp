// Observation files: YAML and JSON round trips (exact), every rejection, and
// mrcal's corners.vnl, read back by mrcal itself where python3-mrcal is
// installed.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "targets/observations_io.h"
#include "util/atomic_file.h"
#include "tests/python_mrcal.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

Observations sample(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> px(-0.5, 1279.5), mm(-100, 300);
  Observations o;
  o.image_width_px = 1280;
  o.image_height_px = 960;
  o.target_name = "bench \"A\": charuco";
  for (int v = 0; v < 3; ++v) {
    ViewObservations view;
    view.source = v == 1 ? "shots/empty view.png" : "shots/img" + std::to_string(v) + ".png";
    if (v != 1)
      for (int id = 0; id < 20; id += 1 + v) {
        CornerObservation c;
        c.id = id;
        c.pixel_px = Eigen::Vector2d(px(rng), px(rng) * 0.75);
        c.board_point_mm = Eigen::Vector3d(mm(rng), mm(rng), v == 2 ? 1e-17 : 0.0);
        view.corners.push_back(c);
      }
    o.views.push_back(view);
  }
  return o;
}

void expect_equal(const Observations& a, const Observations& b) {
  EXPECT_EQ(a.image_width_px, b.image_width_px);
  EXPECT_EQ(a.image_height_px, b.image_height_px);
  EXPECT_EQ(a.target_name, b.target_name);
  ASSERT_EQ(a.views.size(), b.views.size());
  for (std::size_t v = 0; v < a.views.size(); ++v) {
    EXPECT_EQ(a.views[v].source, b.views[v].source);
    ASSERT_EQ(a.views[v].corners.size(), b.views[v].corners.size());
    for (std::size_t c = 0; c < a.views[v].corners.size(); ++c) {
      EXPECT_EQ(a.views[v].corners[c].id, b.views[v].corners[c].id);
      EXPECT_EQ(a.views[v].corners[c].pixel_px, b.views[v].corners[c].pixel_px);  // bit for bit
      EXPECT_EQ(a.views[v].corners[c].board_point_mm, b.views[v].corners[c].board_point_mm);
    }
  }
}

TEST(ObservationsFile, RoundTripsExactlyInBothFormats) {
  for (const ObservationsFormat format : {ObservationsFormat::yaml, ObservationsFormat::json}) {
    const Observations o = sample(42);
    expect_equal(parse_observations(format_observations(o, format), format, "x"), o);
  }
}

TEST(ObservationsFile, FilesByExtension) {
  const fs::path dir = fs::temp_directory_path() / "glasspiv_targets_observations_test";
  fs::create_directories(dir);
  const Observations o = sample(7);
  for (const char* name : {"obs.yaml", "obs.yml", "obs.json"}) {
    const std::string path = (dir / name).string();
    write_observations(path, o);
    expect_equal(read_observations(path), o);
  }
  EXPECT_EQ(read_file((dir / "obs.json").string()).front(), '{');
  EXPECT_THROW(write_observations((dir / "obs.txt").string(), o), InputError);
  fs::remove_all(dir);
}

TEST(ObservationsFile, YamlLooksAsDocumented) {
  Observations o;
  o.image_width_px = 640;
  o.image_height_px = 480;
  o.target_name = "t";
  o.views.push_back({"a.png", {{3, {1.25, 2.5}, {15, 30, 0}}}});
  o.views.push_back({"b.png", {}});
  const std::string text = format_observations(o, ObservationsFormat::yaml);
  EXPECT_NE(text.find("glasspiv_observations: 1\n"), std::string::npos) << text;
  EXPECT_NE(text.find("image_size_px: [640, 480]\n"), std::string::npos) << text;
  EXPECT_NE(text.find("- [3, 1.25, 2.5, 15, 30, 0]\n"), std::string::npos) << text;
  EXPECT_NE(text.find("corners: []"), std::string::npos) << text;
}

struct Rejection {
  const char* name;
  std::string text;
  const char* field;
};

TEST(ObservationsFile, RejectsMalformedFiles) {
  const std::string head = "glasspiv_observations: 1\nimage_size_px: [640, 480]\ntarget: t\n";
  const Rejection yaml[] = {
      {"unknown key", head + "views: []\nextra: 1\n", "extra"},
      {"missing views", head, "views"},
      {"version", "glasspiv_observations: 2\nimage_size_px: [640, 480]\ntarget: t\nviews: []\n",
       "glasspiv_observations"},
      {"size", "glasspiv_observations: 1\nimage_size_px: [640]\ntarget: t\nviews: []\n", "image_size_px"},
      {"zero size", "glasspiv_observations: 1\nimage_size_px: [0, 480]\ntarget: t\nviews: []\n", "image_size_px"},
      {"view key", head + "views:\n  - source: a\n    corners: []\n    pose: 1\n", "views[0].pose"},
      {"short corner", head + "views:\n  - source: a\n    corners:\n      - [1, 2, 3]\n", "views[0].corners[0]"},
      {"text in corner", head + "views:\n  - source: a\n    corners:\n      - [1, x, 3, 0, 0, 0]\n",
       "views[0].corners[0][1]"},
      {"fractional id", head + "views:\n  - source: a\n    corners:\n      - [1.5, 2, 3, 0, 0, 0]\n",
       "views[0].corners[0][0]"},
      {"negative id", head + "views:\n  - source: a\n    corners:\n      - [-1, 2, 3, 0, 0, 0]\n",
       "views[0].corners[0]"},
      {"repeated id",
       head + "views:\n  - source: a\n    corners:\n      - [1, 2, 3, 0, 0, 0]\n      - [1, 5, 6, 0, 0, 0]\n",
       "views[0].corners[1]"},
      {"outside the image", head + "views:\n  - source: a\n    corners:\n      - [1, 640, 3, 0, 0, 0]\n",
       "views[0].corners[0]"},
      {"nan", head + "views:\n  - source: a\n    corners:\n      - [1, .nan, 3, 0, 0, 0]\n",
       "views[0].corners[0][1]"},
  };
  for (const Rejection& r : yaml) {
    SCOPED_TRACE(r.name);
    try {
      parse_observations(r.text, ObservationsFormat::yaml, "obs.yaml");
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), r.field) << e.what();
      EXPECT_EQ(e.file(), "obs.yaml");
    }
  }
  const Rejection json[] = {
      {"not json", "{\"glasspiv_observations\": 1,", ""},
      {"unknown key",
       R"({"glasspiv_observations": 1, "image_size_px": [2, 2], "target": "t", "views": [], "x": 1})", "x"},
      {"string number",
       R"({"glasspiv_observations": 1, "image_size_px": ["2", 2], "target": "t", "views": []})", "image_size_px[0]"},
      {"corner", R"({"glasspiv_observations": 1, "image_size_px": [2, 2], "target": "t",
                    "views": [{"source": "a", "corners": [[0, 0, 0, 0, 0]]}]})",
       "views[0].corners[0]"},
      {"source", R"({"glasspiv_observations": 1, "image_size_px": [2, 2], "target": "t",
                    "views": [{"source": 3, "corners": []}]})",
       "views[0].source"},
  };
  for (const Rejection& r : json) {
    SCOPED_TRACE(r.name);
    try {
      parse_observations(r.text, ObservationsFormat::json, "obs.json");
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), r.field) << e.what();
      EXPECT_EQ(e.file(), "obs.json");
    }
  }
}

// Expects an InputError naming `file` and `field`, one line, with every fragment in its message.
void expect_rejected(const std::string& text, ObservationsFormat format, const std::string& file,
                     const std::string& field, const std::vector<std::string>& fragments) {
  try {
    parse_observations(text, format, file);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(e.file(), file) << message;
    EXPECT_EQ(e.field(), field) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    for (const std::string& f : fragments) EXPECT_NE(message.find(f), std::string::npos) << f << " in " << message;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not an InputError: " << e.what();
  }
}

const char* const kJsonHead = R"({"glasspiv_observations": 1, "image_size_px": [640, 480], "target": "t", )";

TEST(ObservationsFile, JsonNumberBeyondADoubleNamesTheField) {
  // json::parse threw out_of_range.406, which is no InputError.
  expect_rejected(std::string(kJsonHead) + R"("views": [{"source": "a", "corners": [[0, 1e999, 3, 0, 0, 0]]}]})",
                  ObservationsFormat::json, "obs.json", "views[0].corners[0][1]", {"1e999", "double"});
  expect_rejected(R"({"glasspiv_observations": 1, "image_size_px": [-1e999, 480], "target": "t", "views": []})",
                  ObservationsFormat::json, "obs.json", "image_size_px[0]", {"1e999"});
  expect_rejected(R"({"glasspiv_observations": 1e400})", ObservationsFormat::json, "obs.json",
                  "glasspiv_observations", {"1e400"});
}

TEST(ObservationsFile, DuplicateKeysAreRefused) {
  // json::parse keeps the last of a key given twice.
  expect_rejected(std::string(kJsonHead) + R"("views": [], "target": "u"})", ObservationsFormat::json, "obs.json",
                  "target", {"twice"});
  expect_rejected(std::string(kJsonHead) + R"("views": [{"source": "a", "source": "b", "corners": []}]})",
                  ObservationsFormat::json, "obs.json", "views[0].source", {"twice"});
  const std::string head = "glasspiv_observations: 1\nimage_size_px: [640, 480]\ntarget: t\n";
  expect_rejected(head + "views: []\ntarget: u\n", ObservationsFormat::yaml, "obs.yaml", "target", {"twice"});
  expect_rejected(head + "views:\n  - {source: a, source: b, corners: []}\n", ObservationsFormat::yaml, "obs.yaml",
                  "views[0].source", {"twice"});
}

TEST(ObservationsFile, ImageSizeHasTheCameraModelsLimit) {
  auto yaml = [](const std::string& size) {
    return "glasspiv_observations: 1\nimage_size_px: " + size + "\ntarget: t\nviews: []\n";
  };
  auto json = [](const std::string& size) {
    return R"({"glasspiv_observations": 1, "image_size_px": )" + size + R"(, "target": "t", "views": []})";
  };
  for (const std::string size : {"[1e8, 1e8]", "[2147483647, 480]", "[65537, 1]", "[65536, 65536]", "[-640, 480]"}) {
    SCOPED_TRACE(size);
    expect_rejected(yaml(size), ObservationsFormat::yaml, "obs.yaml", "image_size_px", {"px"});
    expect_rejected(json(size), ObservationsFormat::json, "obs.json", "image_size_px", {"px"});
  }
  expect_rejected(yaml("[1e8, 1e8]"), ObservationsFormat::yaml, "obs.yaml", "image_size_px",
                  {"line 2", "65536 px a side"});
  expect_rejected(json("[40000, 40000]"), ObservationsFormat::json, "obs.json", "image_size_px", {"1073741824 px"});
  EXPECT_EQ(parse_observations(yaml("[65536, 16384]"), ObservationsFormat::yaml, "obs.yaml").image_width_px, 65536);
  EXPECT_EQ(parse_observations(json("[16384, 65536]"), ObservationsFormat::json, "obs.json").image_height_px, 65536);
  // The writers hold to it too.
  Observations o = sample(3);
  o.image_width_px = 70000;
  EXPECT_THROW(format_observations(o, ObservationsFormat::json), InputError);
}

TEST(ObservationsFile, DeepJsonIsRefused) {
  std::string field = "views";
  for (int level = 2; level <= 64; ++level) field += "[0]";  // the 65th level: 64 open below the root
  expect_rejected(std::string(kJsonHead) + R"("views": )" + std::string(100000, '[') + std::string(100000, ']') + "}",
                  ObservationsFormat::json, "obs.json", field, {"nested more than 64 levels"});
}

TargetSpec charuco_5x4() {
  TargetSpec s;
  s.kind = TargetKind::charuco;
  s.name = "small";
  s.squares_x = 5;
  s.squares_y = 4;
  s.square_size_mm = 15;
  s.marker_size_mm = 11;
  s.dictionary = "DICT_4X4_50";
  return s;
}

Observations vnl_sample() {
  // 5 x 4 squares: a 4 x 3 grid of corners. View a: ids 0..11 but 5 missing;
  // view b: nothing found.
  Observations o;
  o.image_width_px = 640;
  o.image_height_px = 480;
  o.target_name = "small";
  ViewObservations a{"a.png", {}};
  for (int id = 11; id >= 0; --id)  // any order in; row-major out
    if (id != 5) a.corners.push_back({id, {10.5 + id, 20.25 + id}, {0, 0, 0}});
  o.views.push_back(a);
  o.views.push_back({"b.png", {}});
  return o;
}

TEST(MrcalVnl, LinesInGridOrder) {
  const std::string text = format_mrcal_corners_vnl(vnl_sample(), charuco_5x4());
  std::vector<std::string> lines;
  for (std::size_t at = 0, end; (end = text.find('\n', at)) != std::string::npos; at = end + 1)
    lines.push_back(text.substr(at, end - at));
  ASSERT_GE(lines.size(), 1u);
  EXPECT_EQ(lines[0], "# filename x y level");
  std::vector<std::string> data;
  for (const std::string& l : lines)
    if (l.rfind("#", 0) != 0) data.push_back(l);
  ASSERT_EQ(data.size(), 12u + 1u);
  EXPECT_EQ(data[0], "a.png 10.5 20.25 0");
  EXPECT_EQ(data[4], "a.png 14.5 24.25 0");
  EXPECT_EQ(data[5], "a.png - - -");  // corner 5 not seen
  EXPECT_EQ(data[11], "a.png 21.5 31.25 0");
  EXPECT_EQ(data[12], "b.png - -");   // the whole view without detections
  EXPECT_NE(text.find("--object-width-n 4 --object-height-n 3 --object-spacing 15"), std::string::npos);
}

TEST(MrcalVnl, RejectsWhatMrcalCannotRead) {
  Observations o = vnl_sample();
  o.views[0].source = "with space.png";
  EXPECT_THROW(format_mrcal_corners_vnl(o, charuco_5x4(), "c.vnl"), InputError);
  o = vnl_sample();
  o.views[0].corners.push_back({12, {1, 1}, {0, 0, 0}});  // not on a 4 x 3 grid
  EXPECT_THROW(format_mrcal_corners_vnl(o, charuco_5x4(), "c.vnl"), InputError);
  TargetSpec grid;
  grid.kind = TargetKind::aprilgrid;
  grid.squares_x = grid.squares_y = 6;
  grid.square_size_mm = 22;
  grid.marker_size_mm = 6.6;
  grid.dictionary = "tag36h11";
  try {
    format_mrcal_corners_vnl(vnl_sample(), grid, "c.vnl");
    ADD_FAILURE() << "aprilgrid accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "c.vnl");
  }
}

TEST(MrcalVnl, MrcalReadsIt) {
  const std::string python = testing::python_with_mrcal();
  if (python.empty()) GTEST_SKIP() << "python3 with mrcal (python3-mrcal) is not installed";
  const fs::path dir = fs::temp_directory_path() / "glasspiv_targets_vnl_test";
  fs::create_directories(dir);
  const std::string path = (dir / "corners.vnl").string();
  write_mrcal_corners_vnl(path, vnl_sample(), charuco_5x4());
  const std::string command = "'" + python + "' " + std::string(GLASSPIV_SOURCE_DIR) + "/tests/targets/mrcal_vnl_check.py '" +
                              path + "' 4 3 2>&1";
  std::FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  char buffer[512];
  while (std::fgets(buffer, sizeof buffer, pipe)) out += buffer;
  const int status = pclose(pipe);
  fs::remove_all(dir);
  ASSERT_EQ(status, 0) << out;
  // mrcal keeps view a (11 of 12 corners valid; point 0 at (10.5, 20.25)) and
  // drops view b, which has none.
  EXPECT_NE(out.find("a.png 11 10.5 20.25"), std::string::npos) << out;
  EXPECT_EQ(out.find("b.png"), std::string::npos) << out;
}

}  // namespace
}  // namespace glasspiv
