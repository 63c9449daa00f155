#pragma once
// Reading and writing camera files in the formats users already have:
//   glasspiv  our YAML (docs/formats.md), any pinhole + OpenCV model, pose, pixel pitch
//   opencv    OpenCV FileStorage YAML as calibrateCamera users save it
//             (camera_matrix, distortion_coefficients, image_width/height)
//   mrcal     .cameramodel (LENSMODEL_PINHOLE / OPENCV4/5/8/12), written at full precision
//   davis     DaVis Calibration.xml, PinholeOpenCV mapper (k1, k2, p1, p2 only)
// Every reader rejects what it cannot represent with an InputError naming the
// file and the field; every writer writes atomically.
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "calib/camera.h"

namespace glasspiv {

enum class CameraFileFormat { Glasspiv, OpenCV, Mrcal, Davis };

// Limits every camera reader enforces (besides the image size limits of
// calib/camera_model.h, kMaxImageSidePx and kMaxImagePixels):
//   the largest pixel pitch a file may give, in micrometres (1 mm);
constexpr double kMaxPixelPitchUm = 1000;
//   the deepest nesting of lists and mappings in an OpenCV FileStorage file,
//   checked on the text before OpenCV's recursive parser sees it.
constexpr int kMaxOpenCVNestingDepth = 64;

std::string format_name(CameraFileFormat format);
// "glasspiv", "opencv", "mrcal", "davis"; throws InputError(field "format") otherwise.
CameraFileFormat format_from_name(const std::string& name);
// The format a file of this name is written in: .cameramodel -> mrcal, .xml -> davis,
// .yaml/.yml -> glasspiv. Throws InputError naming the path for other extensions.
CameraFileFormat format_for_output_path(const std::string& path);
// The format of a file's contents (sniffed, so OpenCV YAML and ours both load from .yaml).
CameraFileFormat detect_format(std::string_view contents, const std::string& path);

// Parses every camera in `contents`; `path` only names the source in errors.
std::vector<Camera> parse_cameras(std::string_view contents, CameraFileFormat format, const std::string& path);
// Serialises cameras in `format`. Throws InputError if the format cannot hold
// them (e.g. a 14-coefficient model into mrcal or DaVis, several cameras into a
// single-camera format, DaVis without a pixel pitch); `path` names the target.
std::string format_cameras(const std::vector<Camera>& cameras, CameraFileFormat format, const std::string& path);

// File helpers on top of the two above.
std::vector<Camera> read_cameras(const std::string& path);
// The one camera in the file, or the one called `name` when given; in a DaVis
// file a mapper's CameraIdentifier ("1") finds its camera too.
Camera read_camera(const std::string& path, const std::string& name = "");
void write_cameras(const std::string& path, const std::vector<Camera>& cameras,
                   std::optional<CameraFileFormat> format = std::nullopt);

// Helpers the format readers and writers (calib/io/*.cpp) share.
namespace camera_file_detail {
// To be called inside a catch block: rethrows the current exception, except an
// InputError without a file (the CameraModel constructor's), which is rethrown
// naming `path`.
[[noreturn]] void rethrow_naming_file(const std::string& path);
// The name a camera gets when its file has none: the file's stem ("cam0" for
// "setup/cam0.cameramodel"), or "camera" without a path.
std::string default_camera_name(const std::string& path);
// 1-based line of byte `offset` in `text`.
int line_of_offset(std::string_view text, std::size_t offset);
// Throws InputError naming `path` unless the camera's pose and pixel pitch are
// finite (and the pitch positive): writers call it before writing.
void check_writable(const Camera& camera, const std::string& path);
// "" for a usable pixel pitch (positive, finite, at most kMaxPixelPitchUm), else
// what is wrong with it ("must be ..."): readers put it into their InputError.
std::string pixel_pitch_problem(double pitch_um);
// The image size check of calib/camera_model.h for a reader: `width_px` and
// `height_px` as read (before narrowing to int); throws InputError naming `path`
// and `field` (its problem after `where`, e.g. "line 3: ") unless both are whole
// numbers in [1, kMaxImageSidePx] with width x height <= kMaxImagePixels.
// Returns {width, height}.
std::pair<int, int> checked_image_size(double width_px, double height_px, const std::string& path,
                                       const std::string& field, const std::string& where = "");
}  // namespace camera_file_detail

}  // namespace glasspiv
