#pragma once
// YamlFields with the fields every YAML camera reader shares (glasspiv's own
// format and OpenCV's FileStorage YAML).
#include <string>

#include <yaml-cpp/yaml.h>

#include "calib/camera_model.h"
#include "util/input_error.h"
#include "util/yaml_fields.h"

namespace glasspiv {

class CameraYamlFields : public YamlFields {
 public:
  using YamlFields::YamlFields;

  // An image width or height: a whole number of pixels within the image limits.
  int image_side(const YAML::Node& node, const std::string& field) const {
    const double value = real(node, field);
    try {
      return checked_image_side_px(value, field);
    } catch (const InputError& e) {
      fail(field, node, e.problem());
    }
  }
};

}  // namespace glasspiv
