#include "apps/cli_files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <climits>
#include <filesystem>
#include <map>
#include <set>

#include <fmt/format.h>

#include "render/scene.h"
#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {

namespace fs = std::filesystem;

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

std::string folder_shown(const std::string& folder) {
  return !folder.empty() && folder.back() == '/' ? folder : folder + "/";
}

namespace {

// The identity of a file name: the file on disk (device and inode: links and
// hard links are one file) if it exists, else its absolute path with the
// existing part resolved and `.`, `..` removed, which is the file the writer
// will create (its folders created first: `new/../a` is `a`).
std::string identity(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) return fmt::format("i:{}:{}", st.st_dev, st.st_ino);
  std::error_code ec;
  fs::path p = fs::absolute(path, ec);
  const fs::path c = fs::weakly_canonical(p, ec);
  const fs::path resolved = (ec ? p : c).lexically_normal();
  if (::stat(resolved.c_str(), &st) == 0) return fmt::format("i:{}:{}", st.st_dev, st.st_ino);
  return "p:" + resolved.string();
}

// Outputs are named by users and derived by commands (out_edges.png, DIR/frame.tif):
// a name the file system cannot hold is refused here, in words, not by a
// filesystem_error deep in the work.
void check_name_lengths(const OutputFile& out) {
  if (out.path.size() >= PATH_MAX)
    throw InputError(out.path.substr(0, 60) + "...", out.field,
                     fmt::format("the path is {} bytes long, over the system's limit of {}", out.path.size(),
                                 PATH_MAX - 1));
  for (const fs::path& part : fs::path(out.path)) {
    const std::string name = part.string();
    if (name.size() > NAME_MAX)
      throw InputError(out.path.size() > 120 ? out.path.substr(0, 60) + "..." : out.path, out.field,
                       fmt::format("the name '{}...' is {} bytes long, over the file system's limit of {} bytes a "
                                   "name",
                                   name.substr(0, 40), name.size(), NAME_MAX));
  }
}

OutputKind kind_of_extension(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".png" || ext == ".tif" || ext == ".tiff" || ext == ".exr") return OutputKind::image;
  if (ext == ".json") return OutputKind::json;
  if (ext == ".tmap") return OutputKind::transport_map;
  if (ext == ".gop") return OutputKind::correction_operator;
  if (ext == ".pdf") return OutputKind::pdf;
  static const std::set<std::string> text = {".yaml", ".yml", ".xml",  ".cameramodel", ".txt", ".csv", ".dat",
                                             ".vtk",  ".html", ".htm", ".svg",         ".vnl", ".md"};
  if (text.count(ext)) return OutputKind::text;
  return OutputKind::by_extension;  // anything: not checked
}

const char* kind_name(OutputKind kind) {
  switch (kind) {
    case OutputKind::image: return "an image";
    case OutputKind::json: return "a JSON file";
    case OutputKind::text: return "a text file";
    case OutputKind::pdf: return "a PDF file";
    case OutputKind::transport_map: return "a transport map file";
    case OutputKind::correction_operator: return "a correction operator file";
    case OutputKind::folder: return "a folder";
    case OutputKind::by_extension: break;
  }
  return "a file";
}

bool starts_with_bytes(const std::string& head, const char* magic, std::size_t n) {
  return head.size() >= n && head.compare(0, n, magic, n) == 0;
}

bool is_image_signature(const std::string& h) {
  return starts_with_bytes(h, "\x89PNG\r\n\x1a\n", 8) || starts_with_bytes(h, "II*\0", 4) ||
         starts_with_bytes(h, "MM\0*", 4) || starts_with_bytes(h, "II+\0", 4) || starts_with_bytes(h, "MM\0+", 4) ||
         starts_with_bytes(h, "\x76\x2f\x31\x01", 4) || starts_with_bytes(h, "\xff\xd8\xff", 3) ||
         starts_with_bytes(h, "BM", 2) ||
         (h.size() >= 3 && h[0] == 'P' && h[1] >= '1' && h[1] <= '6' && std::isspace(static_cast<unsigned char>(h[2])));
}

// The first bytes of an existing regular file (opened without blocking).
std::string head_of(const std::string& path, std::size_t bytes) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return "";
  struct stat st {};
  std::string head;
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode)) {
    head.resize(bytes);
    const ssize_t got = ::read(fd, head.data(), bytes);
    head.resize(got > 0 ? static_cast<std::size_t>(got) : 0);
  }
  ::close(fd);
  return head;
}

}  // namespace

std::string output_kind_problem(const std::string& path, OutputKind kind) {
  if (kind == OutputKind::by_extension) kind = kind_of_extension(path);
  if (kind == OutputKind::by_extension || kind == OutputKind::folder) return "";
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_size == 0) return "";
  const std::string h = head_of(path, 4096);
  if (h.empty()) return "";
  bool same = false;
  switch (kind) {
    case OutputKind::image: same = is_image_signature(h); break;
    case OutputKind::pdf: same = starts_with_bytes(h, "%PDF-", 5); break;
    case OutputKind::transport_map: same = starts_with_bytes(h, "GPIVTMAP", 8); break;
    case OutputKind::correction_operator: same = starts_with_bytes(h, "GPIVCOPR", 8); break;
    case OutputKind::json: {
      const std::size_t first = h.find_first_not_of(" \t\r\n");
      same = first != std::string::npos && (h[first] == '{' || h[first] == '[');
      break;
    }
    case OutputKind::text:
      same = h.find('\0') == std::string::npos && !is_image_signature(h) && !starts_with_bytes(h, "%PDF-", 5) &&
             !starts_with_bytes(h, "GPIV", 4);
      break;
    case OutputKind::by_extension:
    case OutputKind::folder: same = true; break;
  }
  if (same) return "";
  return fmt::format("exists and is not {}; glasspiv replaces only a file of the kind it writes (remove it or choose "
                     "another name)",
                     kind_name(kind));
}

namespace {

void check_creatable(const OutputFile& out) {
  std::error_code ec;
  fs::path dir = fs::absolute(out.path, ec);
  if (out.kind != OutputKind::folder) dir = dir.parent_path();
  while (!dir.empty() && !fs::exists(dir, ec)) {
    if (dir == dir.root_path()) break;
    dir = dir.parent_path();
  }
  if (dir.empty()) return;
  if (!fs::is_directory(dir, ec))
    throw InputError(out.path, out.field, fmt::format("cannot be created: {} is a file, not a folder", dir.string()));
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw InputError(out.path, out.field, fmt::format("cannot be created: no permission to write in {}", dir.string()));
}

}  // namespace

void check_outputs(const std::vector<std::string>& inputs, const std::vector<OutputFile>& outputs) {
  // Keys once per name: a series of thousands of frames stays fast.
  std::map<std::string, const std::string*> input_ids;
  for (const std::string& in : inputs)
    if (!in.empty()) input_ids.emplace(identity(in), &in);
  std::map<std::string, const OutputFile*> output_ids;
  for (const OutputFile& out : outputs) {
    const std::string id = identity(out.path);
    if (const auto it = input_ids.find(id); it != input_ids.end())
      throw InputError(out.path, out.field,
                       *it->second == out.path
                           ? "is an input file; glasspiv never overwrites its inputs"
                           : fmt::format("is the input file {}; glasspiv never overwrites its inputs", *it->second));
    // Two folder outputs may be one folder (a report and overlays side by side):
    // the files written into it are outputs of their own, checked here too.
    if (out.kind == OutputKind::folder) {
      check_name_lengths(out);
      std::error_code ec;
      const fs::file_type t = fs::status(out.path, ec).type();  // a link to a folder is a folder
      if (!ec && t != fs::file_type::not_found && t != fs::file_type::directory)
        throw InputError(out.path, out.field, "exists and is not a folder");
      continue;
    }
    if (const auto [it, fresh] = output_ids.emplace(id, &out); !fresh)
      throw InputError(out.path, out.field,
                       fmt::format("is the same output as {} ({}): every output must be a file of its own",
                                   it->second->path, it->second->field));
    check_name_lengths(out);
    try {
      check_replaceable_output(out.path);
    } catch (const InputError& e) {
      throw InputError(out.path, out.field, e.problem());
    }
    if (const std::string problem = output_kind_problem(out.path, out.kind); !problem.empty())
      throw InputError(out.path, out.field, problem);
  }
  std::set<std::string> folders;  // each output folder checked once
  for (const OutputFile& out : outputs) {
    std::error_code ec;
    const fs::path path = fs::absolute(out.path, ec);
    if (folders.insert((out.kind == OutputKind::folder ? path : path.parent_path()).string()).second) check_creatable(out);
  }
}

std::vector<std::string> scene_input_files(const Scene& scene) {
  std::vector<std::string> files;
  if (!scene.source.empty()) files.push_back(scene.source);
  for (const SceneCamera& c : scene.cameras)
    if (!c.file.empty()) files.push_back(c.file);
  for (const MeshSolid& m : scene.meshes)
    if (!m.file.empty()) files.push_back(m.file);
  for (const RectangleSolid& r : scene.rectangles)
    if (!r.texture.empty()) files.push_back(r.texture);
  return files;
}

void make_output_folder(const std::string& folder, const std::string& field) {
  if (folder.empty()) return;
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw InputError(folder, field, "cannot create the folder: " + ec.message());
}

void check_output_folder(const std::string& folder, const std::string& field) {
  check_name_lengths({folder, field, OutputKind::folder});
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(folder, ec);
  if (ec || st.type() == fs::file_type::not_found) return;
  if (!fs::is_directory(folder, ec))
    throw InputError(folder, field, "exists and is not a folder");
  for (fs::recursive_directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::file_type t = it->symlink_status(ec).type();
    if (t == fs::file_type::directory) continue;
    if (t == fs::file_type::regular) {
      // The command may replace any file of the folder: only by one of the kind its name says.
      if (const std::string problem = output_kind_problem(it->path().string(), OutputKind::by_extension);
          !problem.empty())
        throw InputError(it->path().string(), field, problem);
      continue;
    }
    try {
      check_replaceable_output(it->path().string());
    } catch (const InputError& e) {
      throw InputError(it->path().string(), field, e.problem() + "; the folder may hold only files and folders");
    }
  }
}

}  // namespace glasspiv
