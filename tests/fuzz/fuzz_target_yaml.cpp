// Fuzz harness: the target spec reader (targets/target_yaml.h, parse_target_yaml).
#include "fuzz_common.h"
#include "targets/target_yaml.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  glasspiv_fuzz::returns_or_refuses("parse_target_yaml", [&] {
    glasspiv::parse_target_yaml(glasspiv_fuzz::as_text(data, size), "fuzz_input.yaml");
  });
  return 0;
}
