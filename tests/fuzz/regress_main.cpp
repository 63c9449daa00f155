// The main() of the regression executables (tests/fuzz/CMakeLists.txt): runs
// every file of the folders (or the files) given on the command line through
// the harness's LLVMFuzzerTestOneInput, the same way libFuzzer's -runs=0 would,
// so the kept corpus and crash reproducers are tests of every build. A folder
// that does not exist counts as empty; file names starting with '.' and
// README files are skipped. Exits 0 when every input was handled (a finding
// aborts inside the harness, with the file name printed first).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace fs = std::filesystem;

static bool skipped(const fs::path& p) {
  const std::string name = p.filename().string();
  return name.empty() || name[0] == '.' || name.rfind("README", 0) == 0;
}

int main(int argc, char** argv) {
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const fs::path arg = argv[i];
    std::error_code ec;
    if (fs::is_directory(arg, ec)) {
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(arg))
        if (e.is_regular_file() && !skipped(e.path())) files.push_back(e.path());
      std::sort(files.begin(), files.end());
      std::printf("%s: %zu inputs\n", arg.string().c_str(), files.size());
      inputs.insert(inputs.end(), files.begin(), files.end());
    } else if (fs::is_regular_file(arg, ec)) {
      inputs.push_back(arg);
    } else {
      std::printf("%s: does not exist, nothing to run\n", arg.string().c_str());
    }
  }
  for (const auto& path : inputs) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
      std::fprintf(stderr, "cannot read %s\n", path.string().c_str());
      return 1;
    }
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::fprintf(stderr, "running %s (%zu bytes)\n", path.string().c_str(), bytes.size());
    // A copy in a buffer of exactly its size, as libFuzzer passes it, so that
    // AddressSanitizer sees a read past the end.
    std::vector<std::uint8_t> exact(bytes.begin(), bytes.end());
    exact.shrink_to_fit();
    LLVMFuzzerTestOneInput(exact.empty() ? nullptr : exact.data(), exact.size());
  }
  std::printf("%zu inputs ran cleanly\n", inputs.size());
  return 0;
}
