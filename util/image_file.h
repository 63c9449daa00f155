#pragma once
// Gray image files through OpenImageIO: PIV recordings in (8/16-bit TIFF, PNG, or
// anything else OIIO reads) and renders out (8/16-bit or float TIFF, PNG, EXR).
// Only I/O: no resampling, no colour management. Writes are atomic
// (util/atomic_file.h). Bad files and unwritable outputs throw InputError
// naming the file; see docs/formats.md, "Images".
#include <array>
#include <optional>
#include <string>
#include <vector>

namespace glasspiv {

enum class PixelFormat { uint8, uint16, float32 };

struct GrayImage {  // single channel, row-major
  int width = 0, height = 0;
  // Integer files normalised to [0, 1]: the level k reads as the float nearest
  // k / 255 resp. k / 65535. Float files as stored (negative, > 1, NaN kept).
  std::vector<float> values;
  PixelFormat source_format = PixelFormat::float32;  // what the file held (half -> float32)
};

// Any format OIIO reads; the first page of a multi-page file. RGB(A) becomes
// Rec.601 luma 0.299 R + 0.587 G + 0.114 B (as OpenCV's cvtColor), gray+alpha
// takes the gray channel; alpha is ignored.
GrayImage read_gray_image(const std::string& path);

// Width and height from an image file's header, without reading its pixels;
// std::nullopt when the file is missing or not an image OIIO opens (how a rerun
// of a series tells a frame already written: outputs are atomic, so a file
// under its final name is complete).
std::optional<std::array<int, 2>> image_file_size(const std::string& path);

// The file type comes from the extension: .tif/.tiff (uncompressed), .png, .exr
// (zip, lossless). uint8/uint16 store round(clamp(v, 0, 1) * 255 resp. 65535),
// halves up, NaN -> 0; float32 stores the values bit for bit (TIFF and EXR only).
// EXR holds no integers and PNG no floats: those combinations are refused.
// Throws std::invalid_argument for an empty image (a programming error).
void write_gray_image(const std::string& path, const float* values, int width, int height,
                      PixelFormat format);
void write_gray_image(const std::string& path, const GrayImage& image, PixelFormat format);

// "8"/"uint8", "16"/"uint16", "float"/"32"/"float32"; anything else throws
// InputError("", field, ...).
PixelFormat pixel_format_from_name(const std::string& name, const std::string& field);
const char* pixel_format_name(PixelFormat format);  // "uint8", "uint16", "float32"

}  // namespace glasspiv
