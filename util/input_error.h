#pragma once
// The one error type for bad user input: it names the file, the field and what
// is wrong, so the command line can print it as one line and exit with status 2.
#include <stdexcept>
#include <string>

namespace glasspiv {

class InputError : public std::runtime_error {
 public:
  // file: the path the user gave ("" when the input did not come from a file).
  // field: the offending field or key path ("" when the whole file is at fault).
  InputError(std::string file, std::string field, std::string problem);

  const std::string& file() const { return file_; }
  const std::string& field() const { return field_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string file_, field_, problem_;
};

}  // namespace glasspiv
