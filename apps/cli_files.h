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

// What an output holds: an existing file under its name is replaced only if it
// holds the same kind (told from its first bytes, not its name), so that
// `--map frame.tif` or `--json photo.png` never destroys a picture.
enum class OutputKind {
  by_extension,  // from the output's extension: .png/.tif/.tiff/.exr image, .json JSON,
                 // .tmap transport map, .gop correction operator, .pdf PDF, .svg and
                 // the text formats (.yaml, .xml, .cameramodel, .txt, .vtk, .html, ...) text;
                 // any other extension: any regular file
  image,                // PNG, TIFF, OpenEXR (or another image format: JPEG, BMP, PNM)
  json,                 // text starting with '{' or '['
  text,                 // no NUL byte, no image or binary-format signature
  pdf,                  // starts with "%PDF-"
  transport_map,        // render/transport_map_file.h
  correction_operator,  // correct/correction_operator_file.h
  folder,               // a folder the command writes files into: must be a folder if it exists
};

// A file a command will write, and the option that names it (for the error).
struct OutputFile {
  std::string path;
  std::string field;  // e.g. "-o", "--map", "--plot"
  OutputKind kind = OutputKind::by_extension;
};

// Every check of a command's outputs, before any work, derived ones (`_edges`,
// per-camera names, files inside an output folder) included: throws InputError
// naming the output and its option if
//  - it is one of `inputs` (by filesystem identity: the same file under another
//    name, `./a` and `a`, through a link, or a hard link): glasspiv never
//    overwrites its inputs;
//  - two outputs are the same file;
//  - it exists and is not a regular file (a device, a symbolic link, a folder),
//    or, for a folder output, not a folder;
//  - it exists and holds another kind of file than the output (OutputKind);
//  - a name in its path is longer than the file system allows (255 bytes), or
//    the whole path longer than PATH_MAX;
//  - it cannot be created: the nearest existing folder above it is a file or
//    not writable.
// inputs: every file the command reads (for a scene: scene_input_files).
void check_outputs(const std::vector<std::string>& inputs, const std::vector<OutputFile>& outputs);

// The problem with replacing the existing regular file `path` by an output of
// `kind` ("" if none: it does not exist, is empty, or holds that kind).
std::string output_kind_problem(const std::string& path, OutputKind kind);

// Every file a scene reads: the scene file itself, its camera files, mesh files
// and rectangle textures (images and target specs).
std::vector<std::string> scene_input_files(const Scene& scene);

// Creates the output folder `folder` (and its parents); InputError(folder,
// field, the system's reason) if it cannot, never a filesystem_error.
void make_output_folder(const std::string& folder, const std::string& field);

// The demo's kind of output, a folder the command owns: InputError if `folder`
// exists and is not a folder, its name is too long, or it holds (at any depth,
// not following links) an entry that is neither a regular file nor a folder,
// or a file whose contents are not of the kind its extension names (the
// command would replace it: output_kind_problem with OutputKind::by_extension).
void check_output_folder(const std::string& folder, const std::string& field);

}  // namespace glasspiv
