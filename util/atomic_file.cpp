#include "util/atomic_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <unistd.h>

#include "util/input_error.h"

namespace glasspiv {
namespace fs = std::filesystem;

namespace {
std::string temporary_path_for(const std::string& path) {
  const fs::path target(path);
  std::random_device seed;
  const std::string stem = "." + target.stem().string() + ".tmp" +
                           std::to_string(::getpid()) + "-" + std::to_string(seed() % 1000000);
  return (target.parent_path() / (stem + target.extension().string())).string();
}
}  // namespace

void write_file_atomically_with(const std::string& path,
                                const std::function<void(const std::string&)>& write) {
  const fs::path target(path);
  if (target.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(target.parent_path(), ec);
    if (ec) throw InputError(path, "", "cannot create the output folder: " + ec.message());
  }
  const std::string temporary = temporary_path_for(path);
  try {
    write(temporary);
  } catch (...) {
    std::remove(temporary.c_str());
    throw;
  }
  std::error_code ec;
  fs::rename(temporary, target, ec);
  if (ec) {
    std::remove(temporary.c_str());
    throw InputError(path, "", "cannot write the output: " + ec.message());
  }
}

void write_file_atomically(const std::string& path, std::string_view contents) {
  write_file_atomically_with(path, [&](const std::string& temporary) {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path, "", std::string("cannot open for writing: ") + std::strerror(errno));
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.flush();
    if (!out) throw InputError(path, "", "write failed (disk full?)");
  });
}

std::string read_file(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "", "file does not exist");
  if (fs::is_directory(path, ec)) throw InputError(path, "", "is a folder, expected a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

}  // namespace glasspiv
