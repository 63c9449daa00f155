#pragma once
// JSON documents as glasspiv reads them (observations, pose and fit results):
// like nlohmann::json::parse, but every problem is an InputError naming the
// file, the field and the line in glasspiv's words, never the library's text:
// malformed text, NaN or Infinity (not JSON), a number beyond a double's range
// ("1e999"), a key given twice in an object (json::parse keeps the last), and
// nesting deeper than kMaxJsonDepth.
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace glasspiv {

constexpr int kMaxJsonDepth = 64;

// `contents` read from `path` (named in the errors).
nlohmann::json parse_json_document(std::string_view contents, const std::string& path);
// The file at `path` (util/atomic_file.h read_file: a regular file) parsed as above.
nlohmann::json read_json_document(const std::string& path);

// JSON text for an output file: indented by 2, invalid UTF-8 in texts (a name
// from a file) replaced by U+FFFD instead of an exception.
std::string json_text(const nlohmann::json& j);

}  // namespace glasspiv
