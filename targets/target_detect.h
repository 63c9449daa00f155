#pragma once
// Finding a target's corners in a photo. Every detector reports pixels in
// glasspiv's convention ((0, 0) = the centre of the top-left pixel; libapriltag's
// and OpenCV 4.6 ChArUco's half-pixel offsets are removed here) and corner ids
// and board points as board_corners() defines them. See docs/targets.md.
// Single markers (aruco_marker, apriltag) are found by detect_markers()
// (targets/marker_detect.h), their corners refined by its edge fit.
#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "calib/observations.h"
#include "targets/target_spec.h"

namespace glasspiv {

struct DetectOptions {
  // Chessboards: how the board is found first, by OpenCV's sector-based
  // detector (findChessboardCornersSB with CALIB_CB_NORMALIZE_IMAGE | EXHAUSTIVE |
  // ACCURACY; the default: it copes with blur and uneven light better) or the
  // classic findChessboardCorners (ADAPTIVE_THRESH | NORMALIZE_IMAGE |
  // FAST_CHECK). A miss is retried: sector_based then tries
  // findChessboardCornersSB without EXHAUSTIVE (which can lose a board to a
  // spurious row of corners along its edge; OpenCV's right09.jpg) and then the
  // classic finder; classic tries the two sector-based calls. Whichever finds
  // it, the corners are then refined by cornerSubPix (11 x 11 window, or less
  // for small squares; 30 iterations / 1e-3 px). Measured on synthetic photos
  // (tests/targets/target_detect_test.cpp): sector-based alone RMS 0.09 px,
  // either with cornerSubPix 0.034 px.
  enum class ChessboardMethod { sector_based, classic };
  ChessboardMethod chessboard = ChessboardMethod::sector_based;
  // ChArUco boards with an even number of rows: a view is only accepted when it
  // shows which layout (opencv or legacy) the board has, i.e. it is consistent
  // with the requested layout and not with the other. With false, views that
  // cannot tell (neither side edge of the board visible) are accepted with the
  // requested layout's ids, which are then off by one column if the layout is
  // wrong.
  bool require_layout_evidence = true;
};

struct DetectionResult {
  ViewObservations view;   // corners sorted by id; empty when the target was not found
  int markers_found = 0;   // charuco markers / apriltags of the board decoded (single markers: 0 or 1)
  std::string note;        // why corners were dropped or none were found; "" otherwise
};

// Holds what a target's detector builds once (dictionary, board, libapriltag
// detector) for many photos. detect() is const but not thread-safe for
// aprilgrids and apriltags (libapriltag's detector holds state): use one
// detector per thread.
class TargetDetector {
 public:
  explicit TargetDetector(const TargetSpec& spec, DetectOptions options = {});
  ~TargetDetector();
  TargetDetector(TargetDetector&&) noexcept;
  TargetDetector& operator=(TargetDetector&&) noexcept;
  TargetDetector(const TargetDetector&) = delete;
  TargetDetector& operator=(const TargetDetector&) = delete;

  // `gray`: CV_8UC1. Not finding the target is no error: an empty corner list.
  // Throws InputError(source, "image", ...) for an empty or non-8-bit-grey image.
  DetectionResult detect(const cv::Mat& gray, const std::string& source) const;

  const TargetSpec& spec() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One-shot form.
ViewObservations detect_target(const cv::Mat& gray, const TargetSpec& spec, const std::string& source);

}  // namespace glasspiv
