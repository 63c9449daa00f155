#include "util/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "util/input_error.h"

namespace glasspiv {
namespace {

// What a file that is not a regular file is, in a message.
std::string not_regular(mode_t mode) {
  if (S_ISDIR(mode)) return "is a folder, expected a file";
  const char* kind = S_ISFIFO(mode)  ? "a fifo"
                     : S_ISCHR(mode) ? "a character device"
                     : S_ISBLK(mode) ? "a block device"
                     : S_ISSOCK(mode) ? "a socket"
                                      : "not a regular file";
  return std::string("is ") + kind + ", not a regular file; glasspiv reads regular files only";
}

std::string stat_problem(int error) {
  if (error == ENOENT) return "file does not exist";
  if (error == ENOTDIR) return "file does not exist (a part of its path is a file, not a folder)";
  if (error == ENAMETOOLONG) return "the name is too long for the file system";
  return std::string("cannot read: ") + std::strerror(error);
}

}  // namespace

std::string input_file_problem(const std::string& path) {
  if (path.empty()) return "no file name given";
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return stat_problem(errno);
  if (!S_ISREG(st.st_mode)) return not_regular(st.st_mode);
  return "";
}

void check_input_file(const std::string& path, const std::string& field) {
  const std::string problem = input_file_problem(path);
  if (!problem.empty()) throw InputError(path, field, problem);
}

int open_input_file(const std::string& path, const std::string& field) {
  check_input_file(path, field);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    const int error = errno;
    throw InputError(path, field, error == ENOENT ? stat_problem(error) : std::string("cannot open: ") + std::strerror(error));
  }
  struct stat st {};
  std::string problem;
  if (::fstat(fd, &st) != 0)
    problem = std::string("cannot read: ") + std::strerror(errno);
  else if (!S_ISREG(st.st_mode))
    problem = not_regular(st.st_mode);  // replaced between the check and the open
  if (!problem.empty()) {
    ::close(fd);
    throw InputError(path, field, problem);
  }
  // Regular files ignore O_NONBLOCK for reads; cleared anyway so that readers see plain blocking I/O.
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  return fd;
}

}  // namespace glasspiv
