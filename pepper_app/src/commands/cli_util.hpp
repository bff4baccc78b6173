#pragma once
// Small helpers shared by the command files: progress lines, camera files, error reporting, the
// configuration options.

#include <chrono>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "commands/error_advice.hpp"
#include "core/camera/intrinsics.hpp"

namespace pepper::app {

/// Prints "label: done/total (pct%)" on stderr at most every 0.5 s, and a final line.
class ProgressLine {
 public:
  explicit ProgressLine(std::string label) : label_(std::move(label)) {}
  void update(std::size_t done, std::size_t total, const std::string& extra = "");
  void finish(const std::string& extra = "");

 private:
  std::string label_;
  std::chrono::steady_clock::time_point last_{};
  std::size_t done_ = 0, total_ = 0;
};

/// Loads --camera FILE (.xml ViSP, .yaml/.yml/.json plain) when non-empty.
std::optional<core::CameraIntrinsics> load_camera_option(const std::string& path);

/// Adds --config FILE, --preset NAME and --set dotted.key=value (repeatable) to `cmd`, filling
/// `file`, `preset` and `sets` (load_app_config's ConfigSources). `set_example` is a key=value
/// shown in the help.
void add_config_options(CLI::App* cmd, std::string& file, std::string& preset,
                        std::vector<std::string>& sets, const std::string& set_example);

/// Adds --tls-pin SHA256 and --trust-new-robot (tcps:// robots; session/known_robots.hpp), as
/// every command that connects to a robot takes them.
void add_trust_options(CLI::App* cmd, std::string& tls_pin, bool& trust_new_robot);

/// Prints "pepper_app: error: <what>" to stderr and returns exit code 1.
int report_error(const std::string& what);

}  // namespace pepper::app
