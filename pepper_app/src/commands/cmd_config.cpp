// `pepper_app config dump [--config F] [--preset NAME] [--set K=V]...`: print the effective
// configuration as YAML. `pepper_app config doc`: print the Markdown reference of every parameter
// (docs/configuration.md).
#include <iostream>
#include <memory>

#include "commands/cli_util.hpp"
#include "commands/commands.hpp"
#include "config/app_config.hpp"
#include "config/config_doc.hpp"
#include "config/config_yaml.hpp"

namespace pepper::app {

void register_config_command(CLI::App& app) {
  auto sources = std::make_shared<ConfigSources>();
  auto* cmd = app.add_subcommand("config", "Inspect the configuration");
  cmd->require_subcommand(1);
  auto* dump = cmd->add_subcommand(
      "dump",
      "Print the effective configuration (defaults, then --preset, then --config, then each "
      "--set) as YAML;\nthe output is a valid --config file.");
  add_config_options(dump, sources->file, sources->preset, sources->sets,
                     "robot.camera_width_px=320");
  dump->footer(
      "Examples:\n  pepper_app config dump --set robot.camera_width_px=320 "
      "--set robot.camera_height_px=240 > qvga.yaml\n"
      "  pepper_app config dump --preset paper > paper.yaml");
  dump->callback([sources] {
    try {
      std::cout << json_to_yaml(config_to_json(load_app_config(*sources)));
      exit_code() = 0;
    } catch (const std::exception& e) {
      exit_code() = report_exception(e);
    }
  });
  auto* doc = cmd->add_subcommand(
      "doc",
      "Print the Markdown reference of every parameter (key, type, default, unit, range, doc)\n"
      "and of the presets, generated from the parameter table: docs/configuration.md.");
  doc->footer("Example:\n  pepper_app config doc > docs/configuration.md");
  doc->callback([] {
    std::cout << configuration_markdown();
    exit_code() = 0;
  });
}

}  // namespace pepper::app
