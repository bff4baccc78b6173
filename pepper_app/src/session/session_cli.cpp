#include "session/session_cli.hpp"

#include <unistd.h>

#include <iostream>

#include <nlohmann/json.hpp>

#include "commands/cli_util.hpp"
#include "session/console.hpp"
#include "teach_ui/ui_server.hpp"

namespace pepper::app {

void add_common_session_options(CLI::App* cmd, CommonSessionArgs& args, bool with_robot) {
  if (with_robot) {
    cmd->add_option("--robot", args.robot,
                    "Robot URL: tcp://HOST[:9559], tcps://HOST[:9503], mock:WORLD.yaml")
        ->required();
    cmd->add_option("--user", args.user, "Login user for tcps:// (NAOqi 2.9: nao); default robot.user");
    cmd->add_option("--password-file", args.password_file,
                    "File whose first line is the password (else $PEPPER_PASSWORD, else a prompt)")
        ->check(CLI::ExistingFile);
    add_trust_options(cmd, args.tls_pin, args.trust_new_robot);
  }
  add_config_options(cmd, args.config_file, args.preset, args.sets, "robot.camera_fps=10");
  cmd->add_option("--events", args.events,
                  "Write the machine-readable events (JSON lines: commands, key images, "
                  "warnings, the result) to this file; - writes them to stdout, as before the "
                  "console showed a progress line");
  cmd->add_flag("--ui", args.ui, "Serve the teach UI on 127.0.0.1 (port: ui.port)");
  cmd->add_option("--ui-port", args.ui_port, "Serve the teach UI on this port (0 = any free port)")
      ->check(CLI::Range(0, 65535));
  add_mode_option(cmd, args.mode);
}

void add_mode_option(CLI::App* cmd, std::string& mode) {
  cmd->add_option("--mode", mode,
                  "What the robot navigates by: forward (the camera looking ahead) or ceiling "
                  "(the camera looking up, docs/method/ceiling.md; mock: robots only for "
                  "now)")
      ->check(CLI::IsMember({"forward", "ceiling"}))
      ->capture_default_str();
}

core::NavMode parse_mode(const std::string& text) {
  const auto mode = core::nav_mode_from_string(text);
  if (!mode) throw ConfigError("--mode " + text + ": must be forward or ceiling");
  return *mode;
}

void refuse_ceiling_on_real_robot(core::NavMode mode, const std::string& robot_url,
                                  const AppConfig& config, const std::string& command) {
  if (mode != core::NavMode::kCeiling) return;
  if (parse_robot_url(robot_url).kind == RobotUrl::Kind::kMock) return;
  if (config.robot.ceiling_height_m > 0.0) return;
  throw ModeUnavailableError(
      command +
      " --mode ceiling on a real robot needs the ceiling's height above the floor, which sets the "
      "scale of everything the camera sees of it: measure it and set robot.ceiling_height_m "
      "(e.g. --set robot.ceiling_height_m=2.7, or in the config file; docs/method/ceiling.md). "
      "mock: robots take their world's ceiling");
}

EventSink::EventSink(const std::string& spec) {
  if (spec.empty()) return;
  if (spec == "-") {
    out_ = &std::cout;
    return;
  }
  file_.open(spec, std::ios::out | std::ios::trunc);
  if (!file_) {
    throw std::runtime_error(spec + ": cannot write: check that its folder exists and is writable");
  }
  out_ = &file_;
}

Console& session_console(const CommonSessionArgs& args) {
  Console& console = terminal_console();
  if (args.events == "-" && ::isatty(STDOUT_FILENO) == 1) console.set_in_place(false);
  return console;
}

AppConfig load_session_config(const CommonSessionArgs& args) {
  return load_app_config(ConfigSources{args.config_file, args.preset, args.sets});
}

RobotConnectOptions robot_connect_options(const CommonSessionArgs& args, const AppConfig& config) {
  RobotConnectOptions o;
  o.user = args.user.empty() ? config.robot.user : args.user;
  o.password_file = args.password_file;
  o.tls_pin = args.tls_pin;
  o.trust_new_robot = args.trust_new_robot;
  o.watchdog_ms = config.robot.watchdog_ms();
  o.frame_stall_ms = config.robot.frame_timeout_ms();
  o.deadman_horizon_ms = config.robot.deadman_horizon_ms();
  o.mock_frame_rate_hz = config.robot.camera_fps;
  return o;
}

naoqi_bridge::CameraRequest camera_request(const AppConfig& config) {
  naoqi_bridge::CameraRequest r;
  r.width_px = config.robot.camera_width_px;
  r.height_px = config.robot.camera_height_px;
  r.fps = config.robot.camera_fps;
  return r;
}

TeachFeedbackLimits teach_feedback_limits(const AppConfig& config, int min_key_features) {
  TeachFeedbackLimits f;
  f.min_view_features = min_key_features;
  f.min_verified_matches = config.navigator.initial.rule.min_best_count;
  // With the heading rule off (0) the count rule alone takes key images in turns; the warning
  // keeps the default bound (a third of the view) as the turn key images can follow.
  if (config.key_images.max_heading_change_rad > 0) {
    f.max_heading_change_rad = config.key_images.max_heading_change_rad;
  }
  f.min_frame_gap = config.key_images.min_frame_gap;
  return f;
}

namespace {

/// Where the camera size was set explicitly (every such "--set", else the --config file), or ""
/// when it is the default; `*count` settings.
std::string explicit_camera_size_source(const std::string& config_file,
                                        const std::vector<std::string>& sets, int* count) {
  std::string out;
  *count = 0;
  for (const auto& s : sets) {
    if (s.rfind("robot.camera_width_px=", 0) == 0 || s.rfind("robot.camera_height_px=", 0) == 0) {
      out += (out.empty() ? "--set " : " --set ") + s;
      ++*count;
    }
  }
  if (!out.empty()) return out;
  *count = 1;
  if (!config_file.empty()) {
    const nlohmann::json tree = read_config_file(config_file);
    if (tree.is_object() && tree.contains("robot") && tree["robot"].is_object() &&
        (tree["robot"].contains("camera_width_px") || tree["robot"].contains("camera_height_px"))) {
      return "robot.camera_width_px/camera_height_px in " + config_file;
    }
  }
  return "";
}

}  // namespace

void refuse_camera_size_other_than_map(const std::string& config_file,
                                       const std::vector<std::string>& sets,
                                       const AppConfig& config,
                                       const core::CameraIntrinsics& map_camera) {
  const int w = config.robot.camera_width_px, h = config.robot.camera_height_px;
  if (w == map_camera.width_px && h == map_camera.height_px) return;
  int settings = 0;
  const std::string source = explicit_camera_size_source(config_file, sets, &settings);
  if (!source.empty()) {
    throw MapConflictError("the map was taught at " + std::to_string(map_camera.width_px) + "x" +
                           std::to_string(map_camera.height_px) + " but " + source +
                           " asks for " + std::to_string(w) + "x" + std::to_string(h) +
                           (settings > 1 ? ": drop those settings" : ": drop that setting") +
                           " (the map decides the camera size)");
  }
}

naoqi_bridge::CameraRequest camera_request_for_map(const CommonSessionArgs& args,
                                                   const AppConfig& config,
                                                   const core::CameraIntrinsics& map_camera) {
  naoqi_bridge::CameraRequest r = camera_request(config);
  refuse_camera_size_other_than_map(args.config_file, args.sets, config, map_camera);
  r.width_px = map_camera.width_px;
  r.height_px = map_camera.height_px;
  return r;
}

naoqi_bridge::HeadLockRequest head_request(const AppConfig& config, core::NavMode mode) {
  naoqi_bridge::HeadLockRequest r;
  r.head_yaw_rad = config.robot.head_yaw_rad;
  r.head_pitch_rad = mode == core::NavMode::kCeiling ? config.robot.ceiling_head_pitch_rad
                                                     : config.robot.head_pitch_rad;
  return r;
}

std::unique_ptr<teach_ui::UiServer> start_session_ui(const CommonSessionArgs& args,
                                                     const AppConfig& config,
                                                     std::ostream* events, Console& console) {
  if (!args.ui && args.ui_port < 0) return nullptr;
  teach_ui::UiOptions o;
  o.port = static_cast<std::uint16_t>(args.ui_port >= 0 ? args.ui_port : config.ui.port);
  o.limits.max_v_m_s = config.ui.max_v_m_s;
  o.limits.max_omega_rad_s = config.ui.max_omega_rad_s;
  o.log = [&console](teach_ui::UiLogLevel level, std::string_view text) {
    if (level >= teach_ui::UiLogLevel::kWarning) console.line("teach UI: " + std::string(text));
  };
  auto ui = std::make_unique<teach_ui::UiServer>(o);
  ui->start();
  if (events != nullptr) {
    *events << nlohmann::json{{"event", "listening"}, {"url", ui->url()}, {"port", ui->port()}}.dump()
            << "\n"
            << std::flush;
  }
  console.line("teach UI: open " + ui->url() + " in a browser on this machine");
  return ui;
}

}  // namespace pepper::app
