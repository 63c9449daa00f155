// util/file_identity.h: one file reached by several names (the same path, a
// ./ prefix, a folder's listing, a symlink, a hard link) and a byte-for-byte
// copy are the same input; files that differ in one byte, or only in size, are not.
#include "util/file_identity.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/temp_dir.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

void write(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

TEST(FileIdentity, SameFileByAnyNameAndCopiesAreOneInput) {
  TempDir dir("file_identity");
  const std::string a = dir.file("a.png"), b = dir.file("b.png"), c = dir.file("c.png");
  write(a, std::string(100000, 'x') + "a");
  write(b, std::string(100000, 'x') + "b");  // same size, one byte differs
  write(c, "short");
  EXPECT_FALSE(find_same_input({a, b, c}));
  EXPECT_FALSE(find_same_input({}));
  EXPECT_FALSE(find_same_input({a, dir.file("missing.png")}));  // left to the reader

  const auto expect_same = [](const std::vector<std::string>& paths, std::size_t first, std::size_t second,
                              bool same_file) {
    const auto s = find_same_input(paths);
    ASSERT_TRUE(s) << paths.back();
    EXPECT_EQ(s->first, first);
    EXPECT_EQ(s->second, second);
    EXPECT_EQ(s->same_file, same_file);
  };
  expect_same({a, b, a}, 0, 2, true);
  const std::string dotted = (std::filesystem::path(dir.file("")) / "." / "a.png").string();
  expect_same({b, a, dotted}, 1, 2, true);
  std::filesystem::create_symlink(a, dir.file("link.png"));
  expect_same({dir.file("link.png"), b, a}, 0, 2, true);
  std::filesystem::create_hard_link(a, dir.file("hard.png"));
  expect_same({c, dir.file("hard.png"), a}, 1, 2, true);
  std::filesystem::copy_file(b, dir.file("copy.png"));
  expect_same({a, b, dir.file("copy.png")}, 1, 2, false);

  try {
    check_distinct_inputs({a, b, dir.file("copy.png")}, "PHOTO", "photo");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), dir.file("copy.png"));
    EXPECT_EQ(e.field(), "PHOTO");
    EXPECT_NE(e.problem().find("same bytes as '" + b + "'"), std::string::npos) << e.what();
  }
  check_distinct_inputs({a, b, c}, "PHOTO", "photo");
}

}  // namespace
}  // namespace glasspiv
