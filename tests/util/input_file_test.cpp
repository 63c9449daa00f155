// Inputs are regular files (util/input_file.h): a fifo, a device or a folder is
// refused by every reader with one InputError, and none blocks. Each reader runs
// on a fifo nobody writes in a child process: a reader that opened it would
// wait forever, so the test fails by timeout, not by hanging.
#include "util/input_file.h"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "tests/temp_dir.h"
#include "util/atomic_file.h"
#include "util/binary_file.h"
#include "util/image_file.h"
#include "util/input_error.h"
#include "util/json_document.h"
#include "util/text_number.h"

namespace glasspiv {
namespace {

// The InputError problem `read` throws, run in a child that is killed after 10 s
// ("hung" then); "" if it threw nothing.
std::string problem_within_seconds(const std::function<void()>& read) {
  int out[2];
  if (::pipe(out) != 0) return "pipe failed";
  const pid_t child = ::fork();
  if (child == 0) {
    ::close(out[0]);
    std::string problem;
    try {
      read();
    } catch (const InputError& e) {
      problem = e.what();
    } catch (const std::exception& e) {
      problem = std::string("not an InputError: ") + e.what();
    }
    if (::write(out[1], problem.data(), problem.size()) < 0) ::_exit(2);
    ::_exit(0);
  }
  ::close(out[1]);
  for (int i = 0; i < 1000; ++i) {
    int status = 0;
    if (::waitpid(child, &status, WNOHANG) == child) {
      std::string problem;
      char block[512];
      for (ssize_t got; (got = ::read(out[0], block, sizeof block)) > 0;) problem.append(block, got);
      ::close(out[0]);
      return problem;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  ::close(out[0]);
  return "hung";
}

TEST(InputFile, RefusesWhatIsNotARegularFile) {
  const TempDir dir("glasspiv_input_file");
  const std::string fifo = dir.file("frame.tif"), folder = dir.file("folder"), file = dir.file("a.txt");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  ASSERT_EQ(::mkdir(folder.c_str(), 0700), 0);
  write_file_atomically(file, "x");
  EXPECT_EQ(input_file_problem(file), "");
  EXPECT_NE(input_file_problem(fifo).find("is a fifo, not a regular file"), std::string::npos);
  EXPECT_NE(input_file_problem(folder).find("is a folder"), std::string::npos);
  EXPECT_NE(input_file_problem("/dev/null").find("character device"), std::string::npos);
  EXPECT_NE(input_file_problem(dir.file("missing")).find("does not exist"), std::string::npos);
  try {
    check_input_file(fifo, "--mask");
    FAIL() << "a fifo passed";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), fifo);
    EXPECT_EQ(e.field(), "--mask");
  }
}

TEST(InputFile, NoReaderBlocksOnAFifo) {
  const TempDir dir("glasspiv_input_fifo");
  const std::string fifo = dir.file("input.tif");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::pair<const char*, std::function<void()>> readers[] = {
      {"read_file", [&] { read_file(fifo); }},
      {"BinaryFileReader", [&] { BinaryFileReader in(fifo); }},
      {"read_gray_image", [&] { read_gray_image(fifo); }},
      {"read_json_document", [&] { read_json_document(fifo); }},
  };
  for (const auto& [name, read] : readers) {
    const std::string problem = problem_within_seconds(read);
    EXPECT_NE(problem.find(fifo + ": is a fifo, not a regular file"), std::string::npos) << name << ": " << problem;
  }
  EXPECT_FALSE(image_file_size(fifo).has_value());
}

TEST(ParseInteger, NeverWrapsOrSaturates) {
  EXPECT_EQ(parse_integer<int>("2147483647"), 2147483647);
  EXPECT_FALSE(parse_integer<int>("2147483648"));
  EXPECT_FALSE(parse_integer<int>("4294967296"));  // would wrap to 0 through a 32-bit read
  EXPECT_EQ(parse_integer<int>("-2147483648"), INT32_MIN);
  EXPECT_EQ(parse_integer<std::uint64_t>("18446744073709551615"), UINT64_MAX);
  EXPECT_FALSE(parse_integer<std::uint64_t>("18446744073709551617"));  // strtoull saturates it
  EXPECT_FALSE(parse_integer<std::int64_t>("9223372036854775808"));
  EXPECT_FALSE(parse_integer<unsigned>("-1"));
  EXPECT_EQ(parse_integer<unsigned>("-0"), 0u);
  EXPECT_EQ(parse_integer<int>("+7"), 7);
  for (const char* bad : {"", "+", "-", "1.0", "1e3", "0x10", " 1", "1 ", "+-1"})
    EXPECT_FALSE(parse_integer<int>(bad)) << bad;
}

TEST(JsonDocument, NotFiniteAndMalformedTextNameTheFieldAndLineInOwnWords) {
  try {
    parse_json_document("{\n  \"covariance\": [[1, NaN]]\n}\n", "pose.json");
    FAIL() << "NaN parsed";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "pose.json");
    EXPECT_EQ(e.field(), "covariance[0][1]");
    EXPECT_NE(e.problem().find("line 2"), std::string::npos) << e.what();
    EXPECT_NE(e.problem().find("no NaN or Infinity"), std::string::npos) << e.what();
    EXPECT_EQ(e.problem().find("json.exception"), std::string::npos) << e.what();
  }
  try {
    parse_json_document("{\"a\": [1, 2", "x.json");
    FAIL() << "truncated text parsed";
  } catch (const InputError& e) {
    EXPECT_EQ(e.problem().find("json.exception"), std::string::npos) << e.what();
    EXPECT_NE(e.problem().find("ends early"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_json_document("{\"a\": 1, \"a\": 2}", "x.json"), InputError);
  EXPECT_EQ(parse_json_document("{\"a\": [1.5]}", "x.json")["a"][0].get<double>(), 1.5);
  // Invalid UTF-8 in a text written out is replaced, not an exception.
  EXPECT_NE(json_text(nlohmann::json{{"name", std::string("a\xff")}}).find("\"name\""), std::string::npos);
}

}  // namespace
}  // namespace glasspiv
