#include "apps/png_file.h"

#include <opencv2/imgcodecs.hpp>

#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {

void write_png(const std::string& path, const cv::Mat& image) {
  write_file_atomically_with(path, [&](const std::string& tmp) {
    if (!cv::imwrite(tmp, image, {cv::IMWRITE_PNG_COMPRESSION, 3})) throw InputError(path, "", "cannot write the PNG");
  });
}

}  // namespace glasspiv
