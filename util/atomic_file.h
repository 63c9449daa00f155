#pragma once
// Outputs are written atomically: into a temporary file beside the target,
// fsync'ed, then renamed over it, and the folder fsync'ed, so neither a crash
// nor a power loss leaves a half-written file under the target's name, and an
// existing file is only replaced by a complete one.
//
// Temporaries are named ".<stem>.tmp-<host>-<pid>-<random><ext>" beside the
// target. They never outlive their writer:
//  - a writer that throws, and any failure after it (fsync, rename), removes
//    its temporary;
//  - SIGINT, SIGTERM and SIGHUP remove every temporary in flight (a fixed table
//    of paths unlinked by an async-signal-safe handler, which then re-raises the
//    signal with its previous disposition);
//  - a process killed outright (SIGKILL, power loss) leaves its temporaries, and
//    the next write into the same folder removes those of processes of this
//    host that no longer run.
// An existing target that is not a regular file (a device, a symbolic link, a
// folder, a fifo) is refused before anything is written: glasspiv replaces
// regular files only.
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace glasspiv {

// Writes `contents` to `path` atomically. Throws InputError naming `path` on failure.
void write_file_atomically(const std::string& path, std::string_view contents);

// Calls `write(temporary_path)` to produce the file (for writers such as OpenCV's
// that insist on a path), then renames it to `path`. The temporary keeps the
// target's extension so format-by-extension writers still work.
void write_file_atomically_with(const std::string& path,
                                const std::function<void(const std::string& temporary_path)>& write);

// Several outputs that stand or fall together: every writer fills its
// temporary first; only when all have succeeded are they renamed to their
// targets. If any writer throws, no target is touched and no temporary is left.
using AtomicFileWriter = std::pair<std::string, std::function<void(const std::string& temporary_path)>>;
void write_files_atomically(const std::vector<AtomicFileWriter>& writers);

// Throws InputError(path, "", ...) if `path` exists and is not a regular file
// (symbolic links are not followed). The writers above call it first.
void check_replaceable_output(const std::string& path);

// Reads a whole file; throws InputError naming `path` if it cannot be read.
std::string read_file(const std::string& path);

// Temporaries of the signal table: at most this many writes in flight at once
// are cleaned up by a signal (more are still written, and removed by the next
// write into their folder if a signal leaves them).
constexpr int kMaxTrackedTemporaries = 64;

}  // namespace glasspiv
