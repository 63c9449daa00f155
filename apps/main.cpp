// glasspiv: PIV inside transparent geometry. One executable, one subcommand per task.
#include <cstdio>
#include <exception>

#include <fmt/format.h>

#include "apps/commands.h"
#include "util/input_error.h"

int main(int argc, char** argv) {
  CLI::App app{"glasspiv: calibrated, ray-traced correction of PIV images taken through glass"};
  app.set_version_flag("--version", std::string("glasspiv ") + GLASSPIV_VERSION);
  app.require_subcommand(1);
  glasspiv::register_camera_commands(app);
  glasspiv::register_demo_command(app);
  glasspiv::register_target_commands(app);
  glasspiv::register_calib_commands(app);
  glasspiv::register_render_command(app);
  glasspiv::register_correct_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "glasspiv: error: %s (see --help)\n", e.what());
    return 2;
  } catch (const glasspiv::InputError& e) {
    std::fprintf(stderr, "glasspiv: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "glasspiv: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}
