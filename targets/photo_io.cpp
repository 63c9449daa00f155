#include "targets/photo_io.h"

#include <filesystem>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "util/image_file.h"
#include "util/input_error.h"
#include "util/input_file.h"

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
  check_input_file(path);  // a regular file (a fifo would block the reader)
  // util/image_file's reader, as for PIV frames: the size limits are checked
  // from the header, damaged or truncated files are refused, nothing is printed.
  StoredImage stored;
  try {
    stored = read_stored_image(path);
  } catch (const InputError& e) {
    throw InputError(path, "", "cannot be read as an image: " + e.problem());
  }
  void* data = nullptr;
  int depth = CV_8U;
  switch (stored.format) {
    case PixelFormat::uint8: data = stored.uint8.data(); depth = CV_8U; break;
    case PixelFormat::uint16: data = stored.uint16.data(); depth = CV_16U; break;
    case PixelFormat::float32: data = stored.float32.data(); depth = CV_32F; break;
  }
  if (stored.channels != 1 && stored.channels != 3)  // read_stored_image gives 1 or 3
    throw InputError(path, "", fmt::format("has {} channels; expected grey or colour", stored.channels));
  // A view of the stored samples; the result below owns its own copy.
  const cv::Mat view(stored.height, stored.width, CV_MAKETYPE(depth, stored.channels), data);
  cv::Mat gray;
  if (stored.channels == 3) cv::cvtColor(view, gray, cv::COLOR_RGB2GRAY);  // OIIO gives R, G, B
  else gray = view;
  gray = to_gray8(gray);
  return gray.data == view.data ? gray.clone() : gray;
}

}  // namespace glasspiv
