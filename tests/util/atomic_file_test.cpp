#include "util/atomic_file.h"

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

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

std::size_t entries(const fs::path& dir) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

TEST_F(AtomicFileTest, RefusesToReplaceWhatIsNotARegularFile) {
  fs::create_directories(dir_);
  const fs::path real = dir_ / "real.txt", link = dir_ / "link.txt", folder = dir_ / "folder.txt", fifo = dir_ / "f.txt";
  write_file_atomically(real.string(), "kept");
  fs::create_symlink(real, link);
  fs::create_directory(folder);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const auto& [path, kind] : {std::pair{link, "symbolic link"}, std::pair{folder, "folder"}, std::pair{fifo, "fifo"}}) {
    try {
      write_file_atomically(path.string(), "replaced");
      FAIL() << "expected InputError for " << path;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(kind), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("regular files only"), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(read_file(real.string()), "kept");
  EXPECT_EQ(entries(dir_), 4u);  // no temporary either
  // A device (checked only: nothing is written).
  EXPECT_THROW(check_replaceable_output("/dev/null"), InputError);
  EXPECT_NO_THROW(check_replaceable_output((dir_ / "absent.txt").string()));
  EXPECT_NO_THROW(check_replaceable_output(real.string()));
}

TEST_F(AtomicFileTest, ASetOfOutputsIsWrittenAllOrNothing) {
  const std::string a = (dir_ / "a.txt").string(), b = (dir_ / "b.txt").string();
  write_file_atomically(a, "old");
  auto put = [](const std::string& text) {
    return [text](const std::string& tmp) { std::ofstream(tmp, std::ios::binary) << text; };
  };
  EXPECT_THROW(write_files_atomically({{a, put("new")}, {b, [](const std::string&) { throw InputError("b", "", "boom"); }}}),
               InputError);
  EXPECT_EQ(read_file(a), "old");
  EXPECT_FALSE(fs::exists(b));
  EXPECT_EQ(entries(dir_), 1u);
  write_files_atomically({{a, put("new")}, {b, put("bee")}});
  EXPECT_EQ(read_file(a), "new");
  EXPECT_EQ(read_file(b), "bee");
  EXPECT_EQ(entries(dir_), 2u);
}

// A child process stopped by `sig` in the middle of writing leaves no temporary.
void expect_signal_leaves_no_temporary(const fs::path& dir, int sig) {
  const fs::path out = dir / "out", ready = dir / "ready";
  fs::create_directories(dir);
  struct sigaction current {};
  ::sigaction(sig, nullptr, &current);
  if (current.sa_handler == SIG_IGN) GTEST_SKIP() << "signal " << sig << " is ignored here (left ignored by design)";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    try {
      write_file_atomically_with((out / "map.tmap").string(), [&](const std::string& tmp) {
        std::ofstream(tmp, std::ios::binary) << std::string(1 << 20, 'x');
        std::ofstream(ready.string()) << tmp;
        for (;;) ::pause();
      });
    } catch (...) {
    }
    ::_exit(3);
  }
  for (int i = 0; i < 1000 && !fs::exists(ready); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const std::string tmp = read_file(ready.string());
  EXPECT_TRUE(fs::exists(tmp)) << "the child did not write its temporary";
  ::kill(child, sig);
  int status = 0;
  pid_t got = 0;
  for (int i = 0; i < 1000 && (got = ::waitpid(child, &status, WNOHANG)) == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  if (got == 0) {
    ::kill(child, SIGKILL);
    ::waitpid(child, &status, 0);
    FAIL() << "the child did not stop on signal " << sig;
  }
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "the signal was not re-raised, status " << status;
  EXPECT_FALSE(fs::exists(tmp)) << tmp << " left behind";
  EXPECT_EQ(entries(out), 0u);
}

TEST_F(AtomicFileTest, SigtermDuringAWriteLeavesNoTemporary) { expect_signal_leaves_no_temporary(dir_, SIGTERM); }
TEST_F(AtomicFileTest, SigintDuringAWriteLeavesNoTemporary) { expect_signal_leaves_no_temporary(dir_, SIGINT); }

TEST_F(AtomicFileTest, TheNextWriteRemovesTemporariesOfDeadProcesses) {
  fs::create_directories(dir_);
  const pid_t dead = ::fork();
  ASSERT_GE(dead, 0);
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  char host[256] = {};
  ::gethostname(host, sizeof(host) - 1);
  const std::string d = std::to_string(dead), alive = std::to_string(::getppid());
  const std::vector<std::string> stale = {".map.tmp-" + std::string(host) + "-" + d + "-123456.tmap",
                                          ".old.tmp" + d + "-42.tif"};  // the name earlier versions used
  const std::vector<std::string> kept = {".map.tmp-" + std::string(host) + "-" + alive + "-1.tmap",  // running
                                         ".map.tmp-elsewhere-" + d + "-7.tmap",  // another machine's
                                         ".map.tmp.notes", "user.tmp123-4.txt"};
  for (const auto& n : stale) std::ofstream((dir_ / n).string()) << "stale";
  for (const auto& n : kept) std::ofstream((dir_ / n).string()) << "kept";
  write_file_atomically((dir_ / "map.tmap").string(), "new");
  for (const auto& n : stale) EXPECT_FALSE(fs::exists(dir_ / n)) << n;
  for (const auto& n : kept) EXPECT_TRUE(fs::exists(dir_ / n)) << n;
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
