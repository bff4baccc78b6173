#include "commands/cli_util.hpp"

#include <cstdio>
#include <iostream>

#include "config/parameters.hpp"
#include "core/camera/intrinsics_io.hpp"
#include "session/console.hpp"

namespace pepper::app {

void ProgressLine::update(std::size_t done, std::size_t total, const std::string& extra) {
  done_ = done;
  total_ = total;
  const auto now = std::chrono::steady_clock::now();
  if (done != total && now - last_ < std::chrono::milliseconds(500)) return;
  last_ = now;
  const double pct = total ? 100.0 * static_cast<double>(done) / static_cast<double>(total) : 0.0;
  std::fprintf(stderr, "%s: %zu/%zu (%.0f%%)%s%s\n", label_.c_str(), done, total, pct,
               extra.empty() ? "" : "  ", extra.c_str());
}

void ProgressLine::finish(const std::string& extra) {
  std::fprintf(stderr, "%s: done, %zu/%zu%s%s\n", label_.c_str(), done_, total_,
               extra.empty() ? "" : "  ", extra.c_str());
}

std::optional<core::CameraIntrinsics> load_camera_option(const std::string& path) {
  if (path.empty()) return std::nullopt;
  return core::camera::load_intrinsics(path);
}

int report_error(const std::string& what) {
  // Through the console: on a terminal it first clears a progress line of a running session.
  terminal_console().line("pepper_app: error: " + what);
  return 1;
}

void add_trust_options(CLI::App* cmd, std::string& tls_pin, bool& trust_new_robot) {
  cmd->add_option("--tls-pin", tls_pin,
                  "tcps://: the robot certificate's SHA-256 fingerprint (AB:CD:...); any other "
                  "certificate is refused before the password is sent (default: the "
                  "known-robots file, trust on first use)");
  cmd->add_flag("--trust-new-robot", trust_new_robot,
                "tcps://: trust a robot seen for the first time and remember its certificate "
                "fingerprint in the known-robots file ($PEPPER_KNOWN_ROBOTS, else "
                "~/.config/pepper_nav/known_robots); without it you are asked, or refused "
                "when there is no terminal");
}

void add_config_options(CLI::App* cmd, std::string& file, std::string& preset,
                        std::vector<std::string>& sets, const std::string& set_example) {
  std::vector<std::string> names;
  std::string listed;
  for (const auto& p : presets()) {
    names.push_back(p.name);
    listed += (listed.empty() ? "" : ", ") + p.name;
  }
  cmd->add_option("--config", file,
                  "Configuration file (YAML/JSON; `pepper_app config dump` writes a complete one, "
                  "docs/configuration.md lists every key)")
      ->check(CLI::ExistingFile);
  const std::string preset_help =
      "Named settings applied before --config and --set: " + listed + " (docs/configuration.md)";
  cmd->add_option("--preset", preset, preset_help)->check(CLI::IsMember(names));
  cmd->add_option(
      "--set", sets,
      "Override one parameter: dotted.key=value (repeatable), e.g. --set " + set_example);
}

}  // namespace pepper::app
