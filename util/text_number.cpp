#include "util/text_number.h"

#include <charconv>
#include <cmath>

#include <fmt/format.h>

namespace glasspiv {

std::string format_number(double value) { return fmt::format("{}", value); }

std::string format_real(double value) {
  std::string text = format_number(value);
  if (std::isfinite(value) && text.find_first_of(".eE") == std::string::npos) text += ".0";
  return text;
}

std::optional<double> parse_number(std::string_view text) {
  const bool plus = !text.empty() && text.front() == '+';
  if (plus) text.remove_prefix(1);
  if (text.empty() || (plus && text.front() == '-')) return std::nullopt;
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

}  // namespace glasspiv
