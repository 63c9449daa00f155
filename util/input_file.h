#pragma once
// Every file glasspiv reads is a regular file: a fifo, a device, a socket or a
// folder where a file is expected is refused before it is opened, so that no
// reader blocks forever in open() on a fifo nobody writes or reads a device
// without end. Every reader (util/atomic_file.h read_file, util/binary_file.h,
// util/image_file.h, the mesh, flow and photo readers) goes through here.
#include <string>

namespace glasspiv {

// Throws InputError(path, field, ...) unless `path` names an existing regular
// file (symbolic links followed): "file does not exist", "is a folder, expected
// a file", "is a fifo, not a regular file; glasspiv reads regular files only".
void check_input_file(const std::string& path, const std::string& field = "");

// The same check as a text for a validator: "" when `path` is a regular file,
// else the problem (without the path).
std::string input_file_problem(const std::string& path);

// Opens `path` read-only (close-on-exec, and O_NONBLOCK so that a fifo swapped
// in after the check still cannot block), then checks the open file itself
// with fstat: a file descriptor of a regular file, or InputError as above. The
// caller closes it.
int open_input_file(const std::string& path, const std::string& field = "");

}  // namespace glasspiv
