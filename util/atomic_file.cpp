#include "util/atomic_file.h"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <random>
#include <regex>
#include <set>
#include <sstream>

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include "util/input_error.h"
#include "util/input_file.h"

namespace glasspiv {
namespace fs = std::filesystem;

namespace {

// ---- The signal table: temporaries in flight, unlinked on SIGINT/SIGTERM/SIGHUP.

constexpr std::size_t kPathCapacity = 4096;
enum SlotState : int { kFree = 0, kFilling = 1, kActive = 2 };
struct Slot {
  std::atomic<int> state{kFree};
  char path[kPathCapacity];
};
Slot g_slots[kMaxTrackedTemporaries];

constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};
constexpr int kSignalCount = sizeof(kSignals) / sizeof(kSignals[0]);
struct sigaction g_previous[kSignalCount];
std::atomic<bool> g_installed[kSignalCount];

// Async-signal-safe: atomics (lock-free), unlink, sigaction, raise.
void remove_temporaries_and_reraise(int sig) {
  const int saved_errno = errno;
  for (Slot& s : g_slots)
    if (s.state.load(std::memory_order_acquire) == kActive) ::unlink(s.path);
  for (int i = 0; i < kSignalCount; ++i)
    if (kSignals[i] == sig && g_installed[i].load()) ::sigaction(sig, &g_previous[i], nullptr);
  errno = saved_errno;
  ::raise(sig);  // delivered with the previous disposition once this handler returns
}

void install_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");
    for (int i = 0; i < kSignalCount; ++i) {
      struct sigaction current{};
      if (::sigaction(kSignals[i], nullptr, &current) != 0) continue;
      // Leave ignored signals ignored and handlers the program installed itself in place.
      if ((current.sa_flags & SA_SIGINFO) || current.sa_handler != SIG_DFL) continue;
      struct sigaction ours{};
      ours.sa_handler = remove_temporaries_and_reraise;
      sigemptyset(&ours.sa_mask);
      for (int s : kSignals) sigaddset(&ours.sa_mask, s);  // one cleanup at a time
      ours.sa_flags = 0;
      g_previous[i] = current;
      if (::sigaction(kSignals[i], &ours, nullptr) == 0) g_installed[i].store(true);
    }
  });
}

// A temporary in the table for as long as it lives; removed (file and entry)
// unless committed.
class TrackedTemporary {
 public:
  explicit TrackedTemporary(std::string path) : path_(std::move(path)) {
    install_handlers();
    if (path_.size() >= kPathCapacity) return;  // untracked: the stale sweep still removes it
    for (int i = 0; i < kMaxTrackedTemporaries; ++i) {
      int expected = kFree;
      if (g_slots[i].state.compare_exchange_strong(expected, kFilling)) {
        std::memcpy(g_slots[i].path, path_.c_str(), path_.size() + 1);
        g_slots[i].state.store(kActive, std::memory_order_release);
        slot_ = i;
        return;
      }
    }
  }
  ~TrackedTemporary() {
    if (!committed_) ::unlink(path_.c_str());
    if (slot_ >= 0) g_slots[slot_].state.store(kFree, std::memory_order_release);
  }
  TrackedTemporary(const TrackedTemporary&) = delete;
  TrackedTemporary& operator=(const TrackedTemporary&) = delete;
  const std::string& path() const { return path_; }
  void committed() { committed_ = true; }

 private:
  std::string path_;
  int slot_ = -1;
  bool committed_ = false;
};

// ---- Names.

std::string host_name() {
  char name[256] = {};
  if (::gethostname(name, sizeof(name) - 1) != 0 || name[0] == 0) return "host";
  std::string h(name);
  for (char& c : h)
    if (c == '/' || c == '\\' || static_cast<unsigned char>(c) < 32) c = '_';
  return h.substr(0, 64);
}

const std::string& this_host() {
  static const std::string host = host_name();
  return host;
}

std::string temporary_path_for(const std::string& path) {
  const fs::path target(path);
  std::random_device seed;
  std::string stem = target.stem().string();
  if (stem.size() > 120) stem.resize(120);  // the name stays within NAME_MAX
  const std::string name = "." + stem + ".tmp-" + this_host() + "-" + std::to_string(::getpid()) + "-" +
                           std::to_string(seed() % 1000000) + target.extension().string();
  return (target.parent_path() / name).string();
}

// Removes the temporaries left in `dir` by processes of this host that no
// longer run (killed outright, or by earlier versions that left them on a
// signal). Once per folder per process: a long series scans its folder once.
void remove_stale_temporaries(const fs::path& dir) {
  static std::mutex mutex;
  static std::set<std::string> swept;
  const fs::path folder = dir.empty() ? fs::path(".") : dir;
  {
    std::error_code ec;
    const std::string key = fs::absolute(folder, ec).lexically_normal().string();
    std::lock_guard<std::mutex> lock(mutex);
    if (!swept.insert(key).second) return;
  }
  static const std::regex current(R"(^\..*\.tmp-(.+)-([0-9]{1,9})-([0-9]{1,6})(\.[^.]*)?$)");
  static const std::regex earlier(R"(^\..*\.tmp([0-9]{1,9})-([0-9]{1,6})(\.[^.]*)?$)");  // no host in the name
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() < 6 || name[0] != '.' || name.find(".tmp") == std::string::npos) continue;
    std::smatch m;
    long pid = 0;
    if (std::regex_match(name, m, current)) {
      if (m[1].str() != this_host()) continue;  // another machine's (a shared folder): not ours to judge
      pid = std::stol(m[2].str());
    } else if (std::regex_match(name, m, earlier)) {
      pid = std::stol(m[1].str());
    } else {
      continue;
    }
    if (pid <= 0 || pid == ::getpid()) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // still running (or not ours to ask)
    std::error_code st;
    if (fs::symlink_status(it->path(), st).type() != fs::file_type::regular) continue;
    fs::remove(it->path(), st);
  }
}

std::string file_kind(fs::file_type type) {
  switch (type) {
    case fs::file_type::directory: return "a folder";
    case fs::file_type::symlink: return "a symbolic link";
    case fs::file_type::block: return "a block device";
    case fs::file_type::character: return "a character device";
    case fs::file_type::fifo: return "a fifo";
    case fs::file_type::socket: return "a socket";
    default: return "not a regular file";
  }
}

void prepare_folder(const std::string& path) {
  const fs::path target(path);
  if (target.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(target.parent_path(), ec);
    if (ec) throw InputError(path, "", "cannot create the output folder: " + ec.message());
  }
  remove_stale_temporaries(target.parent_path());
}

// fsync(2) of a file or folder, so that what a rename publishes survives a power
// loss: the temporary's data before it is renamed, the folder's entry after.
// Filesystems that cannot sync a folder (EINVAL) are not an error.
void sync_path(const std::string& sync, const std::string& path, bool folder) {
  const int fd = ::open(sync.c_str(), O_RDONLY | O_CLOEXEC | (folder ? O_DIRECTORY : 0));
  if (fd < 0) throw InputError(path, "", std::string("cannot write the output: open for fsync: ") + std::strerror(errno));
  int result;
  do result = ::fsync(fd);
  while (result != 0 && errno == EINTR);
  const int error = errno;
  ::close(fd);
  if (result != 0 && !(folder && (error == EINVAL || error == ENOTSUP)))
    throw InputError(path, "", std::string("cannot write the output: fsync: ") + std::strerror(error));
}

// The temporary made durable, checked, renamed over `path`, and the rename made durable.
void rename_into_place(const TrackedTemporary& temporary, const std::string& path) {
  sync_path(temporary.path(), path, false);
  check_replaceable_output(path);  // again: it may have appeared while writing
  std::error_code ec;
  fs::rename(temporary.path(), path, ec);
  if (ec) throw InputError(path, "", "cannot write the output: " + ec.message());
  const fs::path parent = fs::path(path).parent_path();
  sync_path(parent.empty() ? "." : parent.string(), path, true);
}

}  // namespace

void check_replaceable_output(const std::string& path) {
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(path, ec);
  if (ec || st.type() == fs::file_type::not_found || st.type() == fs::file_type::regular) return;
  throw InputError(path, "",
                   "exists and is " + file_kind(st.type()) +
                       "; glasspiv replaces regular files only (remove it or choose another name)");
}

void write_file_atomically_with(const std::string& path,
                                const std::function<void(const std::string&)>& write) {
  check_replaceable_output(path);
  prepare_folder(path);
  TrackedTemporary temporary(temporary_path_for(path));
  write(temporary.path());
  rename_into_place(temporary, path);
  temporary.committed();
}

void write_files_atomically(const std::vector<AtomicFileWriter>& writers) {
  for (const auto& w : writers) check_replaceable_output(w.first);
  std::vector<std::unique_ptr<TrackedTemporary>> temporaries;
  for (const auto& [path, write] : writers) {
    prepare_folder(path);
    temporaries.push_back(std::make_unique<TrackedTemporary>(temporary_path_for(path)));
    write(temporaries.back()->path());
  }
  for (const auto& w : writers) check_replaceable_output(w.first);
  for (std::size_t i = 0; i < writers.size(); ++i) {
    rename_into_place(*temporaries[i], writers[i].first);
    temporaries[i]->committed();
  }
}

void write_file_atomically(const std::string& path, std::string_view contents) {
  write_file_atomically_with(path, [&](const std::string& temporary) {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path, "", std::string("cannot open for writing: ") + std::strerror(errno));
    const auto failed = [&path]() {
      const int error = errno;
      return InputError(path, "", std::string("write failed: ") + (error ? std::strerror(error) : "the disk may be full"));
    };
    errno = 0;
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.flush();
    if (!out) throw failed();
    out.close();
    if (!out) throw failed();
  });
}

std::string read_file(const std::string& path) {
  const int fd = open_input_file(path);  // a regular file, or a one-line InputError (a fifo never blocks)
  std::string contents;
  char block[1 << 16];
  for (;;) {
    const ssize_t got = ::read(fd, block, sizeof block);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) {
      const int error = errno;
      ::close(fd);
      throw InputError(path, "", std::string("cannot read: ") + std::strerror(error));
    }
    if (got == 0) break;
    contents.append(block, static_cast<std::size_t>(got));
  }
  ::close(fd);
  return contents;
}

}  // namespace glasspiv
