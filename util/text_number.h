#pragma once
// Numbers as text for every reader and writer: locale-free and exact both ways.
#include <charconv>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>

namespace glasspiv {

// The shortest decimal text that reads back as exactly `value` ("15", "0.1", "1e-05").
std::string format_number(double value);
// The same, always with a '.' or an exponent, so formats that type their values
// see a real number ("600.0", "1e-05").
std::string format_real(double value);
// All of `text` as a double, correctly rounded; nullopt unless the whole text is
// one number (a leading '+' is allowed; "nan" and "inf" parse, so callers check
// finiteness).
std::optional<double> parse_number(std::string_view text);

// All of `text` as a whole number of type T in decimal (an optional leading '+'
// or '-'; "-0" is 0 for unsigned types too); nullopt unless the whole text is
// one such number within T's range: never wrapped, never saturated.
template <typename T>
std::optional<T> parse_integer(std::string_view text) {
  static_assert(std::is_integral_v<T> && !std::is_same_v<T, bool>);
  bool negative = false;
  if (!text.empty() && (text.front() == '+' || text.front() == '-')) {
    negative = text.front() == '-';
    text.remove_prefix(1);
  }
  if (text.empty() || text.find_first_not_of("0123456789") != std::string_view::npos) return std::nullopt;
  if (negative && std::is_unsigned_v<T>) {
    if (text.find_first_not_of('0') != std::string_view::npos) return std::nullopt;
    return T{0};
  }
  // from_chars reads the sign itself: put it back in front of the digits.
  std::string digits = negative ? "-" : "";
  digits.append(text);
  T value{};
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (ec != std::errc() || end != digits.data() + digits.size()) return std::nullopt;
  return value;
}

}  // namespace glasspiv
