#include "util/yaml_fields.h"

#include <cctype>
#include <climits>
#include <cmath>

#include <fmt/format.h>

#include "util/input_error.h"
#include "util/text_number.h"

namespace glasspiv {

YAML::Node YamlFields::load_mapping(std::string_view contents, const std::string& what) const {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(contents));
  } catch (const YAML::Exception& e) {
    throw InputError(path_, "", fmt::format("malformed YAML, line {}: {}", e.mark.line + 1, e.msg));
  }
  if (!root.IsMap()) throw InputError(path_, "", "expected a YAML mapping of " + what);
  return root;
}

void YamlFields::fail(const std::string& field, const YAML::Node& node, const std::string& problem) const {
  const int line = node.IsDefined() ? node.Mark().line : -1;
  throw InputError(path_, field, line >= 0 ? fmt::format("line {}: {}", line + 1, problem) : problem);
}

double YamlFields::real(const YAML::Node& node, const std::string& field) const {
  if (!node.IsScalar()) fail(field, node, "must be a number");
  const std::string& text = node.Scalar();
  const std::optional<double> value = parse_number(text);
  // YAML spells the non-finite values .nan, .inf, -.inf.
  std::string lower = text.substr(!text.empty() && (text[0] == '+' || text[0] == '-') ? 1 : 0);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const bool yaml_special = lower == ".nan" || lower == ".inf";
  if (yaml_special || (value && !std::isfinite(*value))) fail(field, node, "must be a finite number, got " + text);
  if (!value) fail(field, node, "must be a number, got '" + text + "'");
  return *value;
}

std::vector<double> YamlFields::reals(const YAML::Node& node, const std::string& field,
                                      std::optional<std::size_t> size) const {
  if (!node.IsSequence())
    fail(field, node, size ? fmt::format("must be a list of {} numbers", *size) : "must be a list of numbers");
  if (size && node.size() != *size) fail(field, node, fmt::format("must have {} values, has {}", *size, node.size()));
  std::vector<double> values;
  for (std::size_t i = 0; i < node.size(); ++i) values.push_back(real(node[i], fmt::format("{}[{}]", field, i)));
  return values;
}

int YamlFields::whole(const YAML::Node& node, const std::string& field, int min) const {
  const double value = real(node, field);
  if (value != std::floor(value) || std::fabs(value) > INT_MAX)
    fail(field, node, "must be a whole number, got " + node.Scalar());
  if (value < min) fail(field, node, fmt::format("must be {} or more, got {}", min, node.Scalar()));
  return static_cast<int>(value);
}

std::string YamlFields::text(const YAML::Node& node, const std::string& field) const {
  if (!node.IsScalar()) fail(field, node, "must be a text");
  return node.Scalar();
}

}  // namespace glasspiv
