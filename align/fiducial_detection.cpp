#include "align/fiducial_detection.h"

#include <algorithm>
#include <map>
#include <set>

#include <fmt/format.h>

#include "targets/marker_detect.h"
#include "targets/target_detect.h"
#include "util/input_error.h"

namespace glasspiv {

FiducialsInPhoto detect_fiducials(const cv::Mat& gray8, const std::vector<SceneFiducial>& fiducials,
                                  const std::string& source) {
  if (gray8.empty()) throw InputError(source, "image", "the photo is empty");
  FiducialsInPhoto out;
  out.source = source;
  out.corners_per_fiducial.assign(fiducials.size(), 0);
  // Single markers by dictionary: id -> fiducial. Ids that boards of the same
  // dictionary carry are theirs, not unknown.
  std::map<std::string, std::map<int, int>> singles;
  std::map<std::string, std::set<int>> board_ids;
  for (std::size_t f = 0; f < fiducials.size(); ++f) {
    const TargetSpec& spec = fiducials[f].spec;
    if (is_single_marker(spec.kind))
      singles[spec.dictionary][spec.first_id] = static_cast<int>(f);
    else
      for (const BoardMarker& m : board_markers(spec)) board_ids[spec.dictionary].insert(m.id);
  }
  std::vector<std::vector<FiducialCorner>> found(fiducials.size());
  for (const auto& [dictionary, by_id] : singles) {
    const MarkerDetection detection = detect_markers(gray8, dictionary, source);
    for (const DetectedMarker& m : detection.markers) {
      const auto it = by_id.find(m.id);
      if (it == by_id.end()) {
        if (!board_ids[dictionary].count(m.id)) out.unknown_markers.push_back(fmt::format("{} id {}", dictionary, m.id));
        continue;
      }
      const SceneFiducial& f = fiducials[static_cast<std::size_t>(it->second)];
      for (int k = 0; k < 4; ++k)
        found[static_cast<std::size_t>(it->second)].push_back(
            {it->second, k, f.corner_world_mm(f.corners_board[static_cast<std::size_t>(k)]), m.corners_px[k]});
    }
    for (int id : detection.duplicated_ids)
      if (by_id.count(id)) out.duplicated_markers.push_back(fmt::format("{} id {}", dictionary, id));
  }
  for (std::size_t f = 0; f < fiducials.size(); ++f) {
    if (is_single_marker(fiducials[f].spec.kind)) continue;
    const TargetDetector detector(fiducials[f].spec);
    const DetectionResult result = detector.detect(gray8, source);
    if (!result.note.empty()) out.notes.push_back(fiducials[f].field + ": " + result.note);
    for (const CornerObservation& c : result.view.corners)
      found[f].push_back({static_cast<int>(f), c.id, fiducials[f].world_from_board.apply(c.board_point_mm), c.pixel_px});
  }
  for (std::size_t f = 0; f < fiducials.size(); ++f) {
    std::sort(found[f].begin(), found[f].end(),
              [](const FiducialCorner& a, const FiducialCorner& b) { return a.corner_id < b.corner_id; });
    out.corners_per_fiducial[f] = static_cast<int>(found[f].size());
    out.corners.insert(out.corners.end(), found[f].begin(), found[f].end());
  }
  return out;
}

}  // namespace glasspiv
