#include "apps/cli_checks.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>

#include <fmt/format.h>

#include "util/input_error.h"
#include "util/input_file.h"
#include "util/text_number.h"

namespace glasspiv {
namespace {

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

// CLI11's type name of an option ("FLOAT", "INT", "UINT", "TEXT", ...), validators' descriptions stripped.
std::string base_type(const CLI::Option* o) {
  std::string t = o->get_type_name();
  const auto colon = t.find(':');
  return colon == std::string::npos ? t : t.substr(0, colon);
}

std::string finite_number(std::string& text) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const double v = std::strtod(begin, &end);
  if (end == begin || *end != 0) return "";  // not a number at all: CLI11's own conversion reports it
  if (!std::isfinite(v)) return "'" + text + "' is not a finite number";
  return "";
}

std::string decimal_integer(std::string& text, bool allow_negative) {
  std::size_t i = 0;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
  const bool digits = i < text.size() && text.find_first_not_of("0123456789", i) == std::string::npos;
  if (!digits) return "'" + text + "' is not a whole number in decimal";
  if (!allow_negative && text[0] == '-' && text.find_first_not_of("0", 1) != std::string::npos)
    return "'" + text + "' is negative; this option takes 0 or more";
  // CLI11 refuses a value beyond a narrower type itself, but saturates one
  // beyond 64 bits (strtoll / strtoull): 2^64 + 1 would read as 2^64 - 1.
  // (A value within 64 bits but beyond a narrower type: conversion_problem.)
  if (allow_negative ? !parse_integer<std::int64_t>(text) : !parse_integer<std::uint64_t>(text))
    return "'" + text + "' is out of this option's range";
  return "";
}

// CLI::ExistingFile lets a fifo or a device through (it only refuses folders);
// an input must be a regular file (util/input_file.h), refused naming the option.
CLI::Validator regular_input_file() {
  return CLI::Validator(
      [](std::string& path) -> std::string {
        const std::string problem = input_file_problem(path);
        return problem.empty() ? "" : path + ": " + problem;
      },
      "FILE");
}

// CLI11's PositiveNumber and NonNegativeNumber are Ranges up to the largest
// double, which their message prints in 309 digits; the same checks with a
// short message replace them wherever a command used them.
CLI::Validator sign_check(bool positive, const std::string& description) {
  return CLI::Validator(
      [positive](std::string& text) -> std::string {
        const char* begin = text.c_str();
        char* end = nullptr;
        const double v = std::strtod(begin, &end);
        if (end == begin || *end != 0) return "'" + text + "' is not a number";
        if (positive ? !(v > 0) : !(v >= 0)) return "'" + text + (positive ? "' must be above 0" : "' must be 0 or more");
        return "";
      },
      description);
}

void replace_unbounded_ranges(CLI::Option* o) {
  for (int i = 0;; ++i) {
    CLI::Validator* v = nullptr;
    try {
      v = o->get_validator(i);
    } catch (const CLI::OptionNotFound&) {
      return;
    }
    const std::string d = v->get_description();
    if (d == "POSITIVE" || d == "NONNEGATIVE") *v = sign_check(d == "POSITIVE", d);
    if (d == "FILE") *v = regular_input_file();
  }
}

void visit(CLI::App* app) {
  for (CLI::Option* o : app->get_options({})) {
    if (o->get_type_size_max() == 0) continue;  // a flag
    const std::string type = base_type(o);
    replace_unbounded_ranges(o);
    // transform(): placed before the option's own checks, so `nan` is refused as
    // not finite rather than passing or failing a range check oddly.
    if (starts_with(type, "FLOAT")) {
      o->transform(CLI::Validator(finite_number, "", "finite"));
    } else if (type == "UINT") {
      o->transform(CLI::Validator([](std::string& t) { return decimal_integer(t, false); }, "", "non-negative integer"));
    } else if (type == "INT") {
      o->transform(CLI::Validator([](std::string& t) { return decimal_integer(t, true); }, "", "decimal integer"));
    }
    if (o->check_name("--threads"))
      o->check(CLI::Validator(CLI::Range(0, kMaxThreads)).description("").name("thread limit"));
  }
  for (CLI::App* sub : app->get_subcommands([](CLI::App*) { return true; })) visit(sub);
}

}  // namespace

void check_numeric_options(CLI::App& app) { visit(&app); }

std::string conversion_problem(CLI::App& app, const CLI::ConversionError& e) {
  const std::string what = e.what();
  const std::string prefix = "Could not convert: ";
  const std::size_t eq = what.find(" = ");
  if (what.rfind(prefix, 0) != 0 || eq == std::string::npos) return what;
  const std::string name = what.substr(prefix.size(), eq - prefix.size()), value = what.substr(eq + 3);
  // The option in the deepest subcommand parsed, or an app above it.
  CLI::App* deepest = &app;
  for (bool deeper = true; deeper;) {
    deeper = false;
    for (CLI::App* sub : deepest->get_subcommands())
      if (sub->parsed()) {
        deepest = sub;
        deeper = true;
        break;
      }
  }
  const CLI::Option* option = nullptr;
  for (CLI::App* a = deepest; a && !option; a = a->get_parent()) option = a->get_option_no_throw(name);
  const std::string type = option ? base_type(option) : "";
  if (type == "INT" || type == "UINT") return fmt::format("{}: '{}' is out of this option's range", name, value);
  if (starts_with(type, "FLOAT")) return fmt::format("{}: '{}' is not a number", name, value);
  return fmt::format("{}: '{}' is not a valid value", name, value);
}

void check_sample_grid(const std::string& field, int width_px, int height_px, double step_px) {
  if (!(step_px > 0) || !std::isfinite(step_px)) throw InputError("", field, "must be a finite number above 0");
  const double cols = std::max(2.0, std::round((width_px - 1) / step_px) + 1);
  const double rows = std::max(2.0, std::round((height_px - 1) / step_px) + 1);
  const auto samples = [&](double step) {
    return std::max(2.0, std::round((width_px - 1) / step) + 1) * std::max(2.0, std::round((height_px - 1) / step) + 1);
  };
  if (cols * rows > kMaxGridSamples) {
    // The smallest step (to 1e-3 px) within the limit: (a/s + 1)(b/s + 1) = N solved for 1/s, then checked.
    const double a = std::max(1, width_px - 1), b = std::max(1, height_px - 1);
    const double x = (-(a + b) + std::sqrt((a + b) * (a + b) + 4 * a * b * (kMaxGridSamples - 1))) / (2 * a * b);
    double smallest = std::ceil(1000 / x) / 1000;
    while (samples(smallest) > kMaxGridSamples) smallest += 0.001;
    throw InputError("", field,
                     fmt::format("{} px makes a {} x {} grid over the {}x{} px image ({} samples); the limit is {} "
                                 "samples: give a step of {} px or more",
                                 number(step_px), number(cols), number(rows), width_px, height_px, number(cols * rows),
                                 number(kMaxGridSamples), number(smallest)));
  }
}

std::string number(double value) { return fmt::format("{:.6g}", value); }

std::string count_of(std::size_t n, const std::string& singular, const std::string& plural) {
  return fmt::format("{} {}", n, n == 1 ? singular : (plural.empty() ? singular + "s" : plural));
}

}  // namespace glasspiv
