#pragma once
// Photos for detection: whatever util/image_file's OpenImageIO reader reads
// (JPEG, PNG, TIFF, BMP, PNM, WebP, EXR, camera raw, ...), made 8-bit grey.
#include <string>

#include <opencv2/core.hpp>

namespace glasspiv {

// 8-bit grey: colour (BGR, BGRA) becomes grey; a deeper image (16-bit, float)
// is scaled by its own maximum to 0..255 (an all-zero image stays zero).
// Returns an empty Mat for a channel count other than 1, 3, 4.
cv::Mat to_gray8(const cv::Mat& image);

// Reads a photo with read_stored_image (util/image_file.h; its size limits,
// first page, no EXIF rotation) and makes it 8-bit grey as to_gray8 does:
// colour becomes grey (BT.601 weights), gray + alpha its gray channel, a deeper
// image (16-bit, float) is scaled by its own maximum. Throws InputError naming
// `path` when it is missing, a folder, over the size limits, or not an image
// that decodes cleanly (corrupt, truncated, unknown format); prints nothing.
cv::Mat read_photo_gray8(const std::string& path);

}  // namespace glasspiv
