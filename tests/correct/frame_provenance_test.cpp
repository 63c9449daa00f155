#include "correct/frame_provenance.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <string>

namespace glasspiv {
namespace {

FrameProvenance record() {
  FrameProvenance r;
  r.setup = {{"operator cam0", "0123456789abcdef"}, {"method", "accumulate"}, {"format", "uint16"},
             {"grid", "camera"}, {"weight cam0", "1"}};
  r.inputs = {{"cam0", "f1.tif, 1000 bytes, modified 1700000000.000000001"}};
  return r;
}

// The record written is the record read: a frame made by the same setup from
// the same input is kept.
TEST(FrameProvenance, TheSameRecordIsKept) {
  EXPECT_EQ(provenance_difference(provenance_text(record()), record()), "");
  // One line, whatever the file names hold.
  FrameProvenance odd = record();
  odd.inputs["cam0"] = "a\nb \"c\" #3: d.tif, 1 bytes, modified 1.000000000";
  const std::string text = provenance_text(odd);
  EXPECT_EQ(text.find('\n'), std::string::npos);
  EXPECT_EQ(provenance_difference(text, odd), "");
  EXPECT_EQ(nlohmann::json::parse(text)["inputs"]["cam0"].get<std::string>(), odd.inputs["cam0"]);
}

// Every difference redoes the frame, and says why in words that are the same
// for every frame of the series.
TEST(FrameProvenance, EveryDifferenceIsNamed) {
  const std::string stored = provenance_text(record());
  FrameProvenance moved = record();
  moved.setup["operator cam0"] = "fedcba9876543210";
  moved.setup["grid"] = "sheet";  // a moved camera may change other settings: the operator is named first
  EXPECT_EQ(provenance_difference(stored, moved),
            "the correction operator of camera 'cam0' changed (scene, calibration, pose, tracing or grid)");
  FrameProvenance lsq = record();
  lsq.setup["method"] = "lsq";
  lsq.setup["max iterations"] = "100";  // an option of the new method only: the method is named
  lsq.setup["smoothness"] = "0.01";
  EXPECT_EQ(provenance_difference(stored, lsq), "made with method accumulate, now lsq");
  EXPECT_EQ(provenance_difference(provenance_text(lsq), record()), "made with method lsq, now accumulate");
  FrameProvenance smoother = lsq;
  smoother.setup["smoothness"] = "0.1";
  EXPECT_EQ(provenance_difference(provenance_text(lsq), smoother), "made with smoothness 0.01, now 0.1");
  FrameProvenance two = record();
  two.setup["operator cam1"] = "00000000000000ff";
  two.setup["weight cam1"] = "1";
  EXPECT_EQ(provenance_difference(stored, two), "made without camera 'cam1'");
  FrameProvenance as_float = record();
  as_float.setup["format"] = "float32";
  EXPECT_EQ(provenance_difference(stored, as_float), "made with format uint16, now float32");
  FrameProvenance extra = as_float;  // a setting only the stored record has is named after a changed one
  extra.setup["min pixels"] = "0.25";
  EXPECT_EQ(provenance_difference(provenance_text(extra), record()), "made with format float32, now uint16");
  EXPECT_EQ(provenance_difference(provenance_text(extra), as_float), "made with min pixels 0.25");
  FrameProvenance more = record();
  more.setup["min pixels"] = "0.25";
  EXPECT_EQ(provenance_difference(stored, more), "made without min pixels");
  FrameProvenance touched = record();
  touched.inputs["cam0"] = "f1.tif, 1000 bytes, modified 1700000001.000000001";
  EXPECT_EQ(provenance_difference(stored, touched), "its input frame changed (camera 'cam0')");
}

// A frame without a record (an older glasspiv, another program) or with a
// record of another version is redone.
TEST(FrameProvenance, NoRecordOrAnotherVersionIsRedone) {
  EXPECT_EQ(provenance_difference("", record()), "no provenance record");
  EXPECT_EQ(provenance_difference("written by a camera", record()), "no provenance record");
  EXPECT_EQ(provenance_difference("[1, 2]", record()), "no provenance record");
  nlohmann::json old = nlohmann::json::parse(provenance_text(record()));
  old["glasspiv_corrected_frame"] = kCorrectedFrameVersion + 1;
  EXPECT_EQ(provenance_difference(old.dump(), record()), "made by another version of the correction");
}

}  // namespace
}  // namespace glasspiv
