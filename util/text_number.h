#pragma once
// Numbers as text for every reader and writer: locale-free and exact both ways.
#include <optional>
#include <string>
#include <string_view>

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

}  // namespace glasspiv
