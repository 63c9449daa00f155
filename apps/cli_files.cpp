#include "apps/cli_files.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
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

void check_not_input(const std::string& input, const std::string& output) {
  std::error_code ec;
  if (fs::exists(output, ec) && fs::equivalent(input, output, ec))
    throw InputError(output, "", "is the input file; glasspiv never overwrites its inputs");
}

namespace {

// The identity of a file name: the file on disk (device and inode: links and
// hard links are one file) if it exists, else its absolute path with the
// existing part resolved.
std::string identity(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) return fmt::format("i:{}:{}", st.st_dev, st.st_ino);
  std::error_code ec;
  fs::path p = fs::absolute(path, ec);
  const fs::path c = fs::weakly_canonical(p, ec);
  return "p:" + (ec ? p : c).lexically_normal().string();
}

void check_creatable(const OutputFile& out) {
  std::error_code ec;
  fs::path dir = fs::absolute(out.path, ec).parent_path();
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
    if (const auto [it, fresh] = output_ids.emplace(id, &out); !fresh)
      throw InputError(out.path, out.field,
                       fmt::format("is the same output as {} ({}): every output must be a file of its own",
                                   it->second->path, it->second->field));
    try {
      check_replaceable_output(out.path);
    } catch (const InputError& e) {
      throw InputError(out.path, out.field, e.problem());
    }
  }
  std::set<std::string> folders;  // each output folder checked once
  for (const OutputFile& out : outputs) {
    std::error_code ec;
    if (folders.insert(fs::absolute(out.path, ec).parent_path().string()).second) check_creatable(out);
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

void check_output_folder(const std::string& folder, const std::string& field) {
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(folder, ec);
  if (ec || st.type() == fs::file_type::not_found) return;
  if (!fs::is_directory(folder, ec))
    throw InputError(folder, field, "exists and is not a folder");
  for (fs::recursive_directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::file_type t = it->symlink_status(ec).type();
    if (t == fs::file_type::regular || t == fs::file_type::directory) continue;
    try {
      check_replaceable_output(it->path().string());
    } catch (const InputError& e) {
      throw InputError(it->path().string(), field, e.problem() + "; the folder may hold only files and folders");
    }
  }
}

}  // namespace glasspiv
