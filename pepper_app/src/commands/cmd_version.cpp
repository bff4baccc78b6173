#include <iostream>

#include <opencv2/core/version.hpp>

#include "commands/commands.hpp"

namespace pepper::app {

int& exit_code() {
  static int code = 0;
  return code;
}

void register_version_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("version", "Print the version of pepper_app and its libraries.");
  cmd->footer("Example:\n  pepper_app version");
  cmd->callback([] {
    std::cout << "pepper_app 0.1.0 (OpenCV " << CV_VERSION << ")\n";
    exit_code() = 0;
  });
}

}  // namespace pepper::app
