// Fuzz harness: the camera file reader for the glasspiv camera YAML format
// (calib/io/camera_file.h). Each input is read twice: as a file with the
// format's extension (.yaml) through read_cameras, which sniffs the format from
// the contents (detect_format), and as text forced to this format through
// parse_cameras, so the format's own parser sees every input.
#include "calib/io/camera_file.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static glasspiv_fuzz::ScratchFile file(".yaml");
  const std::string& path = file.write(data, size);
  glasspiv_fuzz::returns_or_refuses("read_cameras", [&] { glasspiv::read_cameras(path); });
  glasspiv_fuzz::returns_or_refuses("parse_cameras(glasspiv)", [&] {
    glasspiv::parse_cameras(glasspiv_fuzz::as_text(data, size), glasspiv::CameraFileFormat::Glasspiv, "fuzz_input.yaml");
  });
  return 0;
}
