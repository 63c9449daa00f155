#pragma once
// Reading typed fields out of a yaml-cpp document with errors that name the
// file, the field path and the line: the shared base of every YAML reader.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace glasspiv {

class YamlFields {
 public:
  explicit YamlFields(std::string path) : path_(std::move(path)) {}

  // Parses `contents` and checks it is a mapping; InputError naming the path
  // and the line for malformed YAML, or "expected a YAML mapping of <what>".
  YAML::Node load_mapping(std::string_view contents, const std::string& what) const;

  // Throws InputError(path, field, "line N: problem").
  [[noreturn]] void fail(const std::string& field, const YAML::Node& node, const std::string& problem) const;
  // A finite number (YAML's .nan / .inf are refused as not finite).
  double real(const YAML::Node& node, const std::string& field) const;
  // A list of finite numbers, of exactly `size` when given.
  std::vector<double> reals(const YAML::Node& node, const std::string& field,
                            std::optional<std::size_t> size = std::nullopt) const;
  // A whole number >= min.
  int whole(const YAML::Node& node, const std::string& field, int min) const;
  std::string text(const YAML::Node& node, const std::string& field) const;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace glasspiv
