#include "util/input_error.h"

namespace glasspiv {
namespace {
std::string format_message(const std::string& file, const std::string& field,
                           const std::string& problem) {
  std::string message;
  if (!file.empty()) message += file;
  if (!field.empty()) message += (message.empty() ? "" : ": ") + std::string("field '") + field + "'";
  if (!message.empty()) message += ": ";
  return message + problem;
}
}  // namespace

InputError::InputError(std::string file, std::string field, std::string problem)
    : std::runtime_error(format_message(file, field, problem)),
      file_(std::move(file)),
      field_(std::move(field)),
      problem_(std::move(problem)) {}

}  // namespace glasspiv
