#pragma once
// Gray image files through OpenImageIO: PIV recordings in (8/16-bit TIFF, PNG, or
// anything else OIIO reads) and renders out (8/16-bit or float TIFF, PNG, EXR).
// Only I/O: no resampling, no colour management. Writes are atomic
// (util/atomic_file.h). Bad files and unwritable outputs throw InputError
// naming the file; see docs/formats.md, "Images".
#include <array>
#include <cstdint>
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

// Limits on every image read here (PIV frames, textures, photos for detection),
// checked from the file's header before any pixel buffer is allocated: each side
// at most kMaxImageSidePx, width x height at most kMaxImagePixels (also for the
// tiles of a tiled file). A PNG must moreover hold enough compressed data for the
// size its header states: deflate expands at most 1032-fold, so a PNG whose IDAT
// bytes x 1032 are fewer than its rows need is refused unread. Over a limit:
// InputError(path, "", message stating the limit).
inline constexpr int kMaxImageSidePx = 65536;
inline constexpr std::int64_t kMaxImagePixels = std::int64_t(1) << 30;  // 1073741824, e.g. 32768 x 32768

// The first page of an image file as stored, reduced to grey or RGB only by
// dropping channels: `channels` is 1 (gray, or gray + alpha: the gray channel)
// or 3 (R, G, B of RGB(A...)), interleaved, row-major. uint8 and uint16 files
// fill `uint8` resp. `uint16` with the stored levels; anything else (half,
// float, the rarer integer types, which OIIO normalises) fills `float32`.
// Bad, damaged or truncated files and files over the limits above throw
// InputError naming the file; nothing is printed (decoder messages on stderr
// are silenced, the error comes back as one line).
struct StoredImage {
  int width = 0, height = 0, channels = 0;
  PixelFormat format = PixelFormat::float32;
  std::vector<std::uint8_t> uint8;
  std::vector<std::uint16_t> uint16;
  std::vector<float> float32;
};
StoredImage read_stored_image(const std::string& path);

// Any format OIIO reads, as read_stored_image; the first page of a multi-page file. RGB(A) becomes
// Rec.601 luma 0.299 R + 0.587 G + 0.114 B (as OpenCV's cvtColor), gray+alpha
// takes the gray channel; alpha is ignored.
GrayImage read_gray_image(const std::string& path);

// Width and height from an image file's header, without reading its pixels;
// std::nullopt when the file is missing or not an image OIIO opens.
std::optional<std::array<int, 2>> image_file_size(const std::string& path);

// What an image file's header says, without reading its pixels, and with
// check_end whether its last row reads back (one strip or tile of a TIFF; a
// PNG or a single-strip TIFF reads whole); std::nullopt when the file is
// missing or not an image OIIO opens.
struct ImageFileHeader {
  int width = 0, height = 0, channels = 0;
  std::string sample_type;     // as stored: "uint8", "uint16", "half", "float", "int32", ...
  std::string description;     // the file's ImageDescription ("" if none): see write_gray_image
  // With check_end, false when the file's last row (or tile) cannot be read:
  // cut short (a power loss, an interrupted copy) or damaged at its end.
  bool pixels_present = true;
};
std::optional<ImageFileHeader> read_image_file_header(const std::string& path, bool check_end = false);

// The file type comes from the extension: .tif/.tiff (uncompressed), .png, .exr
// (zip, lossless). uint8/uint16 store round(clamp(v, 0, 1) * 255 resp. 65535),
// halves up, NaN -> 0; float32 stores the values bit for bit (TIFF and EXR only).
// EXR holds no integers and PNG no floats: those combinations are refused.
// description, unless empty, is stored as the file's ImageDescription (read
// back by read_image_file_header). Throws std::invalid_argument for an empty
// image (a programming error). A file cut short while writing (a full disk, a
// file-size limit) throws InputError naming `path`, and nothing is left.
void write_gray_image(const std::string& path, const float* values, int width, int height,
                      PixelFormat format, const std::string& description = "");
void write_gray_image(const std::string& path, const GrayImage& image, PixelFormat format);

// "8"/"uint8", "16"/"uint16", "float"/"32"/"float32"; anything else throws
// InputError("", field, ...).
PixelFormat pixel_format_from_name(const std::string& name, const std::string& field);
const char* pixel_format_name(PixelFormat format);  // "uint8", "uint16", "float32"

}  // namespace glasspiv
