#include "apps/cli_files.h"

#include <cctype>
#include <filesystem>

#include "util/input_error.h"

namespace glasspiv {

namespace fs = std::filesystem;

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

void check_not_input(const std::string& input, const std::string& output) {
  std::error_code ec;
  if (fs::exists(output, ec) && fs::equivalent(input, output, ec))
    throw InputError(output, "", "is the input file; glasspiv never overwrites its inputs");
}

}  // namespace glasspiv
