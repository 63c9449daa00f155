#pragma once
// Photos for detection: whatever OpenCV reads (IMREAD_UNCHANGED), made 8-bit grey.
#include <string>

#include <opencv2/core.hpp>

namespace glasspiv {

// 8-bit grey: colour (BGR, BGRA) becomes grey; a deeper image (16-bit, float)
// is scaled by its own maximum to 0..255 (an all-zero image stays zero).
// Returns an empty Mat for a channel count other than 1, 3, 4.
cv::Mat to_gray8(const cv::Mat& image);

// Reads a photo with cv::imread(IMREAD_UNCHANGED) and makes it 8-bit grey.
// Throws InputError naming `path` when it is missing, a folder, or not an image
// OpenCV can decode (corrupt, truncated, unknown format).
cv::Mat read_photo_gray8(const std::string& path);

}  // namespace glasspiv
