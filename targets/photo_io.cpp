#include "targets/photo_io.h"

#include <filesystem>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "util/input_error.h"

namespace glasspiv {

cv::Mat to_gray8(const cv::Mat& image) {
  cv::Mat gray;
  if (image.channels() == 1) gray = image;
  else if (image.channels() == 3) cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  else if (image.channels() == 4) cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  else return {};
  if (gray.depth() == CV_8U) return gray;
  double max = 0;
  cv::minMaxLoc(gray, nullptr, &max);
  cv::Mat out;
  gray.convertTo(out, CV_8U, max > 0 ? 255.0 / max : 1.0);
  return out;
}

cv::Mat read_photo_gray8(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "", "file does not exist");
  if (fs::is_directory(path, ec)) throw InputError(path, "", "is a folder, expected an image");
  cv::Mat image;
  try {
    image = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw InputError(path, "", std::string("cannot be read as an image: ") + e.what());
  }
  if (image.empty()) throw InputError(path, "", "cannot be read as an image (not an image, corrupt, or unreadable)");
  cv::Mat gray = to_gray8(image);
  if (gray.empty())
    throw InputError(path, "",
                     fmt::format("has {} channels; expected grey, colour or colour with alpha", image.channels()));
  return gray;
}

}  // namespace glasspiv
