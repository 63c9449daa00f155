#include "correct/frame_provenance.h"

#include <nlohmann/json.hpp>

namespace glasspiv {
namespace {

constexpr const char* kTag = "glasspiv_corrected_frame";

nlohmann::json as_json(const FrameProvenance& record) {
  return {{kTag, kCorrectedFrameVersion}, {"setup", record.setup}, {"inputs", record.inputs}};
}

// "key" of the setup, named for a person reading why a frame is redone.
std::string what_changed(const std::string& key, const std::string& was, const std::string& now) {
  if (key.rfind("operator ", 0) == 0 || key.rfind("weight ", 0) == 0) {
    if (was.empty()) return "made without camera '" + key.substr(key.find(' ') + 1) + "'";
    if (now.empty()) return "made with camera '" + key.substr(key.find(' ') + 1) + "' too";
  }
  if (key.rfind("operator ", 0) == 0)
    return "the correction operator of camera '" + key.substr(9) +
           "' changed (scene, calibration, pose, tracing or grid)";
  if (was.empty()) return "made without " + key;
  if (now.empty()) return "made with " + key + " " + was;
  return "made with " + key + " " + was + ", now " + now;
}

}  // namespace

std::string provenance_text(const FrameProvenance& record) {
  return as_json(record).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string provenance_difference(const std::string& stored, const FrameProvenance& wanted) {
  if (stored.empty()) return "no provenance record";
  const nlohmann::json s = nlohmann::json::parse(stored, nullptr, false);
  if (s.is_discarded() || !s.is_object() || !s.contains(kTag)) return "no provenance record";
  if (!s[kTag].is_number_integer() || s[kTag].get<int>() != kCorrectedFrameVersion)
    return "made by another version of the correction";
  const nlohmann::json w = as_json(wanted);
  if (s == w) return "";
  const auto strings = [](const nlohmann::json& j, const char* part) {
    std::map<std::string, std::string> out;
    if (j.contains(part) && j[part].is_object())
      for (auto it = j[part].begin(); it != j[part].end(); ++it)
        out[it.key()] = it.value().is_string() ? it.value().get<std::string>() : it.value().dump();
    return out;
  };
  // The setup first (it redoes a whole series): the operators (the scene and
  // the cameras, whose change may change other settings too), then settings
  // both records hold (a changed method, before the options only one of the
  // methods has), then settings only one holds.
  const std::map<std::string, std::string> was = strings(s, "setup"), now = strings(w, "setup");
  for (const bool operators : {true, false})
    for (const auto& [key, value] : now) {
      const auto it = was.find(key);
      if ((key.rfind("operator ", 0) == 0) == operators && it != was.end() && it->second != value)
        return what_changed(key, it->second, value);
    }
  for (const auto& [key, value] : now)
    if (!was.count(key)) return what_changed(key, "", value);
  for (const auto& [key, value] : was)
    if (!now.count(key)) return what_changed(key, value, "");
  const std::map<std::string, std::string> in_was = strings(s, "inputs"), in_now = strings(w, "inputs");
  for (const auto& [camera, identity] : in_now) {
    const auto it = in_was.find(camera);
    if (it == in_was.end() || it->second != identity) return "its input frame changed (camera '" + camera + "')";
  }
  return "its input frames changed";
}

}  // namespace glasspiv
