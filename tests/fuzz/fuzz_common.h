#pragma once
// Shared by the fuzz harnesses (tests/fuzz/fuzz_*.cpp, docs/fuzzing.md).
//
// Every harness defines LLVMFuzzerTestOneInput. Built with clang and
// -fsanitize=fuzzer,address,undefined (GLASSPIV_FUZZ=ON) it is a libFuzzer
// target; built with the normal compiler it is linked with regress_main.cpp
// into a regression executable that ctest runs over the kept corpus and crash
// reproducers.
//
// The contract checked: a reader either returns or throws InputError (a
// correct refusal of bad input). Any other exception is a finding and aborts,
// so libFuzzer keeps the input; crashes, hangs, leaks and sanitizer reports
// are findings by themselves.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>
#include <typeinfo>

#include "util/input_error.h"

namespace glasspiv_fuzz {

inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// Runs `body`; returns true when it returned, false when it threw InputError.
// Anything else it throws is reported as a finding in `reader` and aborts.
template <typename Body>
bool returns_or_refuses(const char* reader, Body&& body) {
  try {
    body();
    return true;
  } catch (const glasspiv::InputError&) {
    return false;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "FUZZ FINDING: %s threw %s (not InputError): %s\n", reader, typeid(e).name(), e.what());
    std::fflush(stderr);
    std::abort();
  } catch (...) {
    std::fprintf(stderr, "FUZZ FINDING: %s threw something that is not a std::exception\n", reader);
    std::fflush(stderr);
    std::abort();
  }
}

// For readers that only take a path: the input written to a scratch file of
// this process with the extension `ext` (".tmap", ".png", ...), under /dev/shm
// where there is one (no disk traffic). The file is removed at exit.
class ScratchFile {
 public:
  explicit ScratchFile(const std::string& ext) {
    std::error_code ec;
    std::filesystem::path dir = "/dev/shm";
    if (!std::filesystem::is_directory(dir, ec)) dir = std::filesystem::temp_directory_path();
    path_ = (dir / ("glasspiv_fuzz_" + std::to_string(::getpid()) + "_input" + ext)).string();
  }
  ~ScratchFile() { std::remove(path_.c_str()); }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  // Replaces the file's contents with the bytes; returns its path.
  const std::string& write(const void* data, std::size_t size) {
    std::FILE* f = std::fopen(path_.c_str(), "wb");
    if (f == nullptr) {
      std::perror(path_.c_str());
      std::abort();
    }
    if (size > 0 && std::fwrite(data, 1, size, f) != size) {
      std::perror(path_.c_str());
      std::abort();
    }
    std::fclose(f);
    return path_;
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace glasspiv_fuzz
