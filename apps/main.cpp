// glasspiv: PIV inside transparent geometry. One executable, one subcommand per task.
#include <csignal>
#include <cstdio>
#include <exception>
#include <filesystem>

#include <fmt/format.h>

#include "apps/cli_checks.h"
#include "apps/commands.h"
#include "util/input_error.h"

namespace {

// The deepest subcommand the command line chose, and the first word it could
// not place ("" if none): `glasspiv camera frobnicate --help` must not print
// help and succeed.
std::string unplaced_word(CLI::App& app, CLI::App*& deepest) {
  deepest = &app;
  for (;;) {
    CLI::App* next = nullptr;
    for (CLI::App* sub : deepest->get_subcommands())
      if (sub->parsed()) next = sub;
    if (!next) break;
    deepest = next;
  }
  for (CLI::App* a = deepest; a; a = a->get_parent()) {
    const std::vector<std::string> extra = a->remaining();
    if (!extra.empty()) return extra.front();
  }
  return "";
}

int help_or_unknown(CLI::App& app, const CLI::Error& e) {
  CLI::App* deepest = nullptr;
  const std::string word = unplaced_word(app, deepest);
  if (!word.empty()) {
    std::string path;
    for (CLI::App* a = deepest; a; a = a->get_parent()) path = a->get_name() + (path.empty() ? "" : " " + path);
    std::fprintf(stderr, "glasspiv: error: '%s' is not a command or argument of `%s` (see `%s --help`)\n",
                 word.c_str(), path.c_str(), path.c_str());
    return 2;
  }
  return app.exit(e);
}

}  // namespace

int main(int argc, char** argv) {
  // Progress lines reach a log or a pipe as they are printed, not at exit.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  // Past a file-size limit (ulimit -f) write() fails with EFBIG instead of the
  // process dying of SIGXFSZ: the writer reports the output and removes its temporary.
  std::signal(SIGXFSZ, SIG_IGN);
  // Named, so usage lines read `glasspiv ...`, not the executable's full path.
  CLI::App app{"glasspiv: calibrated, ray-traced correction of PIV images taken through glass", "glasspiv"};
  app.set_version_flag("--version", std::string("glasspiv ") + GLASSPIV_VERSION);
  app.require_subcommand(1);
  glasspiv::register_camera_commands(app);
  glasspiv::register_demo_command(app);
  glasspiv::register_target_commands(app);
  glasspiv::register_calib_commands(app);
  glasspiv::register_render_command(app);
  glasspiv::register_correct_commands(app);
  glasspiv::register_align_commands(app);
  glasspiv::register_piv_command(app);
  glasspiv::register_simulate_command(app);
  // One check for the numbers of every command (finite, decimal, not negative where unsigned).
  glasspiv::check_numeric_options(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return help_or_unknown(app, e);
  } catch (const CLI::CallForAllHelp& e) {
    return help_or_unknown(app, e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ConversionError& e) {
    std::fprintf(stderr, "glasspiv: error: %s (see --help)\n", glasspiv::conversion_problem(app, e).c_str());
    return 2;
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "glasspiv: error: %s (see --help)\n", e.what());
    return 2;
  } catch (const glasspiv::InputError& e) {
    std::fprintf(stderr, "glasspiv: error: %s\n", e.what());
    return 2;
  } catch (const std::filesystem::filesystem_error& e) {
    // The commands check their files first (apps/cli_files.h) and turn what the
    // file system refuses into an InputError; one that still got here (a folder
    // removed or made read-only during the run) is the file system's refusal of
    // the user's file, not a bug: the path and the system's reason, exit 2.
    std::fprintf(stderr, "glasspiv: error: %s: %s\n", e.path1().empty() ? "a file" : e.path1().c_str(),
                 e.code().message().c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "glasspiv: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}
