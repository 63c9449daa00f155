#include "util/json_document.h"

#include <algorithm>
#include <cctype>
#include <vector>

#include <fmt/format.h>

#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

// Builds the document like json::parse, but refuses a key given twice in an
// object (json::parse keeps the last), a number beyond a double's range
// ("1e999") and nesting deeper than kMaxJsonDepth, each as an InputError
// naming the file and the field.
class JsonBuilder : public nlohmann::json_sax<nlohmann::json> {
 public:
  using json = nlohmann::json;
  JsonBuilder(const std::string& path, std::string_view contents, json& root)
      : path_(path), contents_(contents), root_(root) {}

  bool null() override { return add(nullptr); }
  bool boolean(bool v) override { return add(v); }
  bool number_integer(number_integer_t v) override { return add(v); }
  bool number_unsigned(number_unsigned_t v) override { return add(v); }
  bool number_float(number_float_t v, const string_t&) override { return add(v); }
  bool string(string_t& v) override { return add(v); }
  bool binary(binary_t& v) override { return add(json::binary(v)); }
  bool start_object(std::size_t) override { return open(json::object()); }
  bool start_array(std::size_t) override { return open(json::array()); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }
  bool key(string_t& k) override {
    if (open_.back().value->contains(k)) throw InputError(path_, child_field(k), "appears twice in the object");
    key_ = k;
    return true;
  }
  bool parse_error(std::size_t position, const std::string& last_token, const nlohmann::detail::exception& e) override {
    const std::string where = place_of(position);
    if (e.id == 406)
      throw InputError(path_, pending_field(),
                       fmt::format("{}: the number '{}' lies beyond a double's range (about 1.8e308)", where,
                                   last_token));
    // The word where the parser stopped (it reads "NaN" only up to the 'N'), printable.
    std::string token = word_around(position);
    if (token.empty()) token = last_token.size() > 20 ? last_token.substr(last_token.size() - 20) : last_token;
    for (char& c : token)
      if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) == 127) c = ' ';
    std::string lower = token;
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (!lower.empty() && (lower[0] == '-' || lower[0] == '+')) lower.erase(0, 1);
    // JSON has no spelling of NaN or infinity (Python's json module writes them anyway).
    if (lower == "nan" || lower == "inf" || lower == "infinity")
      throw InputError(path_, pending_field(),
                       fmt::format("{}: '{}' is not a JSON number (JSON has no NaN or Infinity; every number must be "
                                   "finite)",
                                   where, token));
    if (position >= contents_.size())
      throw InputError(path_, pending_field(), fmt::format("{}: the JSON text ends early (truncated?)", where));
    throw InputError(path_, pending_field(), fmt::format("{}: not valid JSON (near '{}')", where, token));
  }

 private:
  struct Open {
    json* value;
    std::string field;
  };
  std::string child_field(const std::string& key) const {
    const std::string& parent = open_.back().field;
    return parent.empty() ? key : parent + "." + key;
  }
  // The field of the value that comes next.
  std::string pending_field() const {
    if (open_.empty()) return "";
    const json& parent = *open_.back().value;
    if (parent.is_array()) return fmt::format("{}[{}]", open_.back().field, parent.size());
    return key_.empty() ? open_.back().field : child_field(key_);
  }
  // Places `v` where the next value goes; returns where it went.
  json* place(json&& v, std::string* field) {
    *field = pending_field();
    if (open_.empty()) {
      root_ = std::move(v);
      return &root_;
    }
    json& parent = *open_.back().value;
    if (parent.is_array()) {
      parent.push_back(std::move(v));
      return &parent.back();
    }
    json& slot = parent[key_];
    slot = std::move(v);
    key_.clear();
    return &slot;
  }
  bool add(json&& v) {
    std::string field;
    place(std::move(v), &field);
    return true;
  }
  bool open(json&& v) {
    std::string field;
    json* at = place(std::move(v), &field);
    if (open_.size() >= static_cast<std::size_t>(kMaxJsonDepth))
      throw InputError(path_, field, fmt::format("nested more than {} levels deep", kMaxJsonDepth));
    open_.push_back({at, field});
    return true;
  }
  bool close() {
    open_.pop_back();
    return true;
  }

  // The run of letters, digits, signs and dots around the byte the parser
  // stopped at (`position`, 1-based), at most 20 characters.
  std::string word_around(std::size_t position) const {
    const auto in_word = [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.';
    };
    if (position == 0 || position > contents_.size() || !in_word(contents_[position - 1])) return "";
    std::size_t begin = position - 1;
    while (begin > 0 && in_word(contents_[begin - 1])) --begin;
    std::string word;
    for (std::size_t i = begin; i < contents_.size() && word.size() < 20 && in_word(contents_[i]); ++i) word += contents_[i];
    return word;
  }

  // "line L, column C" of byte `position` (1-based, as the parser counts).
  std::string place_of(std::size_t position) const {
    const std::size_t end = std::min(position > 0 ? position - 1 : 0, contents_.size());
    std::size_t line = 1, column = 1;
    for (std::size_t i = 0; i < end; ++i) {
      if (contents_[i] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    return fmt::format("line {}, column {}", line, column);
  }

  const std::string& path_;
  std::string_view contents_;
  json& root_;
  std::vector<Open> open_;
  std::string key_;
};

}  // namespace

nlohmann::json parse_json_document(std::string_view contents, const std::string& path) {
  nlohmann::json root;
  JsonBuilder builder(path, contents, root);
  nlohmann::json::sax_parse(contents, &builder);
  return root;
}

nlohmann::json read_json_document(const std::string& path) { return parse_json_document(read_file(path), path); }

std::string json_text(const nlohmann::json& j) {
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

}  // namespace glasspiv
