#pragma once
// Numbers as text for the targets/ file readers and writers: locale-free,
// exact both ways.
#include <optional>
#include <string>
#include <string_view>

namespace glasspiv::targets_detail {

// The shortest decimal text that reads back as exactly `value` ("15", "0.1", "1e-05").
std::string format_number(double value);
// All of `text` as a double, or nullopt (a leading '+' is allowed; the caller
// checks finiteness).
std::optional<double> parse_number(std::string_view text);

}  // namespace glasspiv::targets_detail
