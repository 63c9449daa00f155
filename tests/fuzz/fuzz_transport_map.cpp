// Fuzz harness: the transport map file reader (render/transport_map_file.h,
// read_transport_map; layout in docs/transport_map_file.md).
//
// The payload checksum stops almost every mutation at "header.checksum". So
// each input is read as it is, and then, when it is long enough to hold a
// header, once more with the header's checksum replaced by the payload's true
// XXH64, so that mutations reach the checks behind the checksum (sizes,
// pixel_offsets, tags, values).
#include <cstring>
#include <vector>

#include "fuzz_common.h"
#include "render/transport_map_file.h"

namespace {
constexpr std::size_t kHeaderBytes = 144;    // docs/transport_map_file.md, "Header"
constexpr std::size_t kChecksumOffset = 136;  // header.checksum, u64 little-endian
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static glasspiv_fuzz::ScratchFile file(".tmap");
  std::uint64_t fingerprint = 0;
  glasspiv_fuzz::returns_or_refuses("read_transport_map", [&] {
    glasspiv::read_transport_map(file.write(data, size), &fingerprint);
  });
  if (size >= kHeaderBytes) {
    std::vector<std::uint8_t> fixed(data, data + size);
    const std::uint64_t sum = glasspiv::transport_map_checksum(fixed.data() + kHeaderBytes, size - kHeaderBytes);
    for (int i = 0; i < 8; ++i) fixed[kChecksumOffset + i] = static_cast<std::uint8_t>(sum >> (8 * i));
    if (std::memcmp(fixed.data(), data, size) != 0)
      glasspiv_fuzz::returns_or_refuses("read_transport_map (checksum fixed)", [&] {
        glasspiv::read_transport_map(file.write(fixed.data(), fixed.size()), &fingerprint);
      });
  }
  return 0;
}
