// `pepper_app replay --robot URL --map DIR`: drive a taught tour again by itself.
// See pepper_app/src/session/replay_session.hpp and docs/user_guide.md.
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands/cli_util.hpp"
#include "commands/commands.hpp"
#include "core/memory/visual_memory.hpp"
#include "evaluation/closed_loop.hpp"
#include "session/ceiling_replay.hpp"
#include "session/console.hpp"
#include "session/replay_session.hpp"
#include "session/session_cli.hpp"
#include "session/signals.hpp"
#include "session/taught_path.hpp"
#include "sim/world.hpp"
#include "teach_ui/ui_server.hpp"

namespace pepper::app {
namespace {

struct ReplayArgs {
  CommonSessionArgs common;
  std::string map;
  std::string record;
  std::string json_out;
  int64_t max_frames = 0;
  int mock_start = -1;
  uint64_t seed = 1;
  std::string mock_lighting;  ///< empty: "replay" with --mock-start, else the robot's own
  bool wait_start = false;
  std::string mock_command_log;
  std::string camera;  ///< --camera FILE: the calibration the map was taught with
};

/// Exit codes (docs/user_guide.md "Exit codes"): 0 the tour was completed, 1 the replay ended
/// without completing it (lost, not localised, overdue, STOP, stalled camera, frame limit),
/// 3 the connection to the robot was lost, 4 an error (exception, collision, refused map),
/// 130 interrupted (Ctrl-C).
int replay_exit_code(const ReplayResult& r) {
  if (r.tour_complete) return 0;
  if (r.outcome == "interrupted") return 130;
  if (r.outcome == "connection_lost") return 3;
  if (r.outcome == "error" || r.outcome == "collision") return 4;
  return 1;
}

int run_replay(const ReplayArgs& a) {
  Console& console = session_console(a.common);
  try {
    const AppConfig config = load_session_config(a.common);
    const core::NavMode mode = parse_mode(a.common.mode);
    refuse_ceiling_on_real_robot(mode, a.common.robot, config, "replay");  // before map and robot
    core::memory::LoadOptions load;
    load.expected_mode = mode;  // a map of the other mode is refused, naming both
    core::memory::VisualMemory map = core::memory::load_map(a.map, load);
    const RobotConnectOptions connect = robot_connect_options(a.common, config);
    RobotConnection robot = open_robot(a.common.robot, connect);
    if (robot.mock && a.mock_start >= 0) {
      // The simulated robot of `evaluate`'s run K+1 with this seed: same start, camera noise and
      // lighting, so the two replay the same run.
      evaluation::EvaluationOptions eo;
      eo.seed = a.seed;
      evaluation::MockReplaySetup setup = evaluation::mock_replay_setup(
          robot.mock->world(), a.mock_start, a.mock_lighting.empty() ? "replay" : a.mock_lighting,
          eo);
      setup.robot.frame_rate_hz = connect.mock_frame_rate_hz;
      setup.bridge.description = robot.url.url;
      const RobotUrl url = robot.url;
      const auto world = robot.mock->world_ptr();
      robot.bridge.reset();  // it refers to the robot: gone first
      robot.mock.reset();
      robot = open_mock_robot(world, setup.robot, setup.bridge);
      robot.url = url;
      robot.mock->place(setup.start);
    } else if (!a.mock_lighting.empty() && robot.mock) {
      robot.mock->set_lighting(a.mock_lighting);
    }
    ReplaySessionOptions o;
    // The map decides the camera size (an explicit conflicting --set is refused).
    o.camera = camera_request_for_map(a.common, config, map.camera);
    o.camera_model = load_camera_option(a.camera);
    if (o.camera.width_px != config.robot.camera_width_px ||
        o.camera.height_px != config.robot.camera_height_px) {
      console.line("replay: camera " + std::to_string(o.camera.width_px) + "x" +
                   std::to_string(o.camera.height_px) + ", the size the map was taught at");
    }
    o.head = head_request(config, mode);
    o.navigator = config.navigator_options();
    o.frame_timeout_ms = config.robot.frame_timeout_ms();
    o.max_frames = a.max_frames;
    o.give_up_lost_s = config.replay.give_up_lost_s;
    o.give_up_not_localised_s = config.replay.give_up_not_localised_s;
    o.arrival_tolerance_m = config.replay.arrival_tolerance_m;
    o.arrival_tolerance_rad = config.replay.arrival_tolerance_rad;
    o.telemetry_jsonl = a.json_out;
    o.record_dir = a.record;
    o.wait_for_start = a.wait_start;
    o.config_json = config_to_json(config).dump();
    const bool ui_wanted = a.common.ui || a.common.ui_port >= 0;
    if (robot.mock && ui_wanted) o.pace_hz = config.robot.camera_fps;
    if (robot.mock) {  // the top view shows the taught path when the map was taught on this world
      try {
        const auto taught = load_taught_path(a.map);
        if (taught && taught->world == robot.mock->world().name) {
          o.taught_path_m = taught->path_m;
          o.taught_keys_m = taught->key_images_m;
        } else if (taught) {
          console.line("pepper_app replay: note: the map was taught in mock world '" +
                       taught->world + "', not this one: no taught path in the top view");
        }
      } catch (const std::exception& e) {  // display only: never a reason not to replay
        console.line(std::string("pepper_app replay: warning: ") + e.what());
      }
    }
    {
      const auto problems = o.validate();
      if (!problems.empty()) {
        for (const auto& p : problems) console.line("pepper_app replay: " + p);
        return 2;
      }
    }
    EventSink events(a.common.events);
    install_interrupt_handlers();
    auto ui = start_session_ui(a.common, config, events.stream(), console);
    SessionLink link(ui.get(), events.stream());
    link.set_console(&console);
    console.line("replay: " + std::to_string(map.key_images.size()) + " key images from " + a.map +
                 " on " + robot.bridge->describe() + "; Ctrl-C (or STOP in the UI) stops the robot");
    // Ceiling mode: the ceiling navigator steps the same replay loop (ceiling_replay.hpp).
    StepFunction step;
    if (mode == core::NavMode::kCeiling) {
      CeilingReplay ceiling =
          make_ceiling_replay(robot.mock.get(), config.robot.ceiling_height_m, a.map, map,
                              o.head.head_pitch_rad, config.ceiling_navigator_options());
      for (const auto& w : ceiling.warnings) console.line("pepper_app replay: warning: " + w);
      step = std::move(ceiling.step);
      o.ceiling_telemetry = std::move(ceiling.telemetry_json);
    }
    const ReplayResult r = run_replay_session(robot, std::move(map), o, link, step);
    if (!a.mock_command_log.empty() && robot.mock) {
      std::ofstream out(a.mock_command_log);
      for (const auto& c : robot.mock->command_log()) {
        out << nlohmann::json{{"t_ns", c.t_ns},
                              {"v_x_m_s", c.velocity.v_x_m_s},
                              {"omega_rad_s", c.velocity.omega_rad_s},
                              {"stop_move", c.stop_move}}
                   .dump()
            << "\n";
      }
    }
    // One result line: the outcome, why, and how far the replay came.
    std::ostringstream result;
    result << "replay " << r.outcome << ": ";
    if (!r.error.empty()) {
      const std::string step = next_step_for(r.error_exception);
      result << r.error << (step.empty() ? "" : ": " + step) << "; ";
    } else if (!r.detail.empty()) {
      result << r.detail << "; ";
    }
    result << r.frames << " frames, ";
    if (r.max_key_reached < 0) {
      result << "never localised in the map's " << r.key_image_count << " key images";
    } else {
      result << "furthest key image " << r.max_key_reached << " of " << r.key_image_count - 1;
    }
    console.line(result.str());
    return replay_exit_code(r);
  } catch (const std::exception& e) {
    // A ConfigError or a RobotUrlError is 2: refused before anything moved.
    return report_exception(e, 4);
  }
}

}  // namespace

void register_replay_command(CLI::App& app) {
  auto args = std::make_shared<ReplayArgs>();
  auto* cmd = app.add_subcommand(
      "replay",
      "Replay a taught tour: localise in the map, then servo along the key images until the end\n"
      "of the tour. The robot stops whenever the navigator is unsure, frames stall, the\n"
      "connection is lost, on Ctrl-C and on the UI's STOP. Exit code 0 when the end was reached.");
  add_common_session_options(cmd, args->common, true);
  cmd->add_option("--map", args->map, "Map folder (from `teach` or `map build`)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--record", args->record, "Also record the replay's frames in this folder");
  cmd->add_option("--camera", args->camera,
                  "Calibration of the robot's camera, the file the map was taught with (`teach "
                  "--camera`): checked against the map's camera, model included")
      ->check(CLI::ExistingFile);
  cmd->add_option("--json", args->json_out,
                  "Write per-frame command + telemetry as JSON lines (every frame; the "
                  "session's events, one per change, are --events)");
  cmd->add_option("--max-frames", args->max_frames, "Stop after this many frames")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--mock-start", args->mock_start,
                  "mock: robots: start where `evaluate` starts its run K+1 (the world's start, "
                  "perturbed by --seed: up to 0.3 m sideways, 10 degrees, and along the tour), "
                  "with the same camera noise")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--seed", args->seed, "Seed of --mock-start's perturbation and camera noise (0: the taught start, unperturbed)")
      ->capture_default_str();
  cmd->add_option("--mock-lighting", args->mock_lighting,
                  "mock: robots: the world's lighting condition to replay under (teach, replay, "
                  "... as the world file names them; default: replay with --mock-start, else "
                  "teach)");
  cmd->add_flag("--wait-start", args->wait_start, "Wait for the UI's start-replay button");
  cmd->add_option("--mock-command-log", args->mock_command_log,
                  "mock: robots: write every base command received as JSON lines here");
  cmd->footer(
      "Examples:\n"
      "  pepper_app replay --robot tcp://10.0.0.5 --map maps/lab --ui --json lab_run1.jsonl\n"
      "  pepper_app replay --robot mock:worlds/robotics_room.yaml --map /tmp/room --mock-start 0\n"
      "  pepper_app replay --robot mock:worlds/robotics_room.yaml --map /tmp/room --events run.jsonl\n"
      "Console: a progress line (key image k of K, distance, frame rate, elapsed) that updates in\n"
      "place on a terminal (a line every 5 s in a log), warnings and the result line. The events\n"
      "(JSON lines: commands, localisation, warnings, replay_done) go to --events FILE, or to\n"
      "stdout with --events -.");
  cmd->callback([args] { exit_code() = run_replay(*args); });
}

}  // namespace pepper::app
