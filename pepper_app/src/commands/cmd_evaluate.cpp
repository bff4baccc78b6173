// `pepper_app evaluate`: closed-loop evaluation on the mock robot (docs/evaluation.md): teach a
// world's tour, replay it from perturbed starts (optionally with disturbances and for several
// feature sets), print a table, write JSON, PNG plots and an HTML report.
#include <cstdio>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "commands/cli_util.hpp"
#include "commands/commands.hpp"
#include "config/app_config.hpp"
#include "evaluation/closed_loop.hpp"
#include "evaluation/output.hpp"
#include "report/map_page.hpp"
#include "session/session_cli.hpp"
#include "sim/world.hpp"

namespace pepper::app {

namespace {

namespace ev = pepper::app::evaluation;

struct EvaluateArgs {
  std::vector<std::string> worlds;
  int starts = 10;
  std::string features = "both";
  std::string controller;  ///< empty: the configuration's navigator.controller
  uint64_t seed = 1;
  std::string json_out;
  std::string plots_dir;
  std::string map_dir;
  std::vector<std::string> disturbances{"none"};
  bool compare_features = false;
  std::string size = "640x480";
  std::string lens = "none";            ///< --lens: none or pepper (the mock's lens)
  std::string lens_correction = "on";   ///< --lens-correction: on or off
  std::string mode = "forward";  ///< --mode (core/nav_mode.hpp)
  double lateral_m = 0.3;
  double yaw_deg = 10.0;
  double along_m = -1.0;
  double light_factor = 0.0;
  double drop_probability = 0.15;
  double latency_s = 0.2;
  int crowd_people = 5;
  double converged_after_m = 1.5;
  double converged_below_m = 0.05;
  double end_tolerance_m = 0.3;
  bool quiet = false;
  ConfigSources config;
  std::string trace_dir;
  std::vector<int> only_runs;
  std::string command_line;
};

core::control::FeatureMode parse_features(const std::string& s) {
  if (s == "both" || s == "lines+points") return core::control::FeatureMode::kLinesAndPoints;
  if (s == "lines") return core::control::FeatureMode::kLinesOnly;
  if (s == "points") return core::control::FeatureMode::kPointsOnly;
  throw std::invalid_argument("--features must be lines, points or both, got '" + s + "'");
}

/// "none", "light", "light+person", ...
std::set<ev::Disturbance> parse_disturbance_set(const std::string& s) {
  std::set<ev::Disturbance> out;
  if (s == "none") return out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, '+')) out.insert(ev::parse_disturbance(item));
  return out;
}

int run_evaluate(const EvaluateArgs& a) {
  ev::EvaluationOptions o;
  if (std::sscanf(a.size.c_str(), "%dx%d", &o.width_px, &o.height_px) != 2) {
    std::cerr << "pepper_app evaluate: --size must be WIDTHxHEIGHT, got '" << a.size
              << "': give 640x480 or 320x240\n";
    return 2;
  }
  std::vector<core::control::FeatureMode> modes;
  std::vector<std::set<ev::Disturbance>> configs;
  try {
    if (a.compare_features) {
      modes = {core::control::FeatureMode::kLinesOnly, core::control::FeatureMode::kPointsOnly,
               core::control::FeatureMode::kLinesAndPoints};
    } else {
      modes = {parse_features(a.features)};
    }
    for (const auto& d : a.disturbances) configs.push_back(parse_disturbance_set(d));
    ev::set_lens_options(a.lens, a.lens_correction, o);
    if (!a.controller.empty() && a.controller != "ibvs" && a.controller != "vnhv") {
      throw std::invalid_argument("--controller must be ibvs or vnhv, got '" + a.controller + "'");
    }
  } catch (const std::invalid_argument& e) {
    std::cerr << "pepper_app evaluate: " << message_with_next_step(e) << "\n";
    return 2;
  }
  try {
    // --controller is a shorthand for --set navigator.controller=... (applied last).
    ConfigSources sources = a.config;
    if (!a.controller.empty()) sources.sets.push_back("navigator.controller=" + a.controller);
    const AppConfig config = load_app_config(sources);
    const core::NavMode mode = parse_mode(a.mode);
    o.mode = mode;
    o.ceiling = config.ceiling_navigator_options();
    if (mode == core::NavMode::kCeiling && (a.compare_features || a.features != "both")) {
      // A usage error, not a configuration value: std::invalid_argument adds no --set advice.
      throw std::invalid_argument(
          (a.compare_features ? std::string("--compare-features") : "--features " + a.features) +
          " chooses the forward mode's features: drop it with --mode ceiling (it navigates by the "
          "ceiling mosaic's landmarks)");
    }
    o.navigator = config.navigator_options();
    o.key_images = config.teach_options().selector;
    o.head = head_request(config, mode);
    o.give_up_lost_s = config.replay.give_up_lost_s;
    o.give_up_not_localised_s = config.replay.give_up_not_localised_s;
    o.arrival_tolerance_m = config.replay.arrival_tolerance_m;
    o.arrival_tolerance_rad = config.replay.arrival_tolerance_rad;
  } catch (const std::exception& e) {
    std::cerr << "pepper_app evaluate: " << message_with_next_step(e) << "\n";
    return 2;
  }
  o.starts = a.starts;
  o.only_runs = a.only_runs;
  o.seed = a.seed;
  o.trace_dir = a.trace_dir;
  o.perturb_lateral_m = a.lateral_m;
  o.perturb_yaw_deg = a.yaw_deg;
  o.perturb_along_m = a.along_m;
  o.disturbance.light_factor = a.light_factor;
  o.disturbance.drop_probability = a.drop_probability;
  o.disturbance.latency_s = a.latency_s;
  o.disturbance.crowd_people = a.crowd_people;
  o.converged_after_m = a.converged_after_m;
  o.converged_below_m = a.converged_below_m;
  o.end_tolerance_m = a.end_tolerance_m;
  if (const auto errors = o.validate(); !errors.empty()) {
    for (const auto& e : errors) std::cerr << "pepper_app evaluate: " << e << "\n";
    return 2;
  }
  const ev::ProgressFn progress = [&a](const std::string& line) {
    if (!a.quiet) std::cerr << line << std::endl;
  };

  std::vector<ev::Evaluation> results;
  std::vector<std::filesystem::path> plots;
  std::vector<ev::KeyImageStrip> strips;
  for (const std::string& world_file : a.worlds) {
    auto world = std::make_shared<const sim::World>(sim::load_world(world_file));
    ev::EvaluationOptions to = o;
    if (!a.map_dir.empty()) {
      to.map_dir = std::filesystem::path(a.map_dir) / (world->name + "_" + a.size);
    } else if (!a.plots_dir.empty()) {
      to.map_dir = std::filesystem::path(a.plots_dir) / ("map_" + world->name + "_" + a.size);
    }
    for (const auto mode : modes) {
      // Each modality teaches its own map (lines or points only are whole systems).
      ev::EvaluationOptions mo = to;
      mo.features = mode;
      if (!mo.map_dir.empty()) mo.map_dir += ev::single_modality_tag(mode, "_");
      if (!mo.map_dir.empty() && mo.mode == core::NavMode::kCeiling) mo.map_dir += "_ceiling";
      const ev::TeachResult teach = ev::teach_tour(world, mo, progress);
      if (!a.plots_dir.empty()) {
        strips.push_back({world->name + " (" + core::control::to_string(mode) + ")",
                          report::key_image_thumbnails(teach.map, {})});
      }
      for (const auto& config : configs) {
        ev::EvaluationOptions ro = mo;
        ro.disturbances = config;
        ev::Evaluation e = ev::evaluate(teach, world, ro, progress);
        if (!a.plots_dir.empty()) {
          std::string dist;
          for (const auto& d : e.disturbances) dist += (dist.empty() ? "" : "+") + d;
          const std::string prefix =
              e.world_name + "_" + e.features + (dist.empty() ? "" : "_" + dist) + "_";
          const auto files = ev::write_plots(e, teach, *world, a.plots_dir, prefix);
          plots.insert(plots.end(), files.begin(), files.end());
        }
        if (!a.quiet) std::cout << ev::runs_table(e) << std::endl;
        results.push_back(std::move(e));
      }
    }
  }
  std::cout << ev::summary_table(results);
  if (!a.json_out.empty()) ev::write_text_file(a.json_out, ev::to_json(results).dump(2) + "\n");
  if (!a.plots_dir.empty()) {
    ev::write_html_report(results, plots, strips, a.command_line,
                          std::filesystem::path(a.plots_dir) / "report.html");
  }
  int failures = 0;
  for (const auto& e : results) failures += e.summary.runs - e.summary.successes;
  return failures == 0 ? 0 : 1;
}

}  // namespace

void register_evaluate_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "evaluate",
      "Closed-loop evaluation on the mock robot: teach a world's tour, replay it from perturbed "
      "starts (lateral, heading, along the tour), with optional disturbances, and report success, "
      "lateral deviation from the taught path, final error, key images per metre, omega "
      "smoothness and per-frame time (docs/evaluation.md). Exit code 1 when a run fails.");
  auto args = std::make_shared<EvaluateArgs>();
  cmd->add_option("--world", args->worlds, "World YAML file(s) (worlds/*.yaml)")->required();
  add_config_options(cmd, args->config.file, args->config.preset, args->config.sets,
                     "key_images.relative=0.5");
  cmd->add_option("--trace", args->trace_dir,
                  "Write one JSON-lines trace per run here (ground truth, command, telemetry per "
                  "frame) to diagnose a failed run");
  add_mode_option(cmd, args->mode);
  cmd->add_option("--starts", args->starts, "Replay runs per configuration")->capture_default_str();
  cmd->add_option("--run", args->only_runs,
                  "Replay only these runs of the --starts (1-based; same starts and seeds as in "
                  "the full evaluation), e.g. --starts 10 --run 5 8 --trace DIR");
  cmd->add_option("--features", args->features, "lines, points or both")->capture_default_str();
  cmd->add_option("--controller", args->controller,
                  "ibvs or vnhv (default: the configuration's navigator.controller)");
  cmd->add_option("--seed", args->seed, "Seed of start perturbations, noise and disturbances")
      ->capture_default_str();
  cmd->add_option("--json", args->json_out, "Write the results as JSON to this file");
  cmd->add_option("--plots", args->plots_dir, "Write PNG plots, report.html and the map here");
  cmd->add_option("--map-dir", args->map_dir, "Folder for the taught maps (default: under --plots "
                                              "or a temporary folder)");
  cmd->add_option("--disturbance", args->disturbances,
                  "One or more configurations, each none or "
                  "light|furniture|person|crowd|drops|latency, combined with '+' (e.g. "
                  "light+person); each is evaluated separately. crowd: several people crossing "
                  "the path ahead of the robot (they step aside for it; docs/evaluation.md)")
      ->capture_default_str();
  cmd->add_flag("--compare-features", args->compare_features,
                "Run lines only, points only and both, side by side");
  cmd->add_option("--size", args->size, "Camera size, 640x480 or 320x240 (faster)")
      ->capture_default_str();
  cmd->add_option("--lens", args->lens,
                  "The mock camera's lens: none (pinhole) or pepper (Pepper's top-camera "
                  "calibration with ViSP's distortion model, kud 0.0275)")
      ->capture_default_str();
  cmd->add_option("--lens-correction", args->lens_correction,
                  "on: the app's camera model has the lens's distortion and undistorts the "
                  "features; off: the app takes the pinhole calibration of the same camera")
      ->capture_default_str();
  cmd->add_option("--lateral-m", args->lateral_m, "Start perturbation, lateral, +- metres")
      ->capture_default_str();
  cmd->add_option("--yaw-deg", args->yaw_deg, "Start perturbation, heading, +- degrees")
      ->capture_default_str();
  cmd->add_option("--along-m", args->along_m,
                  "Start perturbation along the tour, +- metres (< 0: the world's range)")
      ->capture_default_str();
  cmd->add_option("--light-factor", args->light_factor,
                  "light disturbance: every light x this, for every run (0: x0.6 to x1.4, evenly "
                  "spread over the runs); the world's own window change stays on top")
      ->capture_default_str();
  cmd->add_option("--drop-probability", args->drop_probability, "drops disturbance: p(frame lost)")
      ->capture_default_str();
  cmd->add_option("--latency-s", args->latency_s, "latency disturbance: command latency, s")
      ->capture_default_str();
  cmd->add_option("--crowd-people", args->crowd_people,
                  "crowd disturbance: how many people cross the path")
      ->capture_default_str();
  cmd->add_option("--converged-after-m", args->converged_after_m,
                  "Deviation statistics skip this travelled distance")
      ->capture_default_str();
  cmd->add_option("--converged-below-m", args->converged_below_m,
                  "... and once |lateral| fell below this (0: distance rule alone)")
      ->capture_default_str();
  cmd->add_option("--end-tolerance-m", args->end_tolerance_m,
                  "Success: final position within this of the taught end")
      ->capture_default_str();
  cmd->add_flag("--quiet", args->quiet, "No progress lines and per-run tables");
  cmd->footer(
      "Examples:\n"
      "  pepper_app evaluate --world worlds/robotics_room.yaml --starts 10 --size 320x240 \\\n"
      "      --json eval.json --plots eval_plots\n"
      "  pepper_app evaluate --world worlds/window_corridor.yaml --disturbance none light person\n"
      "  pepper_app evaluate --world worlds/robotics_room.yaml --mode ceiling --disturbance crowd\n"
      "  pepper_app evaluate --world worlds/white_corridor.yaml --compare-features --starts 5");
  cmd->callback([args, cmd] {
    std::string line = "pepper_app evaluate";
    for (const auto& w : args->worlds) line += " --world " + w;
    args->command_line = line + " (" + cmd->config_to_str(true, false) + ")";
    try {
      exit_code() = run_evaluate(*args);
    } catch (const std::exception& e) {
      std::cerr << "pepper_app evaluate: " << message_with_next_step(e) << "\n";
      exit_code() = 1;
    }
  });
}

}  // namespace pepper::app
