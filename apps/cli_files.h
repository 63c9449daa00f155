#pragma once
// File-name checks shared by the commands.
#include <string>

namespace glasspiv {

// The extension of path, lower case, with its dot ("" if none).
std::string lower_extension(const std::string& path);

// Throws InputError if output names the same file as input: glasspiv never
// overwrites its inputs.
void check_not_input(const std::string& input, const std::string& output);

}  // namespace glasspiv
