#pragma once
// What made one corrected frame, recorded in the frame itself (its TIFF
// ImageDescription, docs/correction.md "Series"), so that a rerun of a series
// keeps exactly the frames it would make again and redoes the others: the
// record is written with the pixels, atomically, and read back from the
// file's header alone. No I/O here: text in, text out.
//
// A record holds two sets of named values, each compared as text:
//  - setup: everything of the series that changes a frame's pixels (each
//    camera's correction operator fingerprint, which covers the scene, the
//    calibration, the pose, the tracing and the grid; the method and its
//    options; the output grid and format; the mask settings; the camera
//    weights; the background);
//  - inputs: per camera, the identity of the input frame it was made from
//    (name, size in bytes, modification time).
#include <map>
#include <string>

namespace glasspiv {

// Bump when the reconstruction changes the pixels it makes for the same
// record, so that frames of an older build are redone.
inline constexpr int kCorrectedFrameVersion = 1;

struct FrameProvenance {
  std::map<std::string, std::string> setup;
  std::map<std::string, std::string> inputs;
};

// The record as one line of JSON: {"glasspiv_corrected_frame": kCorrectedFrameVersion,
// "setup": {...}, "inputs": {...}}, keys sorted, any text escaped (a newline
// or a quote in a file name stays inside its string).
std::string provenance_text(const FrameProvenance& record);

// Why a frame whose record reads `stored` must be made again for `wanted`, in
// a few words that are the same for every frame of a series with the same
// cause ("made with method accumulate, now lsq", "its input frame changed
// (camera 'cam0')", "no provenance record"); "" when it may be kept.
std::string provenance_difference(const std::string& stored, const FrameProvenance& wanted);

}  // namespace glasspiv
