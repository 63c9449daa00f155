// Photos into 8-bit grey: 16-bit scaled by the image's own maximum, colour to
// grey, unreadable files named.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "targets/photo_io.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

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

}  // namespace
}  // namespace glasspiv
