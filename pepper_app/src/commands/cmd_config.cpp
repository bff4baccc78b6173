// `pepper_app config dump [--config F] [--set K=V]...`: print the effective configuration as YAML.
#include <iostream>
#include <memory>

#include "commands/cli_util.hpp"
#include "commands/commands.hpp"
#include "config/app_config.hpp"
#include "config/config_yaml.hpp"

namespace pepper::app {
namespace {

struct ConfigArgs {
  std::string file;
  std::vector<std::string> sets;
};

}  // namespace

void register_config_command(CLI::App& app) {
  auto args = std::make_shared<ConfigArgs>();
  auto* cmd = app.add_subcommand("config", "Inspect the configuration");
  cmd->require_subcommand(1);
  auto* dump = cmd->add_subcommand(
      "dump",
      "Print the effective configuration (defaults, then --config, then each --set) as YAML;\n"
      "the output is a valid --config file.");
  dump->add_option("--config", args->file, "Configuration file (YAML/JSON)")
      ->check(CLI::ExistingFile);
  dump->add_option("--set", args->sets, "Override one parameter: dotted.key=value (repeatable)");
  dump->footer("Example:\n  pepper_app config dump --set robot.camera_width_px=320 "
               "--set robot.camera_height_px=240 > qvga.yaml");
  dump->callback([args] {
    try {
      std::cout << json_to_yaml(config_to_json(load_app_config(args->file, args->sets)));
      exit_code() = 0;
    } catch (const std::exception& e) {
      exit_code() = report_error(e.what());
    }
  });
}

}  // namespace pepper::app
