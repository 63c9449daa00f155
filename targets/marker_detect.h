#pragma once
// Every fiducial marker of one dictionary in a photo at once: ArUco markers of
// an OpenCV predefined dictionary (OpenCV's detectMarkers) or AprilTags of a
// libapriltag family (libapriltag). Both detectors' corners are then refined
// by one edge fit (docs/targets.md): each side of the marker's square is located
// to sub-pixel along many profiles across it and fitted by a line; the corners
// are the lines' intersections. Pixels in glasspiv's convention ((0, 0) = the
// centre of the top-left pixel).
#include <array>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace glasspiv {

struct DetectedMarker {
  int id = 0;
  // Top-left, top-right, bottom-right, bottom-left corner of the marker's black
  // border as printed (AprilTags: of the square libapriltag detects), i.e.
  // board_corners() ids 0..3 of its aruco_marker / apriltag target; glasspiv
  // pixel convention.
  std::array<Eigen::Vector2d, 4> corners_px;
  // false: the edge fit gave up (cells of a few px, a blurred or cut border) and
  // the corners are OpenCV's, refined by cv::cornerSubPix in a window of 0.4
  // cells (less exact: the pose's outlier rounds judge them).
  bool edge_fit = true;
};

struct MarkerDetection {
  std::vector<DetectedMarker> markers;  // sorted by id
  std::vector<int> duplicated_ids;      // ids seen more than once (sorted): not in markers
};

// Holds what a dictionary's detector builds once (OpenCV dictionary, or
// libapriltag family and detector) for many photos. detect() is const but not
// thread-safe for AprilTags (libapriltag's detector holds state): one per thread.
class MarkerDetector {
 public:
  // `dictionary`: an OpenCV predefined dictionary name ("DICT_4X4_50", ...;
  // opencv_dictionary_names()) or an AprilTag family ("tag36h11", ...;
  // apriltag_family_names()). InputError(source, "dictionary", ...) for an
  // unknown name.
  explicit MarkerDetector(const std::string& dictionary, const std::string& source = "");
  ~MarkerDetector();
  MarkerDetector(MarkerDetector&&) noexcept;
  MarkerDetector& operator=(MarkerDetector&&) noexcept;
  MarkerDetector(const MarkerDetector&) = delete;
  MarkerDetector& operator=(const MarkerDetector&) = delete;

  // `gray8`: CV_8UC1 (InputError(source, "image", ...) otherwise); an image
  // without pixels has no markers. A marker whose corners cannot be refined
  // (a side cut by the image's edge, too little contrast) is left out.
  MarkerDetection detect(const cv::Mat& gray8, const std::string& source) const;

  const std::string& dictionary() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One-shot form of MarkerDetector(dictionary, source).detect(gray8, source).
MarkerDetection detect_markers(const cv::Mat& gray8, const std::string& dictionary, const std::string& source);

}  // namespace glasspiv
