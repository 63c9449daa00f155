#include "tests/hand_made_images.h"
#include "util/image_file.h"

#include <algorithm>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <OpenImageIO/half.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

std::uint32_t bits_of(float v) {
  std::uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  return bits;
}

// The largest float f with f * full_scale < level + 0.5, and the next float up:
// the two sides of the rounding boundary. f * full_scale is exact in double.
std::pair<float, float> around_half(int level, double full_scale) {
  const double half = level + 0.5;
  float f = static_cast<float>(half / full_scale);
  while (double(f) * full_scale >= half) f = std::nextafter(f, 0.0f);
  while (double(std::nextafter(f, 2.0f)) * full_scale < half) f = std::nextafter(f, 2.0f);
  return {f, std::nextafter(f, 2.0f)};
}

// Expects an InputError naming `path`, on one line; returns its message.
template <typename Action>
std::string input_error_of(const std::string& path, Action&& action) {
  try {
    action();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError for " << path;
  return "";
}


class ImageFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("glasspiv-image-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::set<std::string> files() const {
    std::set<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) names.insert(entry.path().filename().string());
    return names;
  }

  // Writes an image with OIIO itself, for layouts write_gray_image never produces.
  template <typename T>
  void write_with_oiio(const std::string& file, int width, int height, int channels,
                       const std::vector<T>& pixels) const {
    const OIIO::TypeDesc type(OIIO::BaseTypeFromC<T>::value);
    const auto out = OIIO::ImageOutput::create(file);
    ASSERT_TRUE(out) << OIIO::geterror();
    OIIO::ImageSpec spec(width, height, channels, type);
    spec.attribute("oiio:UnassociatedAlpha", 1);  // else OIIO divides the colour by alpha on writing
    ASSERT_TRUE(out->open(file, spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(type, pixels.data())) << out->geterror();
    ASSERT_TRUE(out->close()) << out->geterror();
  }

  fs::path dir_;
};

TEST_F(ImageFileTest, EveryIntegerLevelRoundTripsExactlyThroughTiffAndPng) {
  std::mt19937 rng(1);
  // Every level once, shuffled; non-square so a swapped width and height shows.
  struct Case { PixelFormat format; int width, height; float full_scale; };
  for (const Case& c : {Case{PixelFormat::uint8, 32, 8, 255.0f}, Case{PixelFormat::uint16, 512, 128, 65535.0f}}) {
    std::vector<int> levels(std::size_t(c.width) * c.height);
    std::iota(levels.begin(), levels.end(), 0);
    std::shuffle(levels.begin(), levels.end(), rng);
    GrayImage written;
    written.width = c.width;
    written.height = c.height;
    for (int level : levels) written.values.push_back(float(level) / c.full_scale);
    for (const std::string name : {"levels.tif", "levels.png"}) {
      SCOPED_TRACE(name + " " + pixel_format_name(c.format));
      write_gray_image(path(name), written, c.format);
      const GrayImage read = read_gray_image(path(name));
      EXPECT_EQ(read.width, c.width);
      EXPECT_EQ(read.height, c.height);
      EXPECT_EQ(read.source_format, c.format);
      ASSERT_EQ(read.values.size(), written.values.size());
      std::size_t mismatches = 0;
      for (std::size_t i = 0; i < levels.size(); ++i) mismatches += read.values[i] != written.values[i];
      EXPECT_EQ(mismatches, 0u);
    }
  }
  EXPECT_EQ(files(), (std::set<std::string>{"levels.tif", "levels.png"}));  // no temporaries left
}

TEST_F(ImageFileTest, Float32RoundTripsBitExactlyThroughTiffAndExr) {
  std::vector<float> values = {-0.0f, std::numeric_limits<float>::denorm_min(), -1e-30f, 1.5f, -0.25f,
                               std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest(),
                               std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                               std::numeric_limits<float>::quiet_NaN()};
  std::mt19937 rng(7);
  std::normal_distribution<float> spread(0.0f, 100.0f);
  const int width = 48, height = 20;
  while (values.size() < std::size_t(width) * height) values.push_back(spread(rng));
  // Upper-case extensions pick the file type too.
  for (const std::string name : {"render.tif", "render.TIFF", "render.exr"}) {
    SCOPED_TRACE(name);
    write_gray_image(path(name), values.data(), width, height, PixelFormat::float32);
    const GrayImage read = read_gray_image(path(name));
    EXPECT_EQ(read.width, width);
    EXPECT_EQ(read.height, height);
    EXPECT_EQ(read.source_format, PixelFormat::float32);
    ASSERT_EQ(read.values.size(), values.size());
    for (std::size_t i = 0; i < values.size(); ++i)
      ASSERT_EQ(bits_of(read.values[i]), bits_of(values[i])) << "pixel " << i << ": " << values[i];
  }
}

TEST_F(ImageFileTest, HalfExrReadsAsFloat32) {
  // Values a half holds exactly, so they must come back unchanged.
  const std::vector<float> values = {0.5f, -2.0f, 1024.0f, 0.125f, 65504.0f, -0.0009765625f};
  std::vector<Imath::half> halves(values.begin(), values.end());
  write_with_oiio(path("half.exr"), 3, 2, 1, halves);
  const GrayImage read = read_gray_image(path("half.exr"));
  EXPECT_EQ(read.source_format, PixelFormat::float32);
  EXPECT_EQ(read.values, values);
}

TEST_F(ImageFileTest, IntegerWritesClampAndRoundHalvesUp) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (const auto& [format, full_scale] : {std::pair{PixelFormat::uint8, 255}, std::pair{PixelFormat::uint16, 65535}}) {
    SCOPED_TRACE(pixel_format_name(format));
    const auto [below_first, above_first] = around_half(0, full_scale);
    const auto [below_last, above_last] = around_half(full_scale - 1, full_scale);
    const std::vector<std::pair<float, int>> cases = {
        {-0.5f, 0}, {1.5f, full_scale}, {nan, 0}, {inf, full_scale}, {-inf, 0},
        {0.5f, (full_scale + 1) / 2},  // 127.5 resp. 32767.5 exactly: the half goes up
        {below_first, 0}, {above_first, 1}, {below_last, full_scale - 1}, {above_last, full_scale}};
    std::vector<float> values;
    for (const auto& [value, level] : cases) values.push_back(value);
    write_gray_image(path("rounding.tif"), values.data(), int(values.size()), 1, format);
    const GrayImage read = read_gray_image(path("rounding.tif"));
    ASSERT_EQ(read.values.size(), cases.size());
    for (std::size_t i = 0; i < cases.size(); ++i)
      EXPECT_EQ(read.values[i] * float(full_scale), float(cases[i].second)) << "value " << cases[i].first;
  }
}

TEST_F(ImageFileTest, ColourBecomesRec601LumaAndAlphaIsIgnored) {
  const int width = 40, height = 30;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<std::uint8_t> rgb, rgba;
  for (int i = 0; i < width * height; ++i) {
    for (int c = 0; c < 3; ++c) {
      rgb.push_back(std::uint8_t(byte(rng)));
      rgba.push_back(rgb.back());
    }
    rgba.push_back(std::uint8_t(byte(rng)));  // alpha, 0 included: must not scale the colour
  }
  write_with_oiio(path("rgb.png"), width, height, 3, rgb);
  write_with_oiio(path("rgba.png"), width, height, 4, rgba);
  for (const std::string name : {"rgb.png", "rgba.png"}) {
    SCOPED_TRACE(name);
    const GrayImage read = read_gray_image(path(name));
    EXPECT_EQ(read.source_format, PixelFormat::uint8);
    ASSERT_EQ(read.values.size(), std::size_t(width) * height);
    for (int i = 0; i < width * height; ++i) {
      const double luma = (0.299 * rgb[3 * i] + 0.587 * rgb[3 * i + 1] + 0.114 * rgb[3 * i + 2]) / 255.0;
      // Float evaluation of three products of values <= 1 errs by a few ulp of 1
      // (< 5e-7); BT.709 weights or premultiplied alpha would be off by > 1e-3.
      ASSERT_NEAR(read.values[i], luma, 1e-6) << "pixel " << i;
    }
  }

  // Gray + alpha: the gray channel, as stored.
  std::vector<std::uint16_t> gray_alpha;
  for (int i = 0; i < width * height; ++i) {
    gray_alpha.push_back(std::uint16_t(i * 50));
    gray_alpha.push_back(std::uint16_t(i % 3 == 0 ? 0 : 30000));
  }
  write_with_oiio(path("gray_alpha.png"), width, height, 2, gray_alpha);
  const GrayImage read = read_gray_image(path("gray_alpha.png"));
  EXPECT_EQ(read.source_format, PixelFormat::uint16);
  for (int i = 0; i < width * height; ++i) ASSERT_EQ(read.values[i], float(i * 50) / 65535.0f) << "pixel " << i;
}

TEST_F(ImageFileTest, MultiPageTiffReadsTheFirstPage) {
  const std::string file = path("pages.tif");
  const OIIO::ImageSpec pages[2] = {OIIO::ImageSpec(8, 4, 1, OIIO::TypeDesc::UINT8),
                                    OIIO::ImageSpec(6, 6, 1, OIIO::TypeDesc::UINT8)};
  const std::vector<std::uint8_t> first(8 * 4, 10), second(6 * 6, 200);
  const auto out = OIIO::ImageOutput::create(file);
  ASSERT_TRUE(out && out->open(file, 2, pages));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, first.data()));
  ASSERT_TRUE(out->open(file, pages[1], OIIO::ImageOutput::AppendSubimage));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, second.data()));
  ASSERT_TRUE(out->close()) << out->geterror();

  const GrayImage read = read_gray_image(file);
  EXPECT_EQ(read.width, 8);
  EXPECT_EQ(read.height, 4);
  EXPECT_EQ(read.values, std::vector<float>(8 * 4, 10.0f / 255.0f));
}

TEST_F(ImageFileTest, BadInputFilesThrowInputErrorAndPrintNothing) {
  const std::vector<float> frame(64 * 64, 0.25f);
  for (const std::string name : {"cut.png", "cut.tif", "cut.exr"}) {
    const PixelFormat format = name == "cut.exr" ? PixelFormat::float32 : PixelFormat::uint16;
    write_gray_image(path(name), frame.data(), 64, 64, format);
    fs::resize_file(path(name), fs::file_size(path(name)) / 2);
  }
  std::ofstream(path("notes.tif")) << "not an image\n";
  fs::create_directories(path("folder.png"));

  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  EXPECT_NE(input_error_of(path("missing.tif"), [&] { read_gray_image(path("missing.tif")); }).find("does not exist"),
            std::string::npos);
  EXPECT_NE(input_error_of(path("folder.png"), [&] { read_gray_image(path("folder.png")); }).find("folder"),
            std::string::npos);
  for (const std::string name : {"notes.tif", "cut.png", "cut.tif", "cut.exr"}) {
    SCOPED_TRACE(name);
    input_error_of(path(name), [&] { read_gray_image(path(name)); });
  }
  // libpng, left to itself, prints "libpng error: ..." for the truncated PNG.
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
}

// The files: a 74-byte PNG and a 234-byte TIFF whose headers claim
// 100000 x 100000 px made the reader allocate ~10 GB. The limits are checked
// from the header, before any pixel buffer, and the message states them.
TEST_F(ImageFileTest, HeadersOverTheSizeLimitsAreRefusedBeforeAllocating) {
  const std::string tiny_idat("\x78\x9c\x63\x00\x00\x00\x01\x00\x01", 9);  // zlib of one zero byte
  write_bytes(path("huge.png"), png_claiming(100000, 100000, tiny_idat));
  write_bytes(path("wide.png"), png_claiming(70000, 1, tiny_idat));  // one side over, few pixels
  write_bytes(path("huge.tif"), tiff_claiming(100000, 100000));
  write_bytes(path("tall.tif"), tiff_claiming(1, 65537));
  write_bytes(path("huge_tiles.tif"), tiff_claiming(16, 16, 65536, 65536));
  ::testing::internal::CaptureStderr();
  for (const std::string name : {"huge.png", "wide.png", "huge.tif", "tall.tif", "huge_tiles.tif"}) {
    SCOPED_TRACE(name);
    const std::string message = input_error_of(path(name), [&] { read_gray_image(path(name)); });
    EXPECT_NE(message.find("over the limit of 65536 px a side and 1073741824 px in all"), std::string::npos)
        << message;
    input_error_of(path(name), [&] { read_stored_image(path(name)); });
  }
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  // At the limit itself the size check passes (the file then fails for its data).
  write_bytes(path("edge.png"), png_claiming(65536, 1, tiny_idat));
  const std::string edge = input_error_of(path("edge.png"), [&] { read_gray_image(path("edge.png")); });
  EXPECT_EQ(edge.find("over the limit"), std::string::npos) << edge;
  EXPECT_NE(edge.find("1032-fold"), std::string::npos) << edge;
}

// Within the limits, a PNG header stating more pixels than its compressed data
// can expand to (deflate: at most 1032-fold) is refused unread too.
TEST_F(ImageFileTest, PngWithTooLittleDataForItsHeaderIsRefusedUnread) {
  write_bytes(path("hollow.png"), png_claiming(30000, 30000, std::string("\x78\x9c\x63\x00\x00\x00\x01\x00\x01", 9)));
  const std::string message = input_error_of(path("hollow.png"), [&] { read_gray_image(path("hollow.png")); });
  EXPECT_NE(message.find("1032-fold"), std::string::npos) << message;
  EXPECT_NE(message.find("30000 x 30000 px"), std::string::npos) << message;
  // A real PNG passes that check, however well it compresses (all zero).
  const std::vector<float> black(1000 * 600, 0.0f);
  write_gray_image(path("black.png"), black.data(), 1000, 600, PixelFormat::uint16);
  EXPECT_EQ(read_gray_image(path("black.png")).values, black);
}

// Damage libpng, libjpeg or libtiff detect must come back as the one-line
// InputError and nothing on stderr ("libpng error: ..." used to be printed).
TEST_F(ImageFileTest, DamagedFilesAreRefusedSilently) {
  std::vector<float> frame(64 * 64);
  for (std::size_t i = 0; i < frame.size(); ++i) frame[i] = float((i * 37) % 251) / 255.0f;
  write_gray_image(path("good.png"), frame.data(), 64, 64, PixelFormat::uint8);
  std::string png = read_file(path("good.png"));
  std::string damaged = png;
  const std::size_t idat = png.find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  for (std::size_t i = idat + 10; i < idat + 40; ++i) damaged[i] = char(damaged[i] ^ 0x5a);  // the pixel data
  write_bytes(path("damaged.png"), damaged);
  std::string ihdr_damaged = png;
  ihdr_damaged[20] = char(ihdr_damaged[20] ^ 1);  // the IHDR CRC no longer matches: libpng fails at open
  write_bytes(path("ihdr.png"), ihdr_damaged);
  // Valid chunks and CRCs, too little pixel data (libpng: "Not enough image data").
  write_bytes(path("short.png"), png_claiming(64, 64, std::string("\x78\x9c\x63\x00\x00\x00\x01\x00\x01", 9)));
  // A truncated JPEG: libjpeg warns "Premature end of JPEG file" and fills grey.
  {
    const auto out = OIIO::ImageOutput::create(path("whole.jpg"));
    ASSERT_TRUE(out);
    std::vector<std::uint8_t> levels(frame.size());
    for (std::size_t i = 0; i < frame.size(); ++i) levels[i] = std::uint8_t(frame[i] * 255.0f);
    ASSERT_TRUE(out->open(path("whole.jpg"), OIIO::ImageSpec(64, 64, 1, OIIO::TypeDesc::UINT8)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, levels.data()));
    ASSERT_TRUE(out->close());
  }
  const std::string jpeg = read_file(path("whole.jpg"));
  write_bytes(path("cut.jpg"), jpeg.substr(0, jpeg.size() / 2));
  EXPECT_EQ(read_gray_image(path("whole.jpg")).width, 64);  // the whole one reads

  ::testing::internal::CaptureStderr();
  for (const std::string name : {"damaged.png", "ihdr.png", "short.png", "cut.jpg"}) {
    SCOPED_TRACE(name);
    input_error_of(path(name), [&] { read_gray_image(path(name)); });
  }
  EXPECT_FALSE(image_file_size(path("ihdr.png")));
  std::fputs("stderr is back\n", stderr);  // the reads give stderr back
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "stderr is back\n");
}

TEST_F(ImageFileTest, FailedWritesLeaveTheTargetUntouchedAndNoTemporary) {
  const std::vector<float> frame(16 * 8, 0.5f);
  write_gray_image(path("keep.png"), frame.data(), 16, 8, PixelFormat::uint8);
  write_gray_image(path("keep.exr"), frame.data(), 16, 8, PixelFormat::float32);
  const std::string png_bytes = read_file(path("keep.png")), exr_bytes = read_file(path("keep.exr"));
  // A folder where the image should go: OIIO writes the temporary, the rename fails.
  fs::create_directories(path("taken.tif") + "/inside");
  const std::set<std::string> before = files();

  ::testing::internal::CaptureStderr();
  const auto write = [&](const std::string& name, PixelFormat format) {
    return input_error_of(path(name), [&] { write_gray_image(path(name), frame.data(), 16, 8, format); });
  };
  const std::string float_png = write("keep.png", PixelFormat::float32);
  EXPECT_NE(float_png.find("PNG"), std::string::npos) << float_png;
  EXPECT_NE(float_png.find("float32"), std::string::npos) << float_png;
  for (const PixelFormat format : {PixelFormat::uint8, PixelFormat::uint16}) {
    const std::string integer_exr = write("keep.exr", format);
    EXPECT_NE(integer_exr.find("EXR holds half/float"), std::string::npos) << integer_exr;
    EXPECT_NE(integer_exr.find(pixel_format_name(format)), std::string::npos) << integer_exr;
  }
  const std::string jpeg = write("out.jpg", PixelFormat::uint8);
  EXPECT_NE(jpeg.find("'.jpg' (use .tif, .png or .exr)"), std::string::npos) << jpeg;
  write("no_extension", PixelFormat::uint8);
  write("taken.tif", PixelFormat::uint16);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");

  EXPECT_EQ(read_file(path("keep.png")), png_bytes);
  EXPECT_EQ(read_file(path("keep.exr")), exr_bytes);
  EXPECT_EQ(files(), before);
  EXPECT_TRUE(fs::is_empty(path("taken.tif") + "/inside"));
}

// The description written with a frame reads back from the header alone, any
// text kept (quotes, a newline); a file cut short is told from a complete one.
TEST_F(ImageFileTest, DescriptionReadsBackFromTheHeaderAndACutFileIsFlagged) {
  const std::vector<float> frame(64 * 48, 0.25f);
  const std::string text = "{\"a\": \"x\\ny \\\"q\\\"\"}";
  for (const PixelFormat format : {PixelFormat::uint16, PixelFormat::float32}) {
    write_gray_image(path("d.tif"), frame.data(), 64, 48, format, text);
    const auto header = read_image_file_header(path("d.tif"), true);
    ASSERT_TRUE(header);
    EXPECT_EQ(header->width, 64);
    EXPECT_EQ(header->height, 48);
    EXPECT_EQ(header->description, text);
    EXPECT_EQ(header->sample_type, format == PixelFormat::uint16 ? "uint16" : "float");
    EXPECT_TRUE(header->pixels_present);
    // Cut short, as a power loss without fsync or an interrupted copy leaves it.
    const std::string bytes = read_file(path("d.tif"));
    for (std::size_t keep : {bytes.size() - 1, bytes.size() / 2, std::size_t(200)}) {
      std::ofstream(path("cut.tif"), std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(keep));
      const auto cut = read_image_file_header(path("cut.tif"), true);
      EXPECT_TRUE(!cut || !cut->pixels_present || cut->description != text) << keep << " of " << bytes.size();
    }
  }
  write_gray_image(path("none.tif"), frame.data(), 64, 48, PixelFormat::uint16);
  EXPECT_EQ(read_image_file_header(path("none.tif"))->description, "");
  EXPECT_FALSE(read_image_file_header(path("missing.tif")));
}

// Past a file-size limit (ulimit -f; SIGXFSZ ignored, as glasspiv's main does)
// a write fails with one InputError naming the target, and leaves nothing.
TEST_F(ImageFileTest, AWriteOverTheFileSizeLimitFailsAndLeavesNothing) {
  const std::vector<float> frame(256 * 256, 0.5f);
  struct rlimit saved{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
  if (saved.rlim_cur != RLIM_INFINITY && saved.rlim_cur < 200000) GTEST_SKIP() << "already under a file-size limit";
  const auto previous = std::signal(SIGXFSZ, SIG_IGN);
  struct rlimit small = saved;
  small.rlim_cur = 50000;  // a 256 x 256 16-bit frame needs 131072 bytes
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string message;
  for (const PixelFormat format : {PixelFormat::uint16, PixelFormat::float32})
    message = input_error_of(path("big.tif"), [&] { write_gray_image(path("big.tif"), frame.data(), 256, 256, format); });
  const std::string text(100000, 'x');
  const std::string text_message = input_error_of(path("big.txt"), [&] { write_file_atomically(path("big.txt"), text); });
  ::setrlimit(RLIMIT_FSIZE, &saved);
  std::signal(SIGXFSZ, previous);
  EXPECT_NE(message.find("big.tif"), std::string::npos) << message;
  EXPECT_EQ(message.find(".tmp"), std::string::npos) << message;
  EXPECT_NE(text_message.find("big.txt"), std::string::npos) << text_message;
  EXPECT_TRUE(files().empty()) << *files().begin();
}

TEST_F(ImageFileTest, EmptyImagesAreAProgrammingError) {
  const float value = 0.0f;
  EXPECT_THROW(write_gray_image(path("a.tif"), &value, 0, 1, PixelFormat::uint8), std::invalid_argument);
  GrayImage mismatched;
  mismatched.width = 2;
  mismatched.height = 2;
  mismatched.values = {0.0f, 1.0f};
  EXPECT_THROW(write_gray_image(path("a.tif"), mismatched, PixelFormat::uint8), std::invalid_argument);
  EXPECT_TRUE(files().empty());
}

TEST(PixelFormatTest, NamesAndAliases) {
  for (const auto& [name, format] : std::vector<std::pair<std::string, PixelFormat>>{
           {"8", PixelFormat::uint8}, {"uint8", PixelFormat::uint8}, {"16", PixelFormat::uint16},
           {"uint16", PixelFormat::uint16}, {"float", PixelFormat::float32}, {"32", PixelFormat::float32},
           {"float32", PixelFormat::float32}}) {
    EXPECT_EQ(pixel_format_from_name(name, "format"), format) << name;
    EXPECT_EQ(pixel_format_from_name(pixel_format_name(format), "format"), format) << name;
  }
  try {
    pixel_format_from_name("12", "render.format");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "");
    EXPECT_EQ(e.field(), "render.format");
    EXPECT_NE(e.problem().find("'12'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace glasspiv
