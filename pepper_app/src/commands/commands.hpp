#pragma once
// Each pepper_app subcommand lives in its own file and registers itself on the root CLI11 app.
// The list is explicit (main.cpp calls each function) so that nothing depends on static
// initialisation order or on the linker keeping unreferenced objects.
//
// Convention for a registrar: add a subcommand with a one-paragraph description and an example
// in its footer, bind options to a struct owned by a shared_ptr captured in the callback, and in
// the callback run the command, returning through `exit_code` (0 success, 1 failure, 2 bad usage).

#include <CLI/CLI.hpp>

namespace pepper::app {

/// Exit code of the command that ran (set by the callbacks).
int& exit_code();

void register_version_command(CLI::App& app);
void register_perception_demo_command(CLI::App& app);
void register_map_command(CLI::App& app);
void register_replay_log_command(CLI::App& app);
void register_world_command(CLI::App& app);
void register_doctor_command(CLI::App& app);
void register_mock_robot_command(CLI::App& app);
void register_evaluate_command(CLI::App& app);
void register_teach_command(CLI::App& app);
void register_replay_command(CLI::App& app);
void register_demo_command(CLI::App& app);
void register_config_command(CLI::App& app);

}  // namespace pepper::app
