#pragma once
// A picture (8-bit grey or BGR cv::Mat) written as PNG, atomically: the one
// PNG writer of the commands and the demo.
#include <string>

#include <opencv2/core.hpp>

namespace glasspiv {

// Throws InputError(path, "", "cannot write the PNG") when OpenCV cannot.
void write_png(const std::string& path, const cv::Mat& image);

}  // namespace glasspiv
