#pragma once
// Checks every command shares: numbers on the command line, the work an option
// implies, and the wording of counts and numbers in messages.
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>

#include "util/input_error.h"
#include "util/text_number.h"

namespace glasspiv {

// Runs work(); an InputError it throws that names no file (the fit and other
// libraries work on data, not files) is rethrown naming `file`, the input the
// data came from.
template <typename F>
auto naming_file(const std::string& file, F&& work) -> decltype(work()) {
  try {
    return work();
  } catch (const InputError& e) {
    if (!e.file().empty()) throw;
    throw InputError(file, e.field(), e.problem());
  }
}

// Applied by main() to every option of every (sub)command, once all are
// registered: a FLOAT value must be a finite number (no nan, inf, 1e999); an
// INT or UINT value must be a whole number written in decimal; a UINT value may
// not be negative (CLI11 would wrap -1 to 2^64 - 1). Also every --threads
// option is bounded by kMaxThreads.
void check_numeric_options(CLI::App& app);

// The message for CLI11's "Could not convert: NAME = VALUE", in words: once
// check_numeric_options has passed a whole number (decimal, within 64 bits), a
// conversion can only fail because the option's type is narrower
// ("--levels: '4294967304' is out of this option's range"); other values
// are "not a number" / "not a valid value". `app`: the parsed command line.
std::string conversion_problem(CLI::App& app, const CLI::ConversionError& e);

// A whole number written inside an option's text ("K/N" of --shard, an item of
// a list): `part` of `text` in decimal, within [min, max] (and so within T),
// else InputError("", field, ...) quoting both: never wrapped or saturated.
template <typename T>
T option_integer(const std::string& field, const std::string& text, std::string_view part, T min, T max) {
  const std::optional<T> value = parse_integer<T>(part);
  if (!value || *value < min || *value > max)
    throw InputError("", field,
                     "'" + text + "': '" + std::string(part) + "' is not a whole number from " + std::to_string(min) +
                         " to " + std::to_string(max));
  return *value;
}

// Limits on the work an option's value implies, checked before the work.
constexpr int kMaxThreads = 1024;                  // --threads
constexpr double kMaxGridSamples = 1e6;            // camera show / compare: --step-px grid over the image
constexpr double kMaxSheetPictureTexels = 1e8;     // render: built-in sheet pattern (--pattern-mm, --particle-diameter-mm)
constexpr double kMaxSheetParticles = 1e7;         // render: --particle-density x the sheet's area

// InputError("", field) if a grid of samples about step_px apart over a
// width x height image (calib/pixel_grid.h over_image) has more than
// kMaxGridSamples samples; the message gives the smallest step allowed.
void check_sample_grid(const std::string& field, int width_px, int height_px, double step_px);

// A number for a message: at most 6 significant digits ("1e+300", not 301 digits).
std::string number(double value);
// "1 solid", "3 solids" (plural: singular + "s" unless given).
std::string count_of(std::size_t n, const std::string& singular, const std::string& plural = "");

}  // namespace glasspiv
