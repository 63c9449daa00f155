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

#include "tests/hand_made_images.h"
#include "targets/photo_io.h"
#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;


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
