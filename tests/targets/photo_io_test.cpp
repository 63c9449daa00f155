// Photos into 8-bit grey: 16-bit scaled by the image's own maximum, colour to
// grey, unreadable files named.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <unistd.h>
#include <opencv2/imgcodecs.hpp>

#include "targets/photo_io.h"
#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

// Hand-made files: a PNG or a baseline TIFF (8-bit gray) whose header states any size.
std::uint32_t crc32_of(const std::string& bytes) {
  std::uint32_t crc = 0xffffffffu;
  for (unsigned char c : bytes) {
    crc ^= c;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}
std::string big_endian(std::uint32_t v) { return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; }
std::string png_chunk(const std::string& type, const std::string& data) {
  return big_endian(std::uint32_t(data.size())) + type + data + big_endian(crc32_of(type + data));
}
std::string png_claiming(std::uint32_t width, std::uint32_t height) {
  const std::string ihdr = big_endian(width) + big_endian(height) + std::string{8, 0, 0, 0, 0};
  const std::string idat("\x78\x9c\x63\x00\x00\x00\x01\x00\x01", 9);  // zlib of one zero byte
  return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", idat) +
         png_chunk("IEND", "");
}
std::string little_endian(std::uint32_t v, int bytes) {
  std::string s;
  for (int i = 0; i < bytes; ++i) s += char(v >> (8 * i));
  return s;
}
std::string tiff_claiming(std::uint32_t width, std::uint32_t height) {
  const std::string data(16, '\0');
  const std::vector<std::pair<std::uint16_t, std::uint32_t>> longs = {
      {256, width}, {257, height}, {273, 8}, {278, height}, {279, std::uint32_t(data.size())}};
  const std::vector<std::pair<std::uint16_t, std::uint32_t>> shorts = {{258, 8}, {259, 1}, {262, 1}, {277, 1}};
  std::vector<std::string> entries;  // TIFF wants them sorted by tag
  for (const auto& [tag, v] : longs) entries.push_back(little_endian(tag, 2) + little_endian(4, 2) + little_endian(1, 4) + little_endian(v, 4));
  for (const auto& [tag, v] : shorts)
    entries.push_back(little_endian(tag, 2) + little_endian(3, 2) + little_endian(1, 4) + little_endian(v, 2) + std::string(2, '\0'));
  std::sort(entries.begin(), entries.end(), [](const std::string& a, const std::string& b) {
    return (std::uint8_t(a[1]) << 8 | std::uint8_t(a[0])) < (std::uint8_t(b[1]) << 8 | std::uint8_t(b[0]));
  });
  std::string tiff = std::string("II*\0", 4) + little_endian(8 + std::uint32_t(data.size()), 4) + data +
                     little_endian(std::uint32_t(entries.size()), 2);
  for (const std::string& e : entries) tiff += e;
  return tiff + little_endian(0, 4);
}
void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// Expects an InputError naming `path`, on one line; returns its message.
std::string input_error_of(const std::string& path) {
  try {
    read_photo_gray8(path);
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError for " << path;
  return "";
}

TEST(ToGray8, SixteenBitScaledByItsOwnMaximum) {
  cv::Mat deep(2, 3, CV_16UC1, cv::Scalar(0));
  deep.at<unsigned short>(0, 0) = 4000;  // a 12-bit camera's brightest pixel
  deep.at<unsigned short>(1, 2) = 1000;
  const cv::Mat gray = to_gray8(deep);
  ASSERT_EQ(gray.type(), CV_8UC1);
  EXPECT_EQ(gray.at<unsigned char>(0, 0), 255);
  EXPECT_EQ(gray.at<unsigned char>(1, 2), 64);  // 1000 * 255 / 4000 = 63.75, rounded
  EXPECT_EQ(gray.at<unsigned char>(0, 1), 0);
  EXPECT_EQ(cv::countNonZero(to_gray8(cv::Mat(2, 2, CV_16UC1, cv::Scalar(0)))), 0);  // all zero stays zero
}

TEST(ToGray8, ColourAndEightBit) {
  const cv::Mat bgr(1, 1, CV_8UC3, cv::Scalar(10, 100, 200));
  const cv::Mat gray = to_gray8(bgr);
  ASSERT_EQ(gray.type(), CV_8UC1);
  EXPECT_NEAR(gray.at<unsigned char>(0, 0), 0.114 * 10 + 0.587 * 100 + 0.299 * 200, 1.0);  // BT.601 weights
  const cv::Mat eight(2, 2, CV_8UC1, cv::Scalar(77));
  EXPECT_EQ(cv::norm(to_gray8(eight), eight, cv::NORM_INF), 0);  // unchanged
  EXPECT_TRUE(to_gray8(cv::Mat(1, 1, CV_8UC2)).empty());
}

TEST(ReadPhoto, SixteenBitPngAndErrorsNamingTheFile) {
  const fs::path dir = fs::temp_directory_path() / "glasspiv_targets_photo_test";
  fs::create_directories(dir);
  cv::Mat deep(4, 4, CV_16UC1, cv::Scalar(500));
  deep.at<unsigned short>(2, 2) = 2000;
  const std::string png = (dir / "deep.png").string();
  ASSERT_TRUE(cv::imwrite(png, deep));
  const cv::Mat gray = read_photo_gray8(png);
  EXPECT_EQ(gray.at<unsigned char>(2, 2), 255);
  EXPECT_EQ(gray.at<unsigned char>(0, 0), 64);  // 500 * 255 / 2000 = 63.75

  const std::string corrupt = (dir / "corrupt.png").string();
  std::ofstream(corrupt) << "not a png";
  for (const std::string& path : {corrupt, (dir / "missing.png").string(), dir.string()}) {
    try {
      read_photo_gray8(path);
      ADD_FAILURE() << path;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path);
    }
  }
  fs::remove_all(dir);
}

TEST(ReadPhoto, ColourIsReadAsRgbAndMadeGrey) {
  const fs::path dir = fs::temp_directory_path() / ("glasspiv_targets_photo_colour_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const cv::Mat red(2, 2, CV_8UC3, cv::Scalar(0, 0, 255));  // OpenCV's BGR: pure red
  const std::string png = (dir / "red.png").string();
  ASSERT_TRUE(cv::imwrite(png, red));
  const cv::Mat gray = read_photo_gray8(png);
  ASSERT_EQ(gray.type(), CV_8UC1);
  EXPECT_EQ(gray.at<unsigned char>(1, 1), 76);  // 0.299 * 255: red's weight, not blue's (29)
  fs::remove_all(dir);
}

// The files: headers claiming 100000 x 100000 px (cv::imread went to
// ~10 GB), a truncated JPEG (accepted, its lower part grey), damaged PNGs
// (libpng lines on stderr). Each is now one InputError and nothing printed.
TEST(ReadPhoto, OversizedTruncatedAndDamagedPhotosAreRefusedSilently) {
  const fs::path dir = fs::temp_directory_path() / ("glasspiv_targets_photo_bad_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto file = [&](const std::string& name) { return (dir / name).string(); };
  write_bytes(file("huge.png"), png_claiming(100000, 100000));
  write_bytes(file("huge.tif"), tiff_claiming(100000, 100000));
  write_bytes(file("short.png"), png_claiming(64, 64));  // valid chunks, too little pixel data

  cv::Mat photo(120, 160, CV_8UC1);
  cv::randu(photo, 0, 256);
  ASSERT_TRUE(cv::imwrite(file("whole.jpg"), photo));
  const std::string jpeg = read_file(file("whole.jpg"));
  write_bytes(file("cut.jpg"), jpeg.substr(0, jpeg.size() / 2));
  ASSERT_TRUE(cv::imwrite(file("whole.png"), photo));
  std::string png = read_file(file("whole.png"));
  write_bytes(file("cut.png"), png.substr(0, png.size() / 2));
  const std::size_t idat = png.find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  for (std::size_t i = idat + 10; i < idat + 40; ++i) png[i] = char(png[i] ^ 0x5a);
  write_bytes(file("damaged.png"), png);
  EXPECT_EQ(cv::norm(read_photo_gray8(file("whole.png")), photo, cv::NORM_INF), 0);
  EXPECT_EQ(read_photo_gray8(file("whole.jpg")).size(), photo.size());

  ::testing::internal::CaptureStderr();
  for (const std::string name : {"huge.png", "huge.tif"}) {
    const std::string message = input_error_of(file(name));
    EXPECT_NE(message.find("over the limit of 65536 px a side and 1073741824 px in all"), std::string::npos)
        << message;
  }
  for (const std::string name : {"cut.jpg", "cut.png", "damaged.png", "short.png"}) {
    SCOPED_TRACE(name);
    input_error_of(file(name));
  }
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace glasspiv
