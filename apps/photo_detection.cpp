#include "apps/photo_detection.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <unistd.h>

#include "apps/cli_files.h"
#include "targets/photo_io.h"
#include "targets/target_detect.h"
#include "util/atomic_file.h"
#include "util/file_identity.h"
#include "util/input_error.h"
#include "util/progress_bar.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

// Detected corners drawn over the photo: a circle and the id at each corner.
cv::Mat overlay(const cv::Mat& gray, const ViewObservations& view) {
  cv::Mat picture;
  cv::cvtColor(gray, picture, cv::COLOR_GRAY2BGR);
  const double scale = std::max(1.0, std::max(gray.cols, gray.rows) / 1500.0);
  const int radius = static_cast<int>(std::lround(4 * scale)), thickness = static_cast<int>(std::lround(scale));
  for (const CornerObservation& c : view.corners) {
    // cv::circle takes fixed-point centres: 4 fractional bits, pixel-centre convention.
    const cv::Point centre(static_cast<int>(std::lround(c.pixel_px.x() * 16)),
                           static_cast<int>(std::lround(c.pixel_px.y() * 16)));
    cv::circle(picture, centre, radius * 16, cv::Scalar(0, 200, 0), thickness, cv::LINE_AA, 4);
    cv::putText(picture, std::to_string(c.id),
                cv::Point(static_cast<int>(c.pixel_px.x() + radius + 2), static_cast<int>(c.pixel_px.y() - radius - 2)),
                cv::FONT_HERSHEY_SIMPLEX, 0.4 * scale, cv::Scalar(0, 0, 255), thickness, cv::LINE_AA);
  }
  return picture;
}

// A per-photo line on stdout without garbling the progress bar on stderr.
void print_line(const std::string& line) {
  if (::isatty(STDERR_FILENO) == 1) {
    std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
  }
  std::printf("%s\n", line.c_str());
  std::fflush(stdout);
}

bool is_image_name(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".tif" || ext == ".tiff" || ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp";
}

}  // namespace

std::vector<std::string> expand_photo_inputs(const std::vector<std::string>& inputs) {
  std::vector<std::string> photos;
  for (const std::string& input : inputs) {
    std::error_code ec;
    if (!fs::exists(input, ec)) throw InputError(input, "", "does not exist");
    if (!fs::is_directory(input, ec)) {
      photos.push_back(input);
      continue;
    }
    std::vector<std::string> found;
    for (const auto& entry : fs::directory_iterator(input, ec))
      if (std::error_code type; entry.is_regular_file(type) && is_image_name(entry.path()))
        found.push_back(entry.path().string());
    if (found.empty()) throw InputError(input, "", "holds no images (.tif, .tiff, .png, .jpg, .jpeg, .bmp)");
    std::sort(found.begin(), found.end());
    photos.insert(photos.end(), found.begin(), found.end());
  }
  return photos;
}

std::vector<std::string> overlay_paths(const std::vector<std::string>& photos, const std::string& overlay_dir) {
  std::vector<std::string> out;
  if (overlay_dir.empty()) return out;
  std::set<std::string> names;
  for (const std::string& path : photos) {
    const std::string stem = fs::path(path).stem().string();
    std::string name = stem + "_corners";
    for (int k = 2; names.count(name); ++k) name = stem + "_corners_" + std::to_string(k);
    names.insert(name);
    out.push_back((fs::path(overlay_dir) / (name + ".png")).string());
  }
  return out;
}

void check_calib_outputs(const std::vector<std::string>& inputs, const std::vector<CalibOutput>& outputs) {
  std::vector<OutputFile> given;
  for (const CalibOutput& out : outputs)
    if (!out.path.empty()) given.push_back(out);
  check_outputs(inputs, given);
}

Observations detect_in_photos(const std::vector<std::string>& photos, const TargetSpec& spec,
                              const std::string& target_path, const PhotoDetectionOptions& options) {
  require_target_corners(spec, target_path, "corner detection");
  // A photo named twice (a folder and a file in it, a link, a copy) is one view.
  check_distinct_inputs(photos, "", "photo");
  DetectOptions detect_options;
  detect_options.require_layout_evidence = !options.lenient_layout;
  const TargetDetector detector(spec, detect_options);

  Observations observations;
  observations.target_name = spec.name;
  std::string first_photo;
  std::map<std::string, int> notes;
  const std::size_t total_corners = board_corner_count(spec);
  // An overlay must not replace a photo or the spec (a photo named x_corners.png
  // inside the overlay folder): checked before the first detection.
  const std::vector<std::string> overlays = overlay_paths(photos, options.overlay_dir);
  std::vector<std::string> inputs = photos;
  inputs.push_back(target_path);
  std::vector<CalibOutput> overlay_outputs;
  for (const std::string& path : overlays) overlay_outputs.push_back({path, "--overlay-dir"});
  check_calib_outputs(inputs, overlay_outputs);
  std::size_t photo_index = 0;
  ProgressBar bar("detecting", photos.size());
  for (const std::string& path : photos) {
    const cv::Mat gray = read_photo_gray8(path);
    if (first_photo.empty()) {
      first_photo = path;
      observations.image_width_px = gray.cols;
      observations.image_height_px = gray.rows;
    } else if (gray.cols != observations.image_width_px || gray.rows != observations.image_height_px) {
      throw InputError(path, "image size",
                       fmt::format("is {} x {} px but '{}' is {} x {} px; the images of one calibration come from "
                                   "one camera",
                                   gray.cols, gray.rows, first_photo, observations.image_width_px,
                                   observations.image_height_px));
    }
    const DetectionResult r = detector.detect(gray, path);
    observations.views.push_back(r.view);
    if (!r.note.empty() && r.view.corners.empty()) ++notes[r.note];
    if (!options.quiet) {
      const std::string markers = spec.kind == TargetKind::chessboard
                                      ? ""
                                      : fmt::format(", {} {}", r.markers_found,
                                                    spec.kind == TargetKind::aprilgrid ? "tags" : "markers");
      print_line(fmt::format("{}: {} of {} corners{}{}", path, r.view.corners.size(), total_corners, markers,
                             r.note.empty() ? "" : " (" + r.note + ")"));
    }
    if (!options.overlay_dir.empty()) {
      const std::string& out = overlays[photo_index];
      const cv::Mat picture = overlay(gray, r.view);
      write_file_atomically_with(out, [&](const std::string& temporary) {
        if (!cv::imwrite(temporary, picture)) throw InputError(out, "", "cannot write the overlay PNG");
      });
    }
    ++photo_index;
    bar.advance();
  }
  bar.finish();

  if (observations.corner_count() == 0) {
    std::string why;
    if (!notes.empty()) {
      auto most = notes.begin();
      for (auto it = notes.begin(); it != notes.end(); ++it)
        if (it->second > most->second) most = it;
      why = fmt::format(" (most often: {})", most->first);
    }
    throw InputError(target_path, "",
                     fmt::format("the target ({}) was found in none of the {} images{}; check the spec against the "
                                 "board: squares, sizes, dictionary, first id, layout",
                                 describe_target(spec), photos.size(), why));
  }
  return observations;
}

}  // namespace glasspiv
