#pragma once
// Hand-made image files for the reader tests: a PNG or a baseline TIFF whose
// header states any size, with a few bytes of pixel data (what a damaged or
// hostile file looks like).
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace glasspiv {

inline std::uint32_t crc32_of(const std::string& bytes) {
  std::uint32_t crc = 0xffffffffu;
  for (unsigned char c : bytes) {
    crc ^= c;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}
inline std::string big_endian(std::uint32_t v) {
  return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
}
inline std::string png_chunk(const std::string& type, const std::string& data) {
  return big_endian(std::uint32_t(data.size())) + type + data + big_endian(crc32_of(type + data));
}
// 8-bit gray; `idat`: the compressed stream (here: any few bytes).
inline std::string png_claiming(std::uint32_t width, std::uint32_t height, const std::string& idat) {
  const std::string ihdr = big_endian(width) + big_endian(height) + std::string{8, 0, 0, 0, 0};
  return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", idat) +
         png_chunk("IEND", "");
}
// The same with the zlib stream of one zero byte as its data.
inline std::string png_claiming(std::uint32_t width, std::uint32_t height) {
  return png_claiming(width, height, std::string("\x78\x9c\x63\x00\x00\x00\x01\x00\x01", 9));
}
inline std::string little_endian(std::uint32_t v, int bytes) {
  std::string s;
  for (int i = 0; i < bytes; ++i) s += char(v >> (8 * i));
  return s;
}
// 8-bit gray, uncompressed, one strip (or, with tile sides, one tile) of 16 bytes.
inline std::string tiff_claiming(std::uint32_t width, std::uint32_t height, std::uint32_t tile_width = 0,
                          std::uint32_t tile_height = 0) {
  const std::string data(16, '\0');
  struct Entry { std::uint16_t tag, type; std::uint32_t value; };  // type 3: SHORT, 4: LONG
  std::vector<Entry> entries = {{256, 4, width}, {257, 4, height}, {258, 3, 8}, {259, 3, 1}, {262, 3, 1}};
  if (tile_width > 0) {
    entries.insert(entries.end(), {{277, 3, 1}, {322, 4, tile_width}, {323, 4, tile_height}, {324, 4, 8},
                                   {325, 4, std::uint32_t(data.size())}});
  } else {
    entries.insert(entries.end(), {{273, 4, 8}, {277, 3, 1}, {278, 4, height}, {279, 4, std::uint32_t(data.size())}});
  }
  std::string tiff = "II*" + std::string(1, '\0') + little_endian(8 + std::uint32_t(data.size()), 4) + data;
  tiff += little_endian(std::uint32_t(entries.size()), 2);
  for (const Entry& e : entries)
    tiff += little_endian(e.tag, 2) + little_endian(e.type, 2) + little_endian(1, 4) +
            (e.type == 3 ? little_endian(e.value, 2) + std::string(2, '\0') : little_endian(e.value, 4));
  return tiff + little_endian(0, 4);
}
inline void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

}  // namespace glasspiv
