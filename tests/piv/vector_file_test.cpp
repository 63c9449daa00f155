#include "piv/vector_file.h"

#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>

#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

PivField small_field() {
  PivField f;
  f.grid = interrogation_grid(64, 48, 32, 16);  // 3 x 2
  f.u_px = {0.1, 2.25, -1.0 / 3, 4, 5, std::nan("")};
  f.v_px = {-0.5, 0, 1e-7, 4, 5, std::nan("")};
  f.flags = {VectorFlag::valid, VectorFlag::valid, VectorFlag::replaced, VectorFlag::valid, VectorFlag::valid,
             VectorFlag::invalid};
  f.peak_ratio = {3.5, 2, 1.25, 7, 8, 0};
  return f;
}

TEST(VectorFile, TextRoundTripsExactly) {
  const fs::path dir = fs::path(testing::TempDir()) / "piv_vector_file_test";
  fs::create_directories(dir);
  const PivField f = small_field();
  write_vector_files((dir / "v.txt").string(), (dir / "v.vtk").string(), f, {"frames: a.tif b.tif"});
  const std::string text = read_file((dir / "v.txt").string());
  EXPECT_NE(text.find("# frames: a.tif b.tif\n"), std::string::npos);
  EXPECT_NE(text.find("# grid: 3 x 2 vectors (cols x rows), window 32 px, step 16 px\n"), std::string::npos);
  EXPECT_NE(text.find("# x_px y_px u_px v_px flag peak_ratio\n15.5 15.5 0.1 -0.5 0 3.5\n"), std::string::npos);
  const std::vector<VectorRecord> r = read_vector_file((dir / "v.txt").string());
  ASSERT_EQ(r.size(), 6u);
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(r[i].x_px, f.x_px(i));
    EXPECT_EQ(r[i].y_px, f.y_px(i));
    EXPECT_EQ(r[i].flag, static_cast<int>(f.flags[i]));
    if (i < 5) {
      EXPECT_EQ(r[i].u_px, f.u_px[i]);  // shortest round-trip text
      EXPECT_EQ(r[i].v_px, f.v_px[i]);
    }
  }
  EXPECT_TRUE(std::isnan(r[5].u_px));
  const std::string vtk = read_file((dir / "v.vtk").string());
  EXPECT_NE(vtk.find("DIMENSIONS 3 2 1\nORIGIN 15.5 15.5 0\nSPACING 16 16 1\nPOINT_DATA 6\n"), std::string::npos);
  EXPECT_NE(vtk.find("VECTORS displacement_px double\n0.1 -0.5 0\n"), std::string::npos);
  EXPECT_EQ(vtk.find("nan"), std::string::npos);  // invalid vectors as 0 0 0, flag 2
  fs::remove_all(dir);
}

TEST(VectorFile, BadLinesAreNamed) {
  const fs::path dir = fs::path(testing::TempDir()) / "piv_vector_file_bad";
  fs::create_directories(dir);
  write_file_atomically((dir / "bad.txt").string(), "# header\n1 2 3 4 0 1\n1 2 3 4 7 1\n");
  try {
    read_vector_file((dir / "bad.txt").string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "line 3");
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace glasspiv
