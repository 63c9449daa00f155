#include "util/binary_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "util/atomic_file.h"
#include "util/input_file.h"

namespace glasspiv {

namespace {

constexpr std::uint64_t kP1 = 0x9E3779B185EBCA87ull, kP2 = 0xC2B2AE3D27D4EB4Full, kP3 = 0x165667B19E3779F9ull,
                        kP4 = 0x85EBCA77C2B2AE63ull, kP5 = 0x27D4EB2F165667C5ull;

std::uint64_t rotl(std::uint64_t x, int r) { return (x << r) | (x >> (64 - r)); }
std::uint64_t read64(const unsigned char* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}
std::uint64_t xxh_round(std::uint64_t acc, std::uint64_t input) { return rotl(acc + input * kP2, 31) * kP1; }
std::uint64_t xxh_merge(std::uint64_t h, std::uint64_t v) { return (h ^ xxh_round(0, v)) * kP1 + kP4; }

constexpr unsigned char kZeros[8] = {};  // padding

}  // namespace

// ---------------------------------------------------------------- hashing

std::string hex_u64(std::uint64_t v) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(v));
  return s;
}

Xxh64::Xxh64() : v_{kP1 + kP2, kP2, 0, 0 - kP1} {}

void Xxh64::update(const void* data, std::size_t size) {
  if (size == 0) return;  // data may be null (an empty vector's)
  const auto* p = static_cast<const unsigned char*>(data);
  total_ += size;
  if (buffered_ + size < 32) {
    std::memcpy(buffer_ + buffered_, p, size);
    buffered_ += size;
    return;
  }
  if (buffered_ > 0) {
    const std::size_t fill = 32 - buffered_;
    std::memcpy(buffer_ + buffered_, p, fill);
    stripe(buffer_);
    p += fill;
    size -= fill;
    buffered_ = 0;
  }
  // Four independent lanes per 32-byte stripe.
  std::uint64_t v0 = v_[0], v1 = v_[1], v2 = v_[2], v3 = v_[3];
  while (size >= 32) {
    v0 = xxh_round(v0, read64(p));
    v1 = xxh_round(v1, read64(p + 8));
    v2 = xxh_round(v2, read64(p + 16));
    v3 = xxh_round(v3, read64(p + 24));
    p += 32;
    size -= 32;
  }
  v_[0] = v0, v_[1] = v1, v_[2] = v2, v_[3] = v3;
  std::memcpy(buffer_, p, size);
  buffered_ = size;
}

void Xxh64::update_padded(const void* data, std::size_t bytes) {
  update(data, bytes);
  update(kZeros, padded8(bytes) - bytes);
}

std::uint64_t Xxh64::digest() const {
  std::uint64_t h;
  if (total_ >= 32) {
    h = rotl(v_[0], 1) + rotl(v_[1], 7) + rotl(v_[2], 12) + rotl(v_[3], 18);
    for (std::uint64_t v : v_) h = xxh_merge(h, v);
  } else {
    h = kP5;
  }
  h += total_;
  const unsigned char* p = buffer_;
  const unsigned char* end = buffer_ + buffered_;
  for (; p + 8 <= end; p += 8) h = rotl(h ^ xxh_round(0, read64(p)), 27) * kP1 + kP4;
  if (p + 4 <= end) {
    std::uint32_t w;
    std::memcpy(&w, p, 4);
    h = rotl(h ^ (std::uint64_t{w} * kP1), 23) * kP2 + kP3;
    p += 4;
  }
  for (; p < end; ++p) h = rotl(h ^ (std::uint64_t{*p} * kP5), 11) * kP1;
  h ^= h >> 33;
  h *= kP2;
  h ^= h >> 29;
  h *= kP3;
  h ^= h >> 32;
  return h;
}

void Xxh64::stripe(const unsigned char* p) {
  for (int i = 0; i < 4; ++i) v_[i] = xxh_round(v_[i], read64(p + 8 * i));
}

std::uint64_t xxh64(const void* data, std::size_t size) {
  Xxh64 x;
  x.update(data, size);
  return x.digest();
}

std::string offsets_problem(const std::vector<std::uint32_t>& offsets, std::uint64_t total, const char* name,
                            const char* total_name) {
  const std::string n = name;
  if (offsets.empty()) return n + " is empty";
  if (offsets.front() != 0) return n + "[0] is " + std::to_string(offsets.front()) + ", expected 0";
  for (std::size_t i = 1; i < offsets.size(); ++i)
    if (offsets[i] < offsets[i - 1])
      return n + "[" + std::to_string(i) + "] = " + std::to_string(offsets[i]) + " is less than " + n + "[" +
             std::to_string(i - 1) + "] = " + std::to_string(offsets[i - 1]) + " (must not decrease)";
  if (offsets.back() != total)
    return "the last entry is " + std::to_string(offsets.back()) + ", expected the " + total_name + " " +
           std::to_string(total);
  return "";
}

// ---------------------------------------------------------------- reading

BinaryFileReader::BinaryFileReader(const std::string& path) : path_(path) {
  const int fd = open_input_file(path);  // a regular file, or a one-line InputError
  file_.reset(::fdopen(fd, "rb"));
  if (!file_) {
    const int error = errno;
    ::close(fd);
    throw InputError(path, "", std::string("cannot open: ") + std::strerror(error));
  }
  struct stat st {};
  if (::fstat(::fileno(file_.get()), &st) != 0)
    throw InputError(path, "", std::string("cannot read: ") + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw InputError(path, "", "is not a regular file");
  size_ = static_cast<std::uint64_t>(st.st_size);
}

void BinaryFileReader::read_header(const char (&magic)[8], const char* what, std::uint32_t version,
                                   unsigned char* header, std::uint32_t header_size) {
  const std::size_t got = std::fread(header, 1, header_size, file_.get());
  if (got < 8 || std::memcmp(header, magic, 8) != 0)
    throw InputError(path_, "magic",
                     std::string("not a ") + what + " file (it does not start with \"" + std::string(magic, 8) +
                         "\")");
  if (got < 16)
    throw InputError(path_, "header", "file ends inside the header (" + std::to_string(got) + " bytes)");
  const std::uint32_t file_version = get_field<std::uint32_t>(header, 8);
  if (file_version != version)
    throw InputError(path_, "header.version",
                     "format version " + std::to_string(file_version) + ", this build reads version " +
                         std::to_string(version));
  const std::uint32_t file_header_size = get_field<std::uint32_t>(header, 12);
  if (file_header_size != header_size)
    throw InputError(path_, "header.header_size",
                     "is " + std::to_string(file_header_size) + ", version " + std::to_string(version) + " has " +
                         std::to_string(header_size));
  if (got < header_size)
    throw InputError(path_, "header",
                     "file ends inside the header (" + std::to_string(got) + " of " + std::to_string(header_size) +
                         " bytes)");
}

void BinaryFileReader::expect_size(std::uint64_t expected, const std::string& header_says) const {
  if (size_ == expected) return;
  constexpr std::uint64_t kOverflow = std::numeric_limits<std::uint64_t>::max();
  throw InputError(path_, "payload",
                   "file is " + std::to_string(size_) + " bytes, the header (" + header_says + ") needs " +
                       (expected == kOverflow ? std::string("far more") : std::to_string(expected)) +
                       (size_ < expected ? ": truncated" : ": trailing bytes"));
}

void BinaryFileReader::read_padded(const char* name, void* data, std::size_t bytes) {
  // Large blocks straight into the vector, each hashed while still in cache.
  constexpr std::size_t kChunk = std::size_t{4} << 20;
  auto* p = static_cast<unsigned char*>(data);
  for (std::size_t done = 0; done < bytes;) {
    const std::size_t want = std::min(kChunk, bytes - done);
    if (std::fread(p + done, 1, want, file_.get()) != want)
      throw InputError(path_, name, "file ended early (changed while being read?)");
    checksum_.update(p + done, want);
    done += want;
  }
  unsigned char pad[8] = {};
  const std::size_t pad_bytes = padded8(bytes) - bytes;
  if (std::fread(pad, 1, pad_bytes, file_.get()) != pad_bytes)
    throw InputError(path_, name, "file ended early (changed while being read?)");
  checksum_.update(pad, pad_bytes);
}

void BinaryFileReader::expect_checksum(std::uint64_t stored) const {
  const std::uint64_t actual = checksum_.digest();
  if (actual != stored)
    throw InputError(path_, "header.checksum",
                     "the payload's checksum is " + hex_u64(actual) + ", the header says " + hex_u64(stored) +
                         ": the file is damaged");
}

// ---------------------------------------------------------------- writing

void BinaryFileWriter::write(const void* data, std::size_t bytes) {
  if (bytes > 0 && std::fwrite(data, 1, bytes, file_) != bytes)
    throw InputError(path_, "", std::string("write failed: ") + std::strerror(errno));
}

void BinaryFileWriter::write_padded(const void* data, std::size_t bytes) {
  write(data, bytes);
  write(kZeros, padded8(bytes) - bytes);
}

void write_binary_file_atomically(const std::string& path, const std::function<void(BinaryFileWriter&)>& write) {
  // Straight from memory into the temporary file, renamed over `path` when complete.
  write_file_atomically_with(path, [&](const std::string& temporary) {
    std::unique_ptr<std::FILE, binary_file_detail::FileCloser> f(std::fopen(temporary.c_str(), "wb"));
    if (!f) throw InputError(path, "", std::string("cannot open for writing: ") + std::strerror(errno));
    BinaryFileWriter out(path, f.get());
    write(out);
    if (std::fflush(f.get()) != 0) throw InputError(path, "", std::string("write failed: ") + std::strerror(errno));
    if (std::fclose(f.release()) != 0)
      throw InputError(path, "", std::string("write failed: ") + std::strerror(errno));
  });
}

}  // namespace glasspiv
