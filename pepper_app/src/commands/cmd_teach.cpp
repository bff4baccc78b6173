// `pepper_app teach --robot URL --map DIR`: teach a tour (record frames, pick key images online,
// save the map). See pepper_app/src/session/teach_session.hpp and docs/user_guide.md.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands/cli_util.hpp"
#include "commands/commands.hpp"
#include "core/memory/visual_memory.hpp"
#include "session/console.hpp"
#include "session/session_cli.hpp"
#include "session/signals.hpp"
#include "session/teach_session.hpp"
#include "teach_ui/ui_server.hpp"

namespace pepper::app {
namespace {

struct TeachArgs {
  CommonSessionArgs common;
  std::string map;
  std::string recording;
  bool scripted = false;
  bool manual = false;
  double max_distance_m = 0.0;
  int64_t max_frames = 0;
  std::string mock_command_log;
  bool overwrite = false;
  std::string camera;  ///< --camera FILE: the calibration to normalise features with
};

namespace fs = std::filesystem;

/// A short description of what is in an existing map folder, for the refusal message.
std::string describe_existing(const fs::path& dir) {
  try {
    const auto map = core::memory::load_map(dir);
    return "a map with " + std::to_string(map.key_images.size()) + " key images";
  } catch (const std::exception&) {
    return "files that are not a readable map";
  }
}

std::filesystem::path free_recording_dir(const std::filesystem::path& map) {
  std::filesystem::path base = map;
  base += ".recording";
  std::filesystem::path p = base;
  for (int i = 1; std::filesystem::exists(p) && !std::filesystem::is_empty(p); ++i) {
    p = base;
    p += "." + std::to_string(i);
  }
  return p;
}

/// Writes the simulated robot's command log as JSON lines (tests assert on the last command).
void write_command_log(const RobotConnection& robot, const std::string& file) {
  if (file.empty() || !robot.mock) return;
  std::ofstream out(file);
  for (const auto& c : robot.mock->command_log()) {
    out << nlohmann::json{{"t_ns", c.t_ns},
                          {"v_x_m_s", c.velocity.v_x_m_s},
                          {"omega_rad_s", c.velocity.omega_rad_s},
                          {"stop_move", c.stop_move}}
               .dump()
        << "\n";
  }
}

// teach --overwrite replaces the old map only with a tour at least this long (m).
constexpr double kMinReplacingTourM = 0.1;

int run_teach(const TeachArgs& a) {
  const fs::path map_dir(a.map);
  const bool map_exists =
      fs::exists(map_dir) && !(fs::is_directory(map_dir) && fs::is_empty(map_dir));
  if (map_exists && !a.overwrite) {
    std::cerr << "pepper_app teach: " << map_dir.string() << " already holds "
              << describe_existing(map_dir) << ": choose another --map, or add --overwrite "
              << "(the old map is then kept as " << map_dir.string()
              << ".previous until the new one is saved)\n";
    return 2;
  }
  fs::path previous;  // where the old map waits while the new one is taught
  Console& console = session_console(a.common);
  try {
    const AppConfig config = load_session_config(a.common);
    const core::NavMode mode = parse_mode(a.common.mode);
    // Refused (exit 2) before the old map is moved aside or anything connects.
    refuse_ceiling_on_real_robot(mode, a.common.robot, config, "teach");
    RobotConnection robot = open_robot(a.common.robot, robot_connect_options(a.common, config));
    if (a.scripted && a.manual) return report_error(
          "--scripted and --manual exclude each other: drop one (--scripted drives the mock "
          "world's path, --manual drives from the UI)");
    TeachSessionOptions o;
    o.map_dir = a.map;
    o.recording_dir =
        a.recording.empty() ? free_recording_dir(a.map) : std::filesystem::path(a.recording);
    o.camera = camera_request(config);
    o.camera_model = load_camera_option(a.camera);
    o.head = head_request(config, mode);
    o.ceiling_height_m = config.robot.ceiling_height_m;
    o.teach = config.teach_options();
    o.mode = mode;
    o.feedback = teach_feedback_limits(config, o.min_key_features);
    o.config_json = config_to_json(config).dump();
    const bool ui_wanted = a.common.ui || a.common.ui_port >= 0;
    o.scripted = a.scripted || (robot.mock && !a.manual && !ui_wanted);
    o.max_distance_m = a.max_distance_m;
    o.max_frames = a.max_frames;
    o.frame_timeout_ms = config.robot.frame_timeout_ms();
    o.max_v_m_s = config.ui.max_v_m_s;
    o.max_omega_rad_s = config.ui.max_omega_rad_s;
    // A simulated robot runs in lockstep; with an operator, pace it at the camera rate.
    if (robot.mock && !o.scripted) o.pace_hz = config.robot.camera_fps;
    {
      const auto problems = o.validate();
      if (!problems.empty()) {
        for (const auto& p : problems) console.line("pepper_app teach: " + p);
        return 2;
      }
    }
    if (map_exists) {
      previous = map_dir;
      previous += ".previous";
      fs::remove_all(previous);
      fs::rename(map_dir, previous);
      console.line("teach: the old map waits in " + previous.string() +
                   " until the new one is saved");
    }
    EventSink events(a.common.events);
    install_interrupt_handlers();
    auto ui = start_session_ui(a.common, config, events.stream(), console);
    SessionLink link(ui.get(), events.stream());
    link.set_console(&console);
    console.line("teach: robot " + robot.bridge->describe() + ", recording to " +
                 o.recording_dir.string() + ", " +
                 (o.scripted ? "scripted drive along the world's path"
                             : "drive from the teach UI (arrow keys); finish with the UI's Finish "
                               "button or Ctrl-C"));
    const TeachResult r = run_teach_session(robot, o, link);
    write_command_log(robot, a.mock_command_log);
    bool kept_old = false;
    if (!previous.empty()) {
      // A tour of a few centimetres (Ctrl-C or Finish before the robot drove) is no tour: it
      // must not cost the operator the map it was to replace.
      const double new_m = std::isfinite(r.map_length_m) ? r.map_length_m : r.distance_m;
      if (r.map_saved && new_m < kMinReplacingTourM) {
        fs::path aside = map_dir;
        aside += ".short";
        fs::remove_all(aside);
        fs::rename(map_dir, aside);
        fs::rename(previous, map_dir);
        kept_old = true;
        std::ostringstream os;
        os << "teach: the new map covers " << std::fixed << std::setprecision(2) << new_m
           << " m (under " << kMinReplacingTourM << " m): the old map stays in " << map_dir.string()
           << "; the new one is kept in " << aside.string();
        console.line(os.str());
      } else if (r.map_saved) {
        fs::remove_all(previous);
      } else if (!fs::exists(map_dir)) {
        fs::rename(previous, map_dir);
        console.line("teach: no new map was saved: the old map is back in " + map_dir.string());
      }
      previous.clear();
    }
    for (const auto& w : r.warnings) console.line("pepper_app: warning: " + w);
    std::ostringstream result;
    result << "teach " << r.outcome << ": " << r.frames_recorded << " frames recorded in "
           << o.recording_dir.string() << ", " << std::fixed << std::setprecision(2)
           << r.distance_m << std::defaultfloat << " m";
    if (r.map_saved && mode == core::NavMode::kCeiling) {
      result << "; ceiling map with " << r.ceiling_landmarks << " landmarks, " << r.key_images
             << " relay images";
      if (std::isfinite(r.map_length_m)) {
        result << " and " << std::fixed << std::setprecision(2) << r.map_length_m
               << std::defaultfloat << " m";
      }
      result << " saved to " << (kept_old ? a.map + ".short" : a.map);
    } else if (r.map_saved) {
      result << "; map with " << r.key_images << " key images";
      // NaN: a map without distances (no odometry and no commanded speeds recorded).
      if (std::isfinite(r.map_length_m)) {
        result << " and " << std::fixed << std::setprecision(2) << r.map_length_m
               << std::defaultfloat << " m";
      }
      result << " saved to " << (kept_old ? a.map + ".short" : a.map);
    }
    console.line(result.str());
    if (!r.error.empty()) {
      const std::string step = next_step_for(r.error_exception);
      return report_error(r.error + (step.empty() ? "" : ": " + step));
    }
    if (r.outcome == "interrupted") return 130;
    return r.map_saved && !kept_old ? 0 : 1;
  } catch (const std::exception& e) {
    if (!previous.empty() && !fs::exists(map_dir)) {  // failed before a new map could be saved
      std::error_code ec;
      fs::rename(previous, map_dir, ec);
    }
    return report_exception(e);
  }
}

}  // namespace

void register_teach_command(CLI::App& app) {
  auto args = std::make_shared<TeachArgs>();
  auto* cmd = app.add_subcommand(
      "teach",
      "Teach a tour: drive the robot (teach UI arrow keys with a dead-man, or the mock world's\n"
      "scripted path), record every frame (crash-safe) and pick key images online; at the end\n"
      "(UI Finish, end of the scripted path, --max-distance, or Ctrl-C) the robot is stopped and\n"
      "the map saved. An interrupted teach keeps its recording: `pepper_app map build` turns it\n"
      "into a map.");
  add_common_session_options(cmd, args->common, true);
  cmd->add_option("--map", args->map,
                  "Map folder to write (saved atomically); an existing map is refused unless "
                  "--overwrite")
      ->required();
  cmd->add_flag("--overwrite", args->overwrite,
                "Replace the map in --map; the old one waits in MAP.previous until the new one "
                "is saved (and comes back if none is, or if the new tour is under 0.1 m: that one is "
                "kept in MAP.short)");
  cmd->add_option("--recording", args->recording,
                  "Recording folder (default: MAP.recording, or MAP.recording.N if taken)");
  cmd->add_flag("--scripted", args->scripted,
                "Drive along the mock world's taught path (mock: robots; default there without --ui)");
  cmd->add_flag("--manual", args->manual, "Drive from the teach UI even on a mock: robot");
  cmd->add_option("--camera", args->camera,
                  "Calibration of the robot's camera (ViSP XML, e.g. cameras/pepper_top.xml with "
                  "Pepper's lens distortion, or YAML): features are normalised through it instead "
                  "of the pinhole intrinsics the robot reports; the map records it, and replay "
                  "takes the same file")
      ->check(CLI::ExistingFile);
  cmd->add_option("--max-distance", args->max_distance_m, "End the tour after this many metres")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--max-frames", args->max_frames, "End the tour after this many frames")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--mock-command-log", args->mock_command_log,
                  "mock: robots: write every base command received as JSON lines here");
  cmd->footer(
      "Examples:\n"
      "  pepper_app teach --robot tcp://10.0.0.5 --map maps/lab --ui\n"
      "  pepper_app teach --robot mock:worlds/robotics_room.yaml --map /tmp/room "
      "--set robot.camera_width_px=320 --set robot.camera_height_px=240 --events teach.jsonl\n"
      "Console: a progress line (key images so far, distance, frame rate, elapsed) that updates\n"
      "in place on a terminal (a line every 5 s in a log), warnings and the result line. The\n"
      "events (JSON lines: commands, map_saved, teach_done) go to --events FILE, or to stdout\n"
      "with --events -.");
  cmd->callback([args] { exit_code() = run_teach(*args); });
}

}  // namespace pepper::app
