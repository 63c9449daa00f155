// Fuzz harness: the observations file reader, YAML form
// (targets/observations_io.h, parse_observations).
#include "fuzz_common.h"
#include "targets/observations_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  glasspiv_fuzz::returns_or_refuses("parse_observations(yaml)", [&] {
    glasspiv::parse_observations(glasspiv_fuzz::as_text(data, size), glasspiv::ObservationsFormat::yaml,
                                 "fuzz_input.yaml");
  });
  return 0;
}
