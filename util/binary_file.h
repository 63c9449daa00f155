#pragma once
// The pieces shared by glasspiv's binary cache files (docs/transport_map_file.md,
// docs/correction_operator_file.md): little-endian files that start with an
// 8-byte magic, a u32 format version and a u32 header size, carry a 64-bit
// fingerprint of their inputs and an XXH64 checksum of the payload, and hold
// arrays that load in large blocks straight into std::vectors, each padded with
// zero bytes to a multiple of 8. Each file keeps its own layout; this is the
// reading, writing, hashing and the checks common to all of them, with their
// one-line InputError(path, field, problem) messages.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <type_traits>
#include <utility>
#include <vector>

#include "util/input_error.h"

namespace glasspiv {

// The files are written and read by copying memory: they need a little-endian
// host with IEEE 754 floats.
#if !defined(__BYTE_ORDER__) || !defined(__ORDER_LITTLE_ENDIAN__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
static_assert(false,
              "util/binary_file.h: the binary cache files are little-endian and are read by copying memory; this "
              "host is not (known) little-endian");
#endif
static_assert(std::numeric_limits<float>::is_iec559 && sizeof(float) == 4, "IEEE 754 binary32 floats required");
static_assert(std::numeric_limits<double>::is_iec559 && sizeof(double) == 8, "IEEE 754 binary64 doubles required");

// Bytes rounded up to a multiple of 8 (every array starts at one).
constexpr std::size_t padded8(std::size_t bytes) { return (bytes + 7) & ~std::size_t{7}; }

// A header field of type T at byte offset `at`.
template <typename T>
void put_field(unsigned char* b, std::size_t at, T v) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::memcpy(b + at, &v, sizeof v);
}
template <typename T>
T get_field(const unsigned char* b, std::size_t at) {
  static_assert(std::is_trivially_copyable_v<T>);
  T v;
  std::memcpy(&v, b + at, sizeof v);
  return v;
}

// 16 lowercase hex digits.
std::string hex_u64(std::uint64_t v);

// XXH64 (xxHash, 64-bit, by Yann Collet; specification in xxHash's
// doc/xxhash_spec.md), streaming, seed 0: the payload checksum. It runs at
// memory speed, unlike FNV-1a (util/fnv1a64.h). `xxhsum -H64` of the same bytes
// prints the same value.
class Xxh64 {
 public:
  Xxh64();
  void update(const void* data, std::size_t size);  // data may be null when size is 0
  // `bytes` of data, then zero bytes up to a multiple of 8: an array as it lies in the file.
  void update_padded(const void* data, std::size_t bytes);
  std::uint64_t digest() const;

 private:
  void stripe(const unsigned char* p);

  std::uint64_t v_[4];
  unsigned char buffer_[32] = {};
  std::size_t buffered_ = 0;
  std::uint64_t total_ = 0;
};

// XXH64 (seed 0) of `size` bytes.
std::uint64_t xxh64(const void* data, std::size_t size);

// The payload checksum of arrays in file order, as the writer computes it
// before writing the header: hash_array(checksum, v) for each.
template <typename T>
void hash_array(Xxh64& checksum, const std::vector<T>& v) {
  checksum.update_padded(v.data(), v.size() * sizeof(T));
}

// The first problem of a CSR offsets array (`name`, e.g. "pixel_offsets") that
// must start at 0, never decrease and end at `total` (`total_name`, e.g.
// "crossing count"), or "" when there is none.
std::string offsets_problem(const std::vector<std::uint32_t>& offsets, std::uint64_t total, const char* name,
                            const char* total_name);

// ---------------------------------------------------------------- reading

namespace binary_file_detail {
struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
}  // namespace binary_file_detail

// A binary file open for reading, its length known up front (so that sizes in a
// header are checked against it before anything is allocated).
class BinaryFileReader {
 public:
  // InputError(path, "", ...): the file does not exist, cannot be opened, or is
  // not a regular file.
  explicit BinaryFileReader(const std::string& path);

  const std::string& path() const { return path_; }
  std::uint64_t size() const { return size_; }

  // Reads the header every file starts with into header[0, header_size): the
  // 8-byte `magic`, u32 format version at 8, u32 header size at 12, then the
  // file's own fields. Throws InputError(path, field, ...) at the first problem:
  // "magic" (does not start with `magic`: "not a <what> file"; an empty file
  // included), "header" (ends inside it), "header.version" (not `version`),
  // "header.header_size" (not `header_size`). Not part of the checksum.
  void read_header(const char (&magic)[8], const char* what, std::uint32_t version, unsigned char* header,
                   std::uint32_t header_size);

  // InputError(path, "payload", "file is N bytes, the header (<header_says>)
  // needs M: truncated" or ": trailing bytes") unless the file is `expected`
  // bytes long. expected = UINT64_MAX (the header's sizes overflow) reads "far more".
  void expect_size(std::uint64_t expected, const std::string& header_says) const;

  // The next array: n elements into v (resized), then its padding to a
  // multiple of 8 bytes, in blocks of 4 MiB straight into the vector, each
  // hashed into the payload checksum while still in cache. InputError(path,
  // name, "file ended early (changed while being read?)") if the file ends first.
  template <typename T>
  void read_array(const char* name, std::vector<T>& v, std::uint64_t n) {
    static_assert(std::is_trivially_copyable_v<T>);
    v.resize(static_cast<std::size_t>(n));
    read_padded(name, v.data(), v.size() * sizeof(T));
  }

  // InputError(path, "header.checksum", "the payload's checksum is ..., the
  // header says ...: the file is damaged") unless the arrays read so far hash to `stored`.
  void expect_checksum(std::uint64_t stored) const;

 private:
  void read_padded(const char* name, void* data, std::size_t bytes);

  std::string path_;
  std::unique_ptr<std::FILE, binary_file_detail::FileCloser> file_;
  std::uint64_t size_ = 0;
  Xxh64 checksum_;
};

// ---------------------------------------------------------------- writing

// Where write_binary_file_atomically's callback writes the file.
class BinaryFileWriter {
 public:
  // InputError naming the target path when the write fails (disk full, file size limit).
  void write(const void* data, std::size_t bytes);
  // v's bytes, then zero bytes up to a multiple of 8.
  template <typename T>
  void write_array(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    write_padded(v.data(), v.size() * sizeof(T));
  }

 private:
  friend void write_binary_file_atomically(const std::string&, const std::function<void(BinaryFileWriter&)>&);
  BinaryFileWriter(const std::string& path, std::FILE* file) : path_(path), file_(file) {}
  void write_padded(const void* data, std::size_t bytes);

  const std::string& path_;
  std::FILE* file_;
};

// Writes `path` atomically (util/atomic_file.h): `write` fills a temporary file
// beside it, renamed over `path` only when complete and flushed, so an existing
// file is only replaced by a complete one and no temporary is left behind.
// InputError naming `path` when the file cannot be written.
void write_binary_file_atomically(const std::string& path, const std::function<void(BinaryFileWriter&)>& write);

// ---------------------------------------------------------------- cache lookup

// The cache lookup of a fingerprinted binary file: the value in `path` if the
// file exists, reads cleanly and carries `fingerprint`; std::nullopt otherwise,
// with *why (if given) set to a one-line reason: "no file", "made for another
// setup (fingerprint <file's>, wanted <fingerprint>)" (decided on the header
// alone) or "unreadable: <the InputError>"; *why is cleared on success.
// read_header(BinaryFileReader&) returns the file's header, with a
// `fingerprint` member; read_body(BinaryFileReader&, const Header&) the value.
template <typename ReadHeader, typename ReadBody>
auto load_cached_binary_file(const std::string& path, std::uint64_t fingerprint, std::string* why,
                             ReadHeader&& read_header, ReadBody&& read_body) {
  using Header = std::decay_t<std::invoke_result_t<ReadHeader&, BinaryFileReader&>>;
  using Value = std::decay_t<std::invoke_result_t<ReadBody&, BinaryFileReader&, const Header&>>;
  auto fail = [&](std::string reason) -> std::optional<Value> {
    if (why) *why = std::move(reason);
    return std::nullopt;
  };
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return fail("no file");
  try {
    BinaryFileReader in(path);
    const Header h = read_header(in);
    if (h.fingerprint != fingerprint)
      return fail("made for another setup (fingerprint " + hex_u64(h.fingerprint) + ", wanted " +
                  hex_u64(fingerprint) + ")");
    std::optional<Value> value(read_body(in, h));
    if (why) why->clear();
    return value;
  } catch (const InputError& e) {
    return fail(std::string("unreadable: ") + e.what());
  }
}

}  // namespace glasspiv
