// pepper_app: teach a room tour to Pepper, replay it, replay it offline on the mock robot.
// Wiring only: every subcommand is registered from pepper_app/src/commands/.
#include <exception>
#include <iostream>

#include <CLI/CLI.hpp>

#include "commands/commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "pepper_app: appearance-based teach & replay navigation for SoftBank Pepper\n"
      "(line segments + points, image-based visual servoing; Bista et al., IROS 2017).\n"
      "Run 'pepper_app <command> --help' for the options and an example of each command."};
  app.require_subcommand(1);
  app.footer("Robot URLs: tcp://HOST:9559 (NAOqi 2.5), tcps://HOST:9503 (NAOqi 2.9, login),\n"
             "mock:WORLD.yaml (in-process simulated Pepper).");

  pepper::app::register_version_command(app);
  pepper::app::register_perception_demo_command(app);
  pepper::app::register_map_command(app);
  pepper::app::register_replay_log_command(app);
  pepper::app::register_world_command(app);
  pepper::app::register_doctor_command(app);
  pepper::app::register_mock_robot_command(app);
  pepper::app::register_evaluate_command(app);
  pepper::app::register_teach_command(app);
  pepper::app::register_replay_command(app);
  pepper::app::register_demo_command(app);
  pepper::app::register_config_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "pepper_app: error: " << e.what() << "\n";
    return 1;
  }
  return pepper::app::exit_code();
}
