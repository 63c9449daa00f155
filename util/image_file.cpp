#include "util/image_file.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <mutex>
#include <utility>

#include <fcntl.h>
#include <unistd.h>

#include <fmt/format.h>
#include <OpenImageIO/imageio.h>

#include "util/atomic_file.h"
#include "util/input_error.h"
#include "util/input_file.h"

namespace glasspiv {
namespace fs = std::filesystem;

namespace {

// OIIO joins several errors with newlines (a truncated TIFF gives one per
// strip); an InputError is printed as one line: the first error and a count.
std::string one_line(const std::string& text) {
  std::istringstream lines(text);
  std::string line, first;
  int more = 0;
  while (std::getline(lines, line)) {
    line.erase(std::remove(line.begin(), line.end(), '\r'), line.end());
    if (line.empty()) continue;
    if (first.empty())
      first = line;
    else
      ++more;
  }
  return more == 0 ? first : first + " (and " + std::to_string(more) + " more errors)";
}

// `temporary`: the file OIIO was writing; its messages name it, the user knows `path`.
[[noreturn]] void fail(const std::string& path, const std::string& oiio_error, const char* fallback,
                       const std::string& temporary = "") {
  std::string message = one_line(oiio_error);
  for (std::size_t at; !temporary.empty() && (at = message.find(temporary)) != std::string::npos;)
    message.replace(at, temporary.size(), path);
  throw InputError(path, "", message.empty() ? fallback : message);
}

// libpng (as OpenImageIO 2.4 drives it) prints "libpng error: ..." to stderr
// besides reporting the error to OIIO, and other decoders may do likewise; the
// command line's only output for a bad file must be its one-line InputError.
// While an image file is opened or read, file descriptor 2 points to /dev/null
// (OIIO's error strings carry the message). Nested and concurrent reads share
// one redirection; glasspiv prints nothing from other threads while reading.
class QuietStderr {
 public:
  QuietStderr() {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (depth_++ > 0) return;
    std::fflush(stderr);
    const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (null < 0) return;
    saved_ = ::fcntl(STDERR_FILENO, F_DUPFD_CLOEXEC, 3);
    if (saved_ >= 0 && ::dup2(null, STDERR_FILENO) < 0) {
      ::close(saved_);
      saved_ = -1;
    }
    ::close(null);
  }
  ~QuietStderr() {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (--depth_ > 0 || saved_ < 0) return;
    std::fflush(stderr);
    ::dup2(saved_, STDERR_FILENO);
    ::close(saved_);
    saved_ = -1;
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  static inline std::mutex mutex_;
  static inline int depth_ = 0;
  static inline int saved_ = -1;
};

// The one size check of every read, from the header: before any pixel buffer.
void check_size_limits(const std::string& path, std::int64_t width, std::int64_t height, const char* what) {
  if (width <= kMaxImageSidePx && height <= kMaxImageSidePx && width * height <= kMaxImagePixels) return;
  throw InputError(path, "",
                   fmt::format("{} {} x {} px, over the limit of {} px a side and {} px in all", what, width,
                               height, kMaxImageSidePx, kMaxImagePixels));
}

std::uint32_t big_endian_32(const unsigned char* b) {
  return (std::uint32_t{b[0]} << 24) | (std::uint32_t{b[1]} << 16) | (std::uint32_t{b[2]} << 8) | b[3];
}

// A PNG's own header, checked before OIIO (libpng) sees the file, by walking
// the chunk headers (a few hundred 8-byte reads, not a pass over the pixels):
// truncation (the usual damage: an interrupted copy) is named as such, and a
// header claiming more pixels than the limits, or than its compressed data can
// hold (deflate expands at most 1032-fold), is refused before anything is
// allocated for the pixels. Anything else wrong is left to OIIO.
void check_png_header(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) return;  // OIIO says why
  std::setvbuf(file.get(), nullptr, _IONBF, 0);  // headers only: don't buffer the data between them
  static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  unsigned char header[8];
  if (std::fread(header, 1, 8, file.get()) != 8 || std::memcmp(header, signature, 8) != 0) return;
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) return;
  std::uintmax_t chunk = 8;  // length (4 bytes, big-endian), type (4), data, CRC (4)
  std::uintmax_t idat_bytes = 0;
  std::uint32_t width = 0, height = 0;
  int bit_depth = 0, colour_type = -1;
  for (;;) {
    if (chunk + 8 > size || std::fseek(file.get(), static_cast<long>(chunk), SEEK_SET) != 0 ||
        std::fread(header, 1, 8, file.get()) != 8)
      break;
    const std::uint32_t length = big_endian_32(header);
    if (chunk == 8 && std::memcmp(header + 4, "IHDR", 4) == 0 && length == 13) {
      unsigned char ihdr[13];
      if (std::fread(ihdr, 1, 13, file.get()) != 13) break;
      width = big_endian_32(ihdr);
      height = big_endian_32(ihdr + 4);
      bit_depth = ihdr[8];
      colour_type = ihdr[9];
    }
    if (std::memcmp(header + 4, "IDAT", 4) == 0) idat_bytes += length;
    chunk += 12 + std::uintmax_t{length};
    if (chunk > size) break;
    if (std::memcmp(header + 4, "IEND", 4) != 0) continue;
    if (colour_type < 0) return;  // no IHDR first: OIIO says what is wrong
    check_size_limits(path, width, height, "the PNG header states");
    const int samples = colour_type == 2 ? 3 : colour_type == 4 ? 2 : colour_type == 6 ? 4 : 1;
    // Non-interlaced size (an interlaced stream is larger): a filter byte per row.
    const std::uintmax_t needed =
        std::uintmax_t{height} * (1 + (std::uintmax_t{width} * samples * bit_depth + 7) / 8);
    if (needed > 1032 * idat_bytes)
      throw InputError(path, "",
                       fmt::format("the PNG header states {} x {} px, {} bytes of image data, but its {} compressed "
                                   "bytes can hold at most {} (deflate expands at most 1032-fold): damaged file",
                                   width, height, needed, idat_bytes, 1032 * idat_bytes));
    return;
  }
  throw InputError(path, "", "truncated PNG file (it ends before its IEND chunk)");
}

// Opens `path` for reading, refused past the limits before anything is read
// beyond the header. The caller holds a QuietStderr.
std::unique_ptr<OIIO::ImageInput> open_checked(const std::string& path) {
  check_input_file(path);  // a regular file: a fifo or a device is refused, never opened
  check_png_header(path);

  OIIO::ImageSpec config;
  // PNG and TIFF store colour unassociated with alpha; OIIO would multiply it by
  // alpha on reading, but alpha is ignored here, so keep the colour as stored.
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) fail(path, OIIO::geterror(), "not an image file OpenImageIO can read");
  in->geterror();  // errors OIIO noted but opened anyway are not fatal; those of reading the pixels are
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.deep) throw InputError(path, "", "deep images are not supported");
  if (spec.depth != 1) throw InputError(path, "", "volume images (depth > 1) are not supported");
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    throw InputError(path, "", "the image is empty");
  check_size_limits(path, spec.width, spec.height, "the image is");
  if (spec.tile_width > 0) check_size_limits(path, spec.tile_width, spec.tile_height, "its tiles are");
  return in;
}

// Reads the first `channels` channels of subimage 0 as T.
template <typename T>
std::vector<T> read_stored(OIIO::ImageInput& in, const std::string& path, int channels) {
  const std::size_t count = std::size_t(in.spec().width) * std::size_t(in.spec().height);
  std::vector<T> stored(count * std::size_t(channels));
  // OIIO 2.4 reports a truncated TIFF's unreadable strips, and a truncated
  // JPEG, as errors but still returns true, with those rows left unset (resp.
  // grey): check both.
  if (!in.read_image(0, 0, 0, channels, OIIO::TypeDesc(OIIO::BaseTypeFromC<T>::value), stored.data()) ||
      in.has_error())
    fail(path, in.geterror(), "cannot read the pixels");
  return stored;
}

// Gray from stored samples. OIIO's own conversion to float multiplies by 1/255
// resp. 1/65535 and misses the float nearest k / 65535 by one ulp for some
// levels; reading the stored integers and dividing here gets every level
// exactly, and is no slower.
template <typename T>
std::vector<float> gray_of(const std::vector<T>& stored, int channels, float full_scale) {
  const std::size_t count = stored.size() / std::size_t(channels);
  const auto value = [full_scale](T v) { return static_cast<float>(v) / full_scale; };
  std::vector<float> gray(count);
  if (channels == 1) {
    for (std::size_t i = 0; i < count; ++i) gray[i] = value(stored[i]);
  } else {
    for (std::size_t i = 0; i < count; ++i) {
      const T* rgb = &stored[3 * i];
      gray[i] = 0.299f * value(rgb[0]) + 0.587f * value(rgb[1]) + 0.114f * value(rgb[2]);
    }
  }
  return gray;
}

enum class FileType { tiff, png, exr };

FileType file_type_for_writing(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".tif" || extension == ".tiff") return FileType::tiff;
  if (extension == ".png") return FileType::png;
  if (extension == ".exr") return FileType::exr;
  throw InputError(path, "",
                   (extension.empty() ? std::string("the file name has no image extension")
                                      : "unsupported image extension '" + extension + "'") +
                       " (use .tif, .png or .exr)");
}

// round(clamp(v, 0, 1) * max), halves up, NaN -> 0. v * max is exact in double
// (24 + 16 significant bits), so the truncation of v * max + 0.5 rounds exactly.
template <typename T>
std::vector<T> quantised(const float* values, std::size_t count) {
  constexpr double max = std::numeric_limits<T>::max();
  std::vector<T> levels(count);
  for (std::size_t i = 0; i < count; ++i) {
    const double v = values[i] > 0 ? std::min(double(values[i]), 1.0) : 0.0;  // NaN fails "> 0"
    levels[i] = static_cast<T>(v * max + 0.5);
  }
  return levels;
}

}  // namespace

StoredImage read_stored_image(const std::string& path) {
  const QuietStderr quiet;
  const auto in = open_checked(path);
  const OIIO::ImageSpec& spec = in->spec();
  StoredImage image;
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.nchannels >= 3 ? 3 : 1;  // RGB(A...) -> RGB; gray(+alpha) -> gray
  switch (spec.format.basetype) {
    case OIIO::TypeDesc::UINT8:
      image.format = PixelFormat::uint8;
      image.uint8 = read_stored<std::uint8_t>(*in, path, image.channels);
      break;
    case OIIO::TypeDesc::UINT16:
      image.format = PixelFormat::uint16;
      image.uint16 = read_stored<std::uint16_t>(*in, path, image.channels);
      break;
    default:  // float, half, and the rarer integer types, which OIIO normalises
      image.format = PixelFormat::float32;
      image.float32 = read_stored<float>(*in, path, image.channels);
      break;
  }
  in->close();
  return image;
}

GrayImage read_gray_image(const std::string& path) {
  StoredImage stored = read_stored_image(path);
  GrayImage image;
  image.width = stored.width;
  image.height = stored.height;
  image.source_format = stored.format;
  switch (stored.format) {
    case PixelFormat::uint8: image.values = gray_of(stored.uint8, stored.channels, 255.0f); break;
    case PixelFormat::uint16: image.values = gray_of(stored.uint16, stored.channels, 65535.0f); break;
    case PixelFormat::float32:
      image.values = stored.channels == 1 ? std::move(stored.float32) : gray_of(stored.float32, stored.channels, 1.0f);
      break;
  }
  return image;
}

std::optional<std::array<int, 2>> image_file_size(const std::string& path) {
  const auto header = read_image_file_header(path);
  if (!header) return std::nullopt;
  return std::array<int, 2>{header->width, header->height};
}

std::optional<ImageFileHeader> read_image_file_header(const std::string& path, bool check_end) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return std::nullopt;
  const std::uintmax_t file_bytes = fs::file_size(path, ec);
  if (ec) return std::nullopt;
  const QuietStderr quiet;  // libpng prints a damaged header's error
  const auto in = OIIO::ImageInput::open(path);
  if (!in) {
    OIIO::geterror();  // clear it
    return std::nullopt;
  }
  const OIIO::ImageSpec& spec = in->spec();
  ImageFileHeader h;
  h.width = spec.width;
  h.height = spec.height;
  h.channels = spec.nchannels;
  switch (spec.format.basetype) {
    case OIIO::TypeDesc::UINT8: h.sample_type = "uint8"; break;
    case OIIO::TypeDesc::INT8: h.sample_type = "int8"; break;
    case OIIO::TypeDesc::UINT16: h.sample_type = "uint16"; break;
    case OIIO::TypeDesc::INT16: h.sample_type = "int16"; break;
    case OIIO::TypeDesc::UINT32: h.sample_type = "uint32"; break;
    case OIIO::TypeDesc::INT32: h.sample_type = "int32"; break;
    case OIIO::TypeDesc::UINT64: h.sample_type = "uint64"; break;
    case OIIO::TypeDesc::INT64: h.sample_type = "int64"; break;
    case OIIO::TypeDesc::HALF: h.sample_type = "half"; break;
    case OIIO::TypeDesc::FLOAT: h.sample_type = "float"; break;
    case OIIO::TypeDesc::DOUBLE: h.sample_type = "double"; break;
    default: h.sample_type = spec.format.c_str(); break;
  }
  h.description = spec.get_string_attribute("ImageDescription");
  // The last row (or tile) read back: a file cut short loses its end, and
  // the pixels come last in a file (as OIIO writes TIFF: the directory first).
  // Reading one strip or tile is cheap next to the frame.
  if (check_end && spec.width > 0 && spec.height > 0 && file_bytes > 0) {
    std::vector<unsigned char> buffer;
    bool read = false;
    if (spec.tile_width > 0) {
      buffer.resize(spec.tile_bytes(true));
      read = in->read_tile(spec.x + ((spec.width - 1) / spec.tile_width) * spec.tile_width,
                           spec.y + ((spec.height - 1) / spec.tile_height) * spec.tile_height, spec.z,
                           OIIO::TypeDesc::UNKNOWN, buffer.data());
    } else {
      buffer.resize(spec.scanline_bytes(true));
      read = in->read_scanline(spec.y + spec.height - 1, spec.z, OIIO::TypeDesc::UNKNOWN, buffer.data());
    }
    h.pixels_present = read && !in->has_error();
    in->geterror();  // clear it
  }
  return h;
}

void write_gray_image(const std::string& path, const float* values, int width, int height,
                      PixelFormat format, const std::string& description) {
  if (values == nullptr || width <= 0 || height <= 0)
    throw std::invalid_argument("write_gray_image: empty image for " + path);
  const FileType type = file_type_for_writing(path);
  if (type == FileType::png && format == PixelFormat::float32)
    throw InputError(path, "", "PNG cannot hold float32 pixels (write .tif or .exr, or uint8/uint16)");
  if (type == FileType::exr && format != PixelFormat::float32)
    throw InputError(path, "",
                     std::string("EXR holds half/float pixels only, not ") + pixel_format_name(format) +
                         " (write float32, or .tif or .png)");

  const std::size_t count = std::size_t(width) * std::size_t(height);
  std::vector<std::uint8_t> levels8;
  std::vector<std::uint16_t> levels16;
  const void* pixels = values;
  OIIO::TypeDesc stored = OIIO::TypeDesc::FLOAT;
  if (format == PixelFormat::uint8) {
    levels8 = quantised<std::uint8_t>(values, count);
    pixels = levels8.data();
    stored = OIIO::TypeDesc::UINT8;
  } else if (format == PixelFormat::uint16) {
    levels16 = quantised<std::uint16_t>(values, count);
    pixels = levels16.data();
    stored = OIIO::TypeDesc::UINT16;
  }

  OIIO::ImageSpec spec(width, height, 1, stored);
  // Uncompressed TIFF reads everywhere and writes ~50x faster than zip, which
  // saves only about a quarter on noisy 16-bit recordings. EXR: zip, lossless.
  if (type == FileType::tiff) spec.attribute("compression", "none");
  if (type == FileType::exr) spec.attribute("compression", "zip");
  if (!description.empty()) spec.attribute("ImageDescription", description);

  write_file_atomically_with(path, [&](const std::string& temporary) {
    const auto out = OIIO::ImageOutput::create(temporary);
    if (!out) fail(path, OIIO::geterror(), "OpenImageIO cannot write this file type", temporary);
    errno = 0;
    if (!out->open(temporary, spec) || !out->write_image(stored, pixels) || !out->close())
      fail(path, out->geterror(), errno ? std::strerror(errno) : "cannot write the image", temporary);
    // libtiff does not report every failed write (its last flush happens in a
    // function without a result): a file cut short by a full disk or a file-size
    // limit is caught here, before it is renamed into place.
    std::error_code ec;
    const std::uintmax_t written = fs::file_size(temporary, ec);
    if (type == FileType::tiff && (ec || written < std::uintmax_t(spec.image_bytes())))
      throw InputError(path, "",
                       fmt::format("cannot write the image: the file holds {} bytes, fewer than its {} bytes of pixels "
                                   "(disk full or a file-size limit?)",
                                   ec ? 0 : written, spec.image_bytes()));
  });
}

void write_gray_image(const std::string& path, const GrayImage& image, PixelFormat format) {
  if (image.values.size() != std::size_t(image.width) * std::size_t(image.height) || image.width <= 0 ||
      image.height <= 0)
    throw std::invalid_argument("write_gray_image: GrayImage values do not match its size, for " + path);
  write_gray_image(path, image.values.data(), image.width, image.height, format);
}

PixelFormat pixel_format_from_name(const std::string& name, const std::string& field) {
  if (name == "8" || name == "uint8") return PixelFormat::uint8;
  if (name == "16" || name == "uint16") return PixelFormat::uint16;
  if (name == "float" || name == "32" || name == "float32") return PixelFormat::float32;
  throw InputError("", field, "unknown pixel format '" + name + "' (use 8, 16 or float)");
}

const char* pixel_format_name(PixelFormat format) {
  switch (format) {
    case PixelFormat::uint8: return "uint8";
    case PixelFormat::uint16: return "uint16";
    case PixelFormat::float32: return "float32";
  }
  return "unknown";
}

}  // namespace glasspiv
