#pragma once
// Text made safe for the HTML pages the demo and the calibration report write.
#include <string>

namespace glasspiv {

// <, >, & and " as entities.
std::string html_escape(const std::string& text);

}  // namespace glasspiv
