#pragma once
// Whether inputs named by different paths are the same data: the same file
// (device and inode, after symlinks are resolved, so `dir/a.png`,
// `./dir/a.png`, a hard link and a symlink to it are one file) or files with
// identical bytes (a copy). A command that counts its inputs as independent
// views (photos) refuses such a pair: the same photo twice is one view, and
// counting it twice halves the reported uncertainty. No console I/O.
#include <optional>
#include <string>
#include <vector>

namespace glasspiv {

struct SameInput {
  std::size_t first = 0, second = 0;  // indices into the paths, first < second
  bool same_file = false;             // true: one file (identity); false: identical bytes
};

// The first pair (by the second index, then the first) of paths that are the
// same file or hold identical bytes; std::nullopt if all are distinct. Files
// are compared by size, then by an XXH64 of their bytes, then byte by byte.
// A path that cannot be read is left to the caller's reader (never a pair).
std::optional<SameInput> find_same_input(const std::vector<std::string>& paths);

// InputError(paths[second], field, "is the same file as / has the same bytes as
// 'paths[first]' ...") for the pair find_same_input finds; `what` names the
// inputs in the message ("photo").
void check_distinct_inputs(const std::vector<std::string>& paths, const std::string& field, const std::string& what);

}  // namespace glasspiv
