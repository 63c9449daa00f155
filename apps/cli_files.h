#pragma once
// File-name checks shared by the commands (the calib commands may use them too).
#include <string>
#include <vector>

namespace glasspiv {

struct Scene;

// The extension of path, lower case, with its dot ("" if none).
std::string lower_extension(const std::string& path);

// A folder as a command prints it: with one trailing slash, whether or not
// the user gave one ("out" and "out/" both print "out/").
std::string folder_shown(const std::string& folder);

// Throws InputError if output names the same file as input: glasspiv never
// overwrites its inputs. (check_outputs does this and more for a whole command.)
void check_not_input(const std::string& input, const std::string& output);

// A file a command will write, and the option that names it (for the error).
struct OutputFile {
  std::string path;
  std::string field;  // e.g. "-o", "--map", "--plot"
};

// Every check of a command's outputs, before any work: throws InputError
// naming the output and its option if
//  - it is one of `inputs` (by filesystem identity: the same file under another
//    name, through a link, or a hard link): glasspiv never overwrites its inputs;
//  - two outputs are the same file;
//  - it exists and is not a regular file (a device, a symbolic link, a folder);
//  - it cannot be created: the nearest existing folder above it is a file or
//    not writable.
// inputs: every file the command reads (for a scene: scene_input_files).
void check_outputs(const std::vector<std::string>& inputs, const std::vector<OutputFile>& outputs);

// Every file a scene reads: the scene file itself, its camera files, mesh files
// and rectangle textures (images and target specs).
std::vector<std::string> scene_input_files(const Scene& scene);

// The demo's kind of output, a folder the command owns: InputError if `folder`
// exists and is not a folder, or holds (at any depth, not following links) an
// entry that is neither a regular file nor a folder.
void check_output_folder(const std::string& folder, const std::string& field);

}  // namespace glasspiv
