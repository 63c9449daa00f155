#pragma once
// Each area of glasspiv registers its subcommands on the one `glasspiv` app.
// Commands are thin: parse, call the library, report. Errors travel as
// InputError and become one line and exit status 2 in main().
#include <CLI/CLI.hpp>

namespace glasspiv {

void register_camera_commands(CLI::App& app);
void register_demo_command(CLI::App& app);
void register_target_commands(CLI::App& app);
void register_calib_commands(CLI::App& app);
void register_render_command(CLI::App& app);
void register_correct_commands(CLI::App& app);  // correct, coverage
void register_align_commands(CLI::App& app);    // align pose, check, refine, sensitivity
void register_piv_command(CLI::App& app);
void register_simulate_command(CLI::App& app);
// Called by register_calib_commands on its `calib` group.
void register_calib_detect_command(CLI::App& calib);
void register_calib_next_command(CLI::App& calib);
// Called by register_align_commands on its `align` group.
void register_align_fit_command(CLI::App* align);

}  // namespace glasspiv
