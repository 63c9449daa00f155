#include "util/file_identity.h"

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include <sys/stat.h>

#include "util/binary_file.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

struct FileFacts {
  bool readable = false;
  dev_t device = 0;
  ino_t inode = 0;
  std::uint64_t size = 0;
  std::optional<std::uint64_t> hash;  // of the bytes, when needed
};

struct CloseFile {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, CloseFile>;

// stat() follows symlinks: a link and its target have one device and inode.
FileFacts facts_of(const std::string& path) {
  FileFacts f;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return f;
  f.readable = true;
  f.device = st.st_dev;
  f.inode = st.st_ino;
  f.size = static_cast<std::uint64_t>(st.st_size);
  return f;
}

std::optional<std::uint64_t> hash_of(const std::string& path) {
  File file(std::fopen(path.c_str(), "rb"));
  if (!file) return std::nullopt;
  Xxh64 h;
  std::vector<unsigned char> buffer(1 << 16);
  for (std::size_t n; (n = std::fread(buffer.data(), 1, buffer.size(), file.get())) > 0;) h.update(buffer.data(), n);
  if (std::ferror(file.get())) return std::nullopt;
  return h.digest();
}

bool same_bytes(const std::string& a, const std::string& b) {
  File fa(std::fopen(a.c_str(), "rb")), fb(std::fopen(b.c_str(), "rb"));
  if (!fa || !fb) return false;
  std::vector<unsigned char> x(1 << 16), y(1 << 16);
  for (;;) {
    const std::size_t n = std::fread(x.data(), 1, x.size(), fa.get());
    const std::size_t m = std::fread(y.data(), 1, y.size(), fb.get());
    if (n != m || std::memcmp(x.data(), y.data(), n) != 0) return false;
    if (n == 0) return !std::ferror(fa.get()) && !std::ferror(fb.get());
  }
}

}  // namespace

std::optional<SameInput> find_same_input(const std::vector<std::string>& paths) {
  std::vector<FileFacts> facts;
  facts.reserve(paths.size());
  for (const std::string& p : paths) facts.push_back(facts_of(p));
  for (std::size_t j = 1; j < paths.size(); ++j) {
    if (!facts[j].readable) continue;
    for (std::size_t i = 0; i < j; ++i) {
      if (!facts[i].readable) continue;
      if (facts[i].device == facts[j].device && facts[i].inode == facts[j].inode) return SameInput{i, j, true};
      if (facts[i].size != facts[j].size) continue;
      for (std::size_t k : {i, j})
        if (!facts[k].hash) facts[k].hash = hash_of(paths[k]);
      if (facts[i].hash && facts[i].hash == facts[j].hash && same_bytes(paths[i], paths[j]))
        return SameInput{i, j, false};
    }
  }
  return std::nullopt;
}

void check_distinct_inputs(const std::vector<std::string>& paths, const std::string& field, const std::string& what) {
  const std::optional<SameInput> same = find_same_input(paths);
  if (!same) return;
  const std::string& first = paths[same->first];
  throw InputError(paths[same->second], field,
                   (same->same_file ? "is the same file as '" + first + "'"
                                    : "has the same bytes as '" + first + "'") +
                       ": one " + what + " is one view, give it once");
}

}  // namespace glasspiv
