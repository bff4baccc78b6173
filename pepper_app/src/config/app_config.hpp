#pragma once
// The application's configuration: every parameter of every concern, with the measured defaults
// (the core options structs' in-class defaults), loadable from YAML/JSON and overridable on the
// command line with dotted names: `--set navigator.ibvs.g1=0.6 --set robot.camera_fps=10`.
//
// File layout (sections = concerns; `pepper_app config dump` prints the full default file,
// docs/configuration.md lists every key with its default, unit, range and meaning):
//   features:   extractor (lines, LBD, FAST, ORB, KLT) and matcher (line matching, RANSACs)
//               — shared by teach and replay, since a map's descriptors must match replay's.
//   key_images: teach key-image selection (epsilon rule)
//   navigator:  control laws, velocity schedule, localisation, switching, hold time
//   robot:      camera request, head lock, safety timeouts, login user
//   replay:     when a replay that cannot go on gives up
//   ui:         teach UI port and driving limits
// A file may also name a preset (`preset: paper`), applied before the file's own values.
// Every key, type, unit and range is declared once, in config/parameters.cpp. Unknown keys and
// wrong types are errors naming the dotted key and the file (with the closest known key); the
// ranges are checked from that table, then the core's validate() functions check the rules
// between fields, before anything moves (STYLE.md 2.5).

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/mapping/teacher.hpp"
#include "core/navigator/navigator.hpp"

namespace pepper::core::ceiling {
struct CeilingNavigatorOptions;  // core/ceiling/ceiling_navigator.hpp
}  // namespace pepper::core::ceiling

namespace pepper::app {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A setting that conflicts with the map being read (the camera size): its message says which
/// setting to drop, so no generic "fix the value" advice is added to it.
class MapConflictError : public ConfigError {
 public:
  using ConfigError::ConfigError;
};

struct RobotConfig {
  int camera_width_px = 640;  ///< kVGA; 320x240 (kQVGA) also supported
  int camera_height_px = 480;
  int camera_fps = 15;
  double head_pitch_rad = 0.0;  ///< 0 = optical axis horizontal (METHOD.md assumes it)
  double head_yaw_rad = 0.0;
  /// Head pitch of the lock in ceiling mode (--mode ceiling, issue 24): looking up, near
  /// HeadPitch's limit (-0.7068 rad), so the camera sees the ceiling from ~0.8 m ahead.
  double ceiling_head_pitch_rad = -0.7;
  /// The ceiling's height above the floor where the robot drives (m), measured by the operator:
  /// ceiling mode on a real robot needs it (the canonical view's scale; a wrong height scales
  /// every distance). 0 = not set: ceiling mode then runs on mock: robots only, which take their
  /// world's ceiling.
  double ceiling_height_m = 0.0;
  double watchdog_s = 0.3;       ///< bridge stops the base without a fresh command this long
  double frame_timeout_s = 1.0;  ///< session stops the base when no frame comes this long
  /// Robot-side deadman: each velocity command ends by itself on the robot after this long
  /// (ALMotion.moveTo with a time; docs/naoqi_bridge.md). 0 = plain move(), no robot-side stop.
  double deadman_horizon_s = 0.25;
  /// The three as whole milliseconds, as the sessions and the bridge take them.
  int watchdog_ms() const { return static_cast<int>(std::lround(watchdog_s * 1e3)); }
  int deadman_horizon_ms() const { return static_cast<int>(std::lround(deadman_horizon_s * 1e3)); }
  int frame_timeout_ms() const { return static_cast<int>(std::lround(frame_timeout_s * 1e3)); }
  std::string user;              ///< login user for tcps:// (NAOqi 2.9: "nao"); password never here
  /// The rule between fields (640x480 or 320x240); each field's range is in the table.
  std::vector<std::string> validate() const;
};

struct ReplayConfig {
  /// Stopped this long (frame time) after having driven, whatever the navigator's reason: the
  /// replay ends as "lost" with advice. 0 = keep trying until the operator stops it.
  double give_up_lost_s = 10.0;
  /// Not localised this long after the first frame: the replay ends as "not_localised" with the
  /// best candidate key image and advice. 0 = wait until the operator stops it.
  double give_up_not_localised_s = 10.0;
  /// End of the tour: "arrived" when the estimated offset from the final key image is within
  /// these, else "not aligned" (m, rad).
  double arrival_tolerance_m = 0.15;
  double arrival_tolerance_rad = 0.1;
};

/// Ceiling-mode replay (issue 24; core/ceiling/ceiling_navigator.hpp, docs/method/ceiling.md):
/// what is its own. The law's gains and the speeds are the forward navigator's
/// (navigator.vnhv.kp_1_m2, kd_1_m, max_abs_theta_rad; navigator.speed.*).
struct CeilingConfig {
  double arc_min_turn_rad = 0.1;        ///< relay segments turning more follow their arc
  double turn_in_place_gain_1_s = 1.0;  ///< facing too far off the path: turn on the spot
  double coast_max_error_m = 0.03;       ///< no fix: coast while the odometry may be this far off
  double coast_max_s = 8.0;             ///< and at most this long since the last fix
};

struct UiConfig {
  int port = 8080;               ///< 0 = any free port
  double max_v_m_s = 0.25;       ///< teach driving limits from the keyboard / buttons
  double max_omega_rad_s = 0.5;
};

struct AppConfig {
  core::features::FeatureExtractorOptions extractor;
  core::features::MatcherOptions matcher;
  core::mapping::KeyImageSelectorOptions key_images;
  core::navigator::NavigatorOptions navigator;  ///< its extractor/matcher come from the above
  RobotConfig robot;
  ReplayConfig replay;
  CeilingConfig ceiling;
  UiConfig ui;

  core::mapping::TeachOptions teach_options() const;
  core::navigator::NavigatorOptions navigator_options() const;
  /// The ceiling navigator's options: `ceiling`, with the forward navigator's VNHV gains and
  /// speed schedule.
  core::ceiling::CeilingNavigatorOptions ceiling_navigator_options() const;

  /// Every problem, each naming the dotted key; empty when valid. The ranges of the parameter
  /// table first (check_ranges); only when they hold, the rules between fields of the core's
  /// and RobotConfig's validate() (their per-field messages would repeat the table's).
  std::vector<std::string> validate() const;
};

/// The whole configuration as JSON (every key, enums by name).
nlohmann::json config_to_json(const AppConfig& config);

/// Applies `tree` over `config` (missing keys keep their value). Unknown keys and wrong types
/// throw ConfigError naming the dotted key; `origin` (a file name) prefixes the message.
void apply_config_json(const nlohmann::json& tree, AppConfig& config, const std::string& origin);

/// Reads a YAML or JSON file into a JSON tree. Throws ConfigError naming the file.
nlohmann::json read_config_file(const std::filesystem::path& file);

/// Parses "dotted.key=value" (value read as a YAML scalar) into a JSON patch tree.
nlohmann::json parse_override(const std::string& assignment);

/// Where a command's configuration comes from (--config, --preset, --set).
struct ConfigSources {
  std::string file;               ///< YAML/JSON file; "" for none
  std::string preset;             ///< preset name (parameters.hpp presets()); "" for none
  std::vector<std::string> sets;  ///< "dotted.key=value", applied in order
};

/// Defaults, then the preset (`sources.preset`, else the file's top-level `preset:` key), then
/// the file's values, then each override in order; then validate(). Throws ConfigError listing
/// every problem.
AppConfig load_app_config(const ConfigSources& sources);
AppConfig load_app_config(const std::filesystem::path& file, const std::vector<std::string>& sets);

}  // namespace pepper::app
