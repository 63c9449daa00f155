#pragma once
// Outputs are written atomically: into a temporary file beside the target, then
// renamed over it, so a crash never leaves a half-written file and an existing
// file is only replaced by a complete one.
#include <functional>
#include <string>
#include <string_view>

namespace glasspiv {

// Writes `contents` to `path` atomically. Throws InputError naming `path` on failure.
void write_file_atomically(const std::string& path, std::string_view contents);

// Calls `write(temporary_path)` to produce the file (for writers such as OpenCV's
// that insist on a path), then renames it to `path`. The temporary keeps the
// target's extension so format-by-extension writers still work.
void write_file_atomically_with(const std::string& path,
                                const std::function<void(const std::string& temporary_path)>& write);

// Reads a whole file; throws InputError naming `path` if it cannot be read.
std::string read_file(const std::string& path);

}  // namespace glasspiv
