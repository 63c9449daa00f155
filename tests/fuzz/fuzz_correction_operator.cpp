// Fuzz harness: the correction operator file reader
// (correct/correction_operator_file.h, read_correction_operator; layout in
// docs/correction_operator_file.md).
//
// As for the transport map: each input is read as it is and, when it holds a
// header, again with the header's checksum set to the payload's true XXH64
// (the transport map file's checksum, transport_map_checksum), so that
// mutations reach the checks behind the checksum.
#include <cstring>
#include <vector>

#include "correct/correction_operator_file.h"
#include "fuzz_common.h"
#include "render/transport_map_file.h"

namespace {
constexpr std::size_t kHeaderBytes = 88;     // docs/correction_operator_file.md, "Header"
constexpr std::size_t kChecksumOffset = 80;  // header.checksum, u64 little-endian
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static glasspiv_fuzz::ScratchFile file(".gpop");
  std::uint64_t fingerprint = 0;
  glasspiv_fuzz::returns_or_refuses("read_correction_operator", [&] {
    glasspiv::read_correction_operator(file.write(data, size), &fingerprint);
  });
  if (size >= kHeaderBytes) {
    std::vector<std::uint8_t> fixed(data, data + size);
    const std::uint64_t sum = glasspiv::transport_map_checksum(fixed.data() + kHeaderBytes, size - kHeaderBytes);
    for (int i = 0; i < 8; ++i) fixed[kChecksumOffset + i] = static_cast<std::uint8_t>(sum >> (8 * i));
    if (std::memcmp(fixed.data(), data, size) != 0)
      glasspiv_fuzz::returns_or_refuses("read_correction_operator (checksum fixed)", [&] {
        glasspiv::read_correction_operator(file.write(fixed.data(), fixed.size()), &fingerprint);
      });
  }
  return 0;
}
