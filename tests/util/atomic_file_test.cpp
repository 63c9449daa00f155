#include "util/atomic_file.h"

#include <filesystem>

#include <gtest/gtest.h>

#include "util/input_error.h"

namespace glasspiv {
namespace fs = std::filesystem;

class AtomicFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("glasspiv-atomic-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(AtomicFileTest, WritesCreatesFoldersAndReadsBack) {
  const std::string path = (dir_ / "a" / "b.txt").string();
  write_file_atomically(path, "hello");
  EXPECT_EQ(read_file(path), "hello");
  write_file_atomically(path, "replaced");
  EXPECT_EQ(read_file(path), "replaced");
  // No temporary file is left beside the output.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_ / "a"), fs::directory_iterator()), 1);
}

TEST_F(AtomicFileTest, FailedWriterLeavesTheOldFileIntact) {
  const std::string path = (dir_ / "keep.txt").string();
  write_file_atomically(path, "original");
  EXPECT_THROW(write_file_atomically_with(path, [](const std::string&) { throw InputError("x", "", "boom"); }),
               InputError);
  EXPECT_EQ(read_file(path), "original");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(AtomicFileTest, MissingFileErrorNamesThePath) {
  try {
    read_file((dir_ / "nope.yaml").string());
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nope.yaml"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos);
  }
}

}  // namespace glasspiv
