#pragma once
// Command-line wiring shared by `teach`, `replay` and `demo`: the common options (--robot,
// --config, --preset, --set, --ui, --ui-port, --user, --password-file), the effective
// configuration, the robot connection options, the camera / head-lock requests from RobotConfig,
// the teach UI server (started on 127.0.0.1; its URL is written as the event
// {"event":"listening","url":"http://127.0.0.1:PORT/"}, plus a human line on the console), and
// the machine-readable event sink (--events FILE, or - for stdout).

#include <CLI/CLI.hpp>
#include <fstream>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "config/app_config.hpp"
#include "core/camera/intrinsics.hpp"
#include "core/nav_mode.hpp"
#include "naoqi_bridge/robot_bridge.hpp"
#include "session/robot_connection.hpp"
#include "session/teach_feedback.hpp"

namespace pepper::teach_ui {
class UiServer;
}

namespace pepper::app {

struct CommonSessionArgs {
  std::string robot;
  std::string config_file;
  std::string preset;
  std::vector<std::string> sets;
  bool ui = false;
  int ui_port = -1;  ///< -1: config ui.port; 0: any free port
  std::string user;
  std::string password_file;
  std::string tls_pin;           ///< tcps: required certificate fingerprint (replaces the file)
  bool trust_new_robot = false;  ///< tcps: trust and remember a robot seen for the first time
  std::string events;  ///< --events: JSON-lines event file, "-" for stdout, "" for none
  std::string mode = "forward";  ///< --mode: forward or ceiling (core/nav_mode.hpp)
};

class Console;

/// Where the session's JSON-lines events go (`--events`): nowhere (""), stdout ("-", what the
/// commands printed before the console existed, for scripts that read a pipe) or a file
/// (truncated). Throws std::runtime_error "FILE: cannot write: ..." when the file cannot be
/// created.
class EventSink {
 public:
  explicit EventSink(const std::string& spec);
  EventSink(const EventSink&) = delete;
  EventSink& operator=(const EventSink&) = delete;
  /// Null when there is no sink.
  std::ostream* stream() { return out_; }

 private:
  std::ofstream file_;
  std::ostream* out_ = nullptr;
};

/// Adds --config, --preset, --set, --ui, --ui-port, --events, --mode (and --robot, --user,
/// --password-file, --tls-pin, --trust-new-robot when `with_robot`).
void add_common_session_options(CLI::App* cmd, CommonSessionArgs& args, bool with_robot);

/// Defaults + --preset + --config file + --set overrides, validated. Throws ConfigError listing
/// problems.
AppConfig load_session_config(const CommonSessionArgs& args);

RobotConnectOptions robot_connect_options(const CommonSessionArgs& args, const AppConfig& config);
naoqi_bridge::CameraRequest camera_request(const AppConfig& config);
/// The teach's live warnings against this configuration: a view needs `min_key_features` lines
/// + points (the weak-key-image bound), the replay min_best_count verified matches to recognise
/// a key image, and the heading rule's bound and frame gap say how fast key images can follow a
/// turn (docs/teach_ui.md "Teach feedback").
TeachFeedbackLimits teach_feedback_limits(const AppConfig& config, int min_key_features);
/// The head lock: robot.head_pitch_rad in forward mode, robot.ceiling_head_pitch_rad in ceiling
/// mode (the yaw is robot.head_yaw_rad in both).
naoqi_bridge::HeadLockRequest head_request(const AppConfig& config,
                                           core::NavMode mode = core::NavMode::kForward);

/// A mode asked for that the commands do not implement; its message says what exists and what to
/// do instead (a ConfigError: exit 2, refused before anything was started).
class ModeUnavailableError : public ConfigError {
 public:
  using ConfigError::ConfigError;
};

/// Adds `--mode forward|ceiling` (default forward) to a command.
void add_mode_option(CLI::App* cmd, std::string& mode);

/// The mode of a --mode value; throws ConfigError listing the modes for any other text.
core::NavMode parse_mode(const std::string& text);


/// Ceiling mode needs the ceiling's height above the floor: a mock: robot's world has it, a real
/// robot needs robot.ceiling_height_m. Throws ModeUnavailableError (exit 2, before anything
/// connects) for ceiling mode on a robot URL that is not `mock:` without that height; returns
/// otherwise. Throws RobotUrlError for a URL that names no robot.
void refuse_ceiling_on_real_robot(core::NavMode mode, const std::string& robot_url,
                                  const AppConfig& config, const std::string& command);

/// The map decides the camera size (issue 30): throws ConfigError, naming the setting to drop,
/// when a --set in `sets` or the `config_file` explicitly asks for a size other than the map's;
/// returns when the size is the map's or only the default differs.
void refuse_camera_size_other_than_map(const std::string& config_file,
                                       const std::vector<std::string>& sets,
                                       const AppConfig& config,
                                       const core::CameraIntrinsics& map_camera);

/// The camera request for replaying a map taught with `map_camera`: the map decides the size
/// (the rest as camera_request). Throws ConfigError, naming the setting to drop, when a --set or
/// the --config file explicitly asks for another size.
naoqi_bridge::CameraRequest camera_request_for_map(const CommonSessionArgs& args,
                                                   const AppConfig& config,
                                                   const core::CameraIntrinsics& map_camera);

/// The command line's console (terminal_console()) for a session with these options: with
/// `--events -` on a terminal, the JSON lines share the screen, so the progress line is printed
/// as log lines instead of being rewritten in place.
Console& session_console(const CommonSessionArgs& args);

/// Starts the UI when --ui or --ui-port was given (else returns null) and announces its URL: as
/// the "listening" event on `events` (may be null) and as a line on `console` (the UI's own
/// warnings go there too).
std::unique_ptr<teach_ui::UiServer> start_session_ui(const CommonSessionArgs& args,
                                                     const AppConfig& config,
                                                     std::ostream* events, Console& console);

}  // namespace pepper::app
