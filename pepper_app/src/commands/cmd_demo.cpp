// `pepper_app demo [--world W] [--out DIR] [--ui] [--quick]`: the newcomer's main job. On the mock
// robot: teach a shipped world's whole tour (robotics_room: a loop around the central tables with
// four 90-degree turns, back to the start; scripted drive, no human), replay it from a perturbed
// start, and write an HTML report (top view of taught and replayed paths, omega and feature-count
// plots, summary table). Everything happens through the same session loops as `teach` and
// `replay` on a real robot; only the robot is simulated. `--mode ceiling` teaches a ceiling
// map and replays it with the ceiling navigator, as `teach`/`replay --mode ceiling` do (the
// feature-count plot then shows the landmarks matched, telemetry's point count).
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands/cli_util.hpp"
#include "commands/commands.hpp"
#include "core/memory/visual_memory.hpp"
#include "evaluation/metrics.hpp"
#include "report/html_report.hpp"
#include "report/plot.hpp"
#include "session/ceiling_replay.hpp"
#include "session/console.hpp"
#include "session/replay_session.hpp"
#include "session/session_cli.hpp"
#include "session/signals.hpp"
#include "session/teach_session.hpp"
#include "teach_ui/ui_server.hpp"

namespace pepper::app {
namespace {

struct DemoArgs {
  CommonSessionArgs common;
  std::string world;  // empty: the default world (default_world())
  std::string out = "demo_out";
  double max_distance_m = 0.0;  // 0: the whole tour
  bool quick = false;           // the first straight only (kQuickDistance_m), for the test suite
  uint64_t seed = 1;
  bool vga = false;
};

// --quick: the first straight of robotics_room, stopping before its corner (about 10 s of CPU
// instead of about 40 s for the whole loop).
constexpr double kQuickDistance_m = 4.5;

std::string fmt(double v, int prec = 3) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(prec) << v;
  return s.str();
}

/// "1.9 m in 2 stretches" (ground-truth distance of the frames driven on odometry alone).
std::string blind_summary(const std::vector<ReplaySample>& samples) {
  double blind_m = 0.0;
  int stretches = 0;
  for (size_t i = 1; i < samples.size(); ++i) {
    const ReplaySample& a = samples[i - 1];
    const ReplaySample& b = samples[i];
    if (b.dead_reckoning && !a.dead_reckoning) ++stretches;
    if (b.dead_reckoning && a.has_pose && b.has_pose) {
      blind_m += std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    }
  }
  if (stretches == 0) return "none";
  return fmt(blind_m, 2) + " m in " + std::to_string(stretches) + " stretch" +
         (stretches == 1 ? "" : "es");
}

// worlds/robotics_room.yaml from the current folder (the README runs from the checkout), else
// from the source tree this binary was built from, so `demo` also works from any folder.
std::string default_world() {
  const std::filesystem::path here = "worlds/robotics_room.yaml";
  if (std::filesystem::exists(here)) return here.string();
  return (std::filesystem::path(PEPPER_WORLDS_DIR) / "robotics_room.yaml").string();
}

int run_demo(const DemoArgs& args) {
  DemoArgs a = args;
  if (a.world.empty()) a.world = default_world();
  if (a.quick) a.max_distance_m = kQuickDistance_m;
  using Clock = std::chrono::steady_clock;
  Console& console = session_console(args.common);
  try {
    CommonSessionArgs common = a.common;
    if (!a.vga) {
      // QVGA keeps the default run short on 2 cores (VGA: --vga).
      common.sets.insert(common.sets.begin(), {"robot.camera_width_px=320",
                                               "robot.camera_height_px=240"});
    }
    const AppConfig config = load_session_config(common);
    const core::NavMode mode = parse_mode(common.mode);
    const std::filesystem::path out = a.out;
    std::filesystem::create_directories(out);
    const std::filesystem::path map_dir = out / "map";
    const std::filesystem::path rec_dir = out / "teach.recording";
    std::filesystem::remove_all(rec_dir);
    EventSink events(common.events);
    install_interrupt_handlers();
    auto ui = start_session_ui(common, config, events.stream(), console);
    SessionLink link(ui.get(), events.stream());
    link.set_console(&console);
    const std::string url = "mock:" + a.world;

    // 1. Teach.
    const auto t0 = Clock::now();
    console.line("demo 1/3: teaching " +
                 (a.max_distance_m > 0 ? fmt(a.max_distance_m, 1) + " m of the tour"
                                       : std::string("the whole tour (its turns and the way "
                                                     "back)")) +
                 " in " + a.world + " (scripted drive on the simulated Pepper)");
    RobotConnection teach_robot = open_robot(url, robot_connect_options(common, config));
    TeachSessionOptions to;
    to.map_dir = map_dir;
    to.recording_dir = rec_dir;
    to.camera = camera_request(config);
    to.head = head_request(config, mode);
    to.teach = config.teach_options();
    to.mode = mode;
    to.feedback = teach_feedback_limits(config, to.min_key_features);
    to.config_json = config_to_json(config).dump();
    to.scripted = true;
    to.max_distance_m = a.max_distance_m;
    to.frame_timeout_ms = config.robot.frame_timeout_ms();
    if (ui) to.pace_hz = 2.0 * config.robot.camera_fps;  // watchable, still quick
    const TeachResult taught = run_teach_session(teach_robot, to, link);
    for (const auto& w : taught.warnings) console.warning(w);
    if (!taught.ok()) {
      return report_error("teach " + taught.outcome + ": " + taught.error);
    }
    const double teach_s = std::chrono::duration<double>(Clock::now() - t0).count();
    console.line("  taught: " + std::to_string(taught.frames_recorded) + " frames, " +
                 std::to_string(taught.key_images) + " key images, " +
                 fmt(taught.distance_m, 2) + " m in " + fmt(teach_s, 1) + " s");

    // 2. Replay from a perturbed start.
    const auto t1 = Clock::now();
    RobotConnection replay_robot = open_robot(url, robot_connect_options(common, config));
    const auto start = replay_robot.mock->world().scenario.replay_start(0, a.seed);
    replay_robot.mock->place(start);
    replay_robot.mock->set_lighting("replay");
    console.line("demo 2/3: replaying from a perturbed start (x " + fmt(start.x_m, 2) + " m, y " +
                 fmt(start.y_m, 2) + " m, yaw " + fmt(start.yaw_rad * 180 / M_PI, 1) + " deg)");
    ReplaySessionOptions ro;
    ro.camera = to.camera;
    ro.head = to.head;
    ro.navigator = config.navigator_options();
    ro.frame_timeout_ms = config.robot.frame_timeout_ms();
    ro.telemetry_jsonl = out / "replay.jsonl";
    ro.config_json = to.config_json;
    ro.taught_path_m = taught.path_m;
    ro.taught_keys_m = taught.key_m;
    // Safety cap: three times the taught frames.
    ro.max_frames = 3 * taught.frames_recorded + 300;
    ro.give_up_lost_s = config.replay.give_up_lost_s;
    ro.give_up_not_localised_s = config.replay.give_up_not_localised_s;
    ro.arrival_tolerance_m = config.replay.arrival_tolerance_m;
    ro.arrival_tolerance_rad = config.replay.arrival_tolerance_rad;
    if (ui) ro.pace_hz = 2.0 * config.robot.camera_fps;
    core::memory::VisualMemory map = core::memory::load_map(map_dir);
    StepFunction step;  // ceiling mode: the ceiling navigator steps the same replay loop
    if (mode == core::NavMode::kCeiling) {
      CeilingReplay ceiling =
          make_ceiling_replay(replay_robot.mock.get(), config.robot.ceiling_height_m, map_dir, map,
                              ro.head.head_pitch_rad, config.ceiling_navigator_options());
      step = std::move(ceiling.step);
      ro.ceiling_telemetry = std::move(ceiling.telemetry_json);
    }
    const ReplayResult replayed =
        run_replay_session(replay_robot, std::move(map), ro, link, std::move(step));
    const double replay_s = std::chrono::duration<double>(Clock::now() - t1).count();
    console.line("  replay " + replayed.outcome + " after " + std::to_string(replayed.frames) +
                 " frames (" + fmt(replay_s, 1) + " s)" +
                 (replayed.detail.empty() ? std::string() : ": " + replayed.detail) +
                 (replayed.error.empty() ? std::string() : ": " + replayed.error));

    // 3. Report.
    console.line("demo 3/3: writing the report");
    namespace ev = evaluation;
    std::vector<double> travelled, lateral, tx, ty, rx, ry, ts, omega, nl, np;
    ev::Polyline path(taught.path_m);
    ev::PathTracker tracker(path, 1.5);
    double dist = 0.0;
    for (std::size_t i = 0; i < replayed.samples.size(); ++i) {
      const auto& s = replayed.samples[i];
      if (i > 0) {
        const auto& p = replayed.samples[i - 1];
        dist += std::hypot(s.x_m - p.x_m, s.y_m - p.y_m);
      }
      travelled.push_back(dist);
      lateral.push_back(tracker.update({s.x_m, s.y_m}).lateral_m);
      rx.push_back(s.x_m);
      ry.push_back(s.y_m);
      ts.push_back(s.t_s);
      omega.push_back(s.omega_rad_s);
      nl.push_back(s.n_lines);
      np.push_back(s.n_points);
    }
    for (const auto& p : taught.path_m) {
      tx.push_back(p.x());
      ty.push_back(p.y());
    }
    // Converged part: after 1.0 m of driving (the perturbed start needs that to settle).
    const ev::DeviationStats dev = ev::lateral_stats(travelled, lateral, 1.0);
    const double final_error_m =
        replayed.samples.empty()
            ? NAN
            : (Eigen::Vector2d(rx.back(), ry.back()) - taught.path_m.back()).norm();

    report::HtmlReport html("Pepper teach & replay demo: " + a.world);
    html.heading("Summary");
    report::Table table;
    table.header = {"quantity", "value"};
    table.rows = {
        {"success (end of tour reached)", replayed.tour_complete ? "yes" : "no"},
        {"replay outcome", replayed.outcome},
        {"arrival (the replay's own estimate)",
         replayed.tour_complete ? replayed.arrival.verdict + ", " +
                                      fmt(replayed.arrival.offset_m * 100, 1) + " cm from " +
                                      replayed.arrival.source
                                : std::string("-")},
        {"taught distance", fmt(taught.distance_m, 2) + " m"},
        {"key images", std::to_string(taught.key_images)},
        {"lateral deviation RMS (after 1 m)", fmt(dev.rms_m * 100, 1) + " cm"},
        {"lateral deviation max (after 1 m)", fmt(dev.max_m * 100, 1) + " cm"},
        {"final position error (ground truth)", fmt(final_error_m * 100, 1) + " cm"},
        {"driven on odometry alone (vision blind)", blind_summary(replayed.samples)},
        {"replay start", "x " + fmt(start.x_m, 2) + " m, y " + fmt(start.y_m, 2) + " m, yaw " +
                             fmt(start.yaw_rad * 180 / M_PI, 1) + " deg"},
        {"frames (teach / replay)",
         std::to_string(taught.frames_recorded) + " / " + std::to_string(replayed.frames)},
        {"camera", std::to_string(to.camera.width_px) + "x" + std::to_string(to.camera.height_px)},
        {"wall time (teach / replay)", fmt(teach_s, 1) + " s / " + fmt(replay_s, 1) + " s"},
    };
    for (const auto& w : taught.warnings) table.rows.push_back({"teach warning", w});
    html.table(table);
    html.heading("Top view (ground truth)");
    report::PlotSpec top{"Taught and replayed paths", "x (m)", "y (m)", 900, 600, true};
    // Where the replay drove on odometry alone (vision blind, issue 29).
    report::Series blind{"driven on odometry alone", {}, {}, cv::Scalar(0, 0, 220), 1, true};
    for (const auto& smp : replayed.samples) {
      if (smp.dead_reckoning && smp.has_pose) {
        blind.x.push_back(smp.x_m);
        blind.y.push_back(smp.y_m);
      }
    }
    html.image(report::render_plot(top, {{"taught", tx, ty, report::palette(0)},
                                         {"replayed", rx, ry, report::palette(1)},
                                         blind}),
               "Base positions in the world frame");
    html.heading("Control");
    html.image(report::render_plot({"Yaw rate command", "t (s)", "omega (rad/s)"},
                                   {{"omega", ts, omega, report::palette(2)}}),
               "omega sent to the base (0 while stopped)");
    html.image(report::render_plot({"Verified matches with the next key image", "t (s)", "count"},
                                   {{"lines", ts, nl, report::palette(0)},
                                    {"points", ts, np, report::palette(3)}}),
               "Feature counts");
    html.image(report::render_plot({"Lateral deviation", "travelled (m)", "lateral (m)"},
                                   {{"lateral", travelled, lateral, report::palette(1)}}),
               "Signed distance from the taught path (> 0 left)");
    const std::filesystem::path report_file = out / "report.html";
    html.write(report_file);
    link.event({{"event", "report"},
                {"path", report_file.string()},
                {"success", replayed.tour_complete},
                {"lateral_rms_m", dev.rms_m},
                {"lateral_max_m", dev.max_m},
                {"final_error_m", final_error_m},
                {"key_images", taught.key_images}});
    console.line(std::string("result: ") +
                 (replayed.tour_complete ? "tour complete" : "tour not completed (" +
                                                                 replayed.outcome + ")") +
                 ", lateral deviation RMS " + fmt(dev.rms_m * 100, 1) + " cm, max " +
                 fmt(dev.max_m * 100, 1) + " cm, final error " + fmt(final_error_m * 100, 1) +
                 " cm (ground truth)");
    console.line("report: " + std::filesystem::absolute(report_file).string());
    return replayed.tour_complete ? 0 : 1;
  } catch (const std::exception& e) {
    return report_exception(e);
  }
}

}  // namespace

void register_demo_command(CLI::App& app) {
  auto args = std::make_shared<DemoArgs>();
  auto* cmd = app.add_subcommand(
      "demo",
      "Teach the whole tour of a shipped world on the simulated Pepper (scripted drive; the\n"
      "default robotics_room: a loop of about 16 m with four 90-degree turns, back to the start),\n"
      "replay it from a perturbed start, and write an HTML report (top view, omega and feature\n"
      "plots, summary). About a minute at 320x240; --quick teaches the first straight only.\n"
      "With --ui the run can be watched live in a browser.");
  add_common_session_options(cmd, args->common, false);
  cmd->add_option("--world", args->world,
                  "World file (default: worlds/robotics_room.yaml of this checkout)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "Output folder (map, recording, telemetry, report.html)");
  auto* distance =
      cmd->add_option("--distance", args->max_distance_m, "Metres of the tour to teach (0 = all)")
          ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--quick", args->quick,
                "Teach only the first 4.5 m (robotics_room: the first straight, no turn): about "
                "a quarter of the time, for tests")
      ->excludes(distance);
  cmd->add_option("--seed", args->seed, "Replay start perturbation seed (0 = unperturbed)");
  cmd->add_flag("--vga", args->vga, "Use 640x480 frames (slower) instead of 320x240");
  cmd->footer(
      "Examples:\n"
      "  pepper_app demo --world worlds/robotics_room.yaml --out /tmp/demo --ui\n"
      "  pepper_app demo --quick --out /tmp/demo --events /tmp/demo_events.jsonl\n"
      "Console: the phases, a progress line per phase (key image k of K, distance, frame rate,\n"
      "elapsed) that updates in place on a terminal (a line every 5 s in a log), warnings and\n"
      "the result. The events (JSON lines: commands, teach_done, replay_done, report) go to\n"
      "--events FILE, or to stdout with --events -.");
  cmd->callback([args] { exit_code() = run_demo(*args); });
}

}  // namespace pepper::app
