// Fuzz harness: the gray image reader (util/image_file.h, read_gray_image and
// image_file_size) for the formats glasspiv reads and writes: PNG, TIFF, JPEG,
// OpenEXR. The input is written to a file whose extension follows its magic
// bytes (OpenImageIO opens by extension first), so one corpus holds all four
// formats and a mutation that breaks the magic still reaches a reader.
#include <cstring>

#include "fuzz_common.h"
#include "util/image_file.h"

namespace {
const char* extension_for(const std::uint8_t* data, std::size_t size) {
  auto starts = [&](const char* magic, std::size_t n) { return size >= n && std::memcmp(data, magic, n) == 0; };
  if (starts("\x89PNG", 4)) return ".png";
  if (starts("\xFF\xD8", 2)) return ".jpg";
  if (starts("v/1\x01", 4)) return ".exr";
  if (starts("II", 2) || starts("MM", 2)) return ".tif";
  // Anything else: the extension from the last byte, so every reader sees junk too.
  static const char* const all[] = {".png", ".tif", ".jpg", ".exr"};
  return all[size == 0 ? 0 : data[size - 1] % 4];
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static glasspiv_fuzz::ScratchFile png(".png"), tif(".tif"), jpg(".jpg"), exr(".exr");
  const std::string ext = extension_for(data, size);
  glasspiv_fuzz::ScratchFile& file = ext == ".png" ? png : ext == ".tif" ? tif : ext == ".jpg" ? jpg : exr;
  const std::string& path = file.write(data, size);
  glasspiv_fuzz::returns_or_refuses("image_file_size", [&] { glasspiv::image_file_size(path); });
  glasspiv_fuzz::returns_or_refuses("read_gray_image", [&] {
    const glasspiv::GrayImage image = glasspiv::read_gray_image(path);
    if (image.values.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height)) {
      std::fprintf(stderr, "FUZZ FINDING: read_gray_image returned %zu values for %d x %d\n", image.values.size(),
                   image.width, image.height);
      std::abort();
    }
  });
  return 0;
}
