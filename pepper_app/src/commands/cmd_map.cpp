// `pepper_app map info DIR`, `map build --recording DIR --map DIR`, and the map management of
// issue 25: `map list DIR`, `map show MAP --out FILE.html`, `map trim MAP --from K --to L --out
// NEWMAP` (offline/map_tools.hpp, report/map_page.hpp).
#include <filesystem>
#include <iostream>
#include <memory>

#include "commands/cli_util.hpp"
#include "commands/commands.hpp"
#include "config/app_config.hpp"
#include "core/memory/visual_memory.hpp"
#include "offline/map_tools.hpp"
#include "offline/offline_jobs.hpp"
#include "report/map_page.hpp"
#include "session/ceiling_map.hpp"
#include "session/session_cli.hpp"
#include "session/taught_path.hpp"
#include "session/teach_session.hpp"

namespace pepper::app {
namespace {

struct MapInfoArgs {
  std::string dir;
  bool full = false;
};

struct MapListArgs {
  std::string dir;
};

struct MapShowArgs {
  std::string map;
  std::string out;
};

struct MapTrimArgs {
  std::string map;
  int from = 0;
  int to = -1;  ///< -1: the final key image
  std::string out;
  bool overwrite = false;
};

namespace fs = std::filesystem;

/// Usage errors of the map commands: exit code 2, nothing written.
int usage_error(const std::string& command, const std::string& what) {
  std::cerr << "pepper_app map " << command << ": " << what << "\n";
  return 2;
}

struct MapBuildArgs {
  std::string recording;
  std::string map;
  std::string camera;
  bool every_frame_key = false;
  double fps = 15.0;
  ConfigSources config;
  std::string steps_csv;
  std::string mode;  ///< --mode; "": the recording's own (forward when it does not say)
};

/// The teach's threshold for weak key images, so `map info`, `map show` and the
/// teach UI agree.
TourCheckOptions tour_check_options() {
  TourCheckOptions o;
  o.min_features = TeachSessionOptions{}.min_key_features;
  return o;
}

int run_map_info(const MapInfoArgs& a) {
  try {
    // --full loads and checks every file (checksums); default reads the manifest only.
    const core::memory::MapSummary summary =
        a.full ? core::memory::summarize(core::memory::load_map(a.dir))
               : core::memory::read_map_info(a.dir);
    if (summary.mode == core::NavMode::kCeiling) {
      // The mosaic and the tour are small: read and checked (checksums, agreement with the
      // manifest) in both forms. The forward checks (weak key images, long gaps) do not apply:
      // relay images are far apart by design and need no lines.
      const CeilingParts parts = load_ceiling_parts(a.dir, summary);
      std::cout << summary.to_text() << ceiling_summary_text(parts);
      for (const auto& w : ceiling_warnings(parts.tour)) std::cout << "warning: " << w << "\n";
      if (parts.tour.height_check) {
        if (const auto w = ceiling_height_warning(*parts.tour.height_check)) {
          std::cout << "warning: " << *w << "\n";
        }
      }
    } else {
      std::cout << summary.to_text();
      for (const auto& w : check_tour(summary, tour_check_options())) {
        std::cout << "warning: " << w.text << "\n";
      }
    }
    if (a.full) std::cout << "all files present and checksums verified\n";
    return 0;
  } catch (const std::exception& e) {
    return report_exception(e);
  }
}

int run_map_list(const MapListArgs& a) {
  try {
    const std::vector<MapListing> maps = find_maps(a.dir);
    for (const auto& m : maps) std::cout << to_text(m) << "\n";
    if (maps.empty()) {
      std::cerr << "map list: no maps under " << a.dir
                << " (a map is a folder with a manifest.json, written by `pepper_app teach` or "
                   "`pepper_app map build`)\n";
    }
    return 0;
  } catch (const std::exception& e) {
    return report_exception(e);
  }
}

int run_map_show(const MapShowArgs& a) {
  try {
    const core::memory::VisualMemory map = core::memory::load_map(a.map);
    const auto warnings = check_tour(core::memory::summarize(map), tour_check_options());
    std::optional<TaughtPath> taught;
    try {
      taught = load_taught_path(a.map);
    } catch (const std::exception& e) {  // the page without a path is still worth having
      std::cerr << "pepper_app: warning: " << e.what() << "\n";
    }
    const std::string name = fs::absolute(a.map).lexically_normal().filename().string();
    report::map_page(name.empty() ? a.map : name, map, warnings, taught).write(a.out);
    std::cout << a.map << ": " << map.key_images.size() << " key images, " << warnings.size()
              << " warning" << (warnings.size() == 1 ? "" : "s") << "\n";
    for (const auto& w : warnings) std::cout << "  warning: " << w.text << "\n";
    std::cout << "page written to " << a.out << "\n";
    return 0;
  } catch (const std::exception& e) {
    return report_exception(e);
  }
}

int run_map_trim(const MapTrimArgs& a) {
  try {
    // Refuse bad arguments before loading anything (the manifest gives the range).
    const core::memory::MapSummary info = core::memory::read_map_info(a.map);
    if (info.mode == core::NavMode::kCeiling) {
      // The cut would leave mosaic.json and ceiling_tour.json behind (ceiling_map.hpp).
      return usage_error("trim", a.map +
                                     " is a ceiling-mode map: map trim cuts forward maps "
                                     "only (the relay chain and the mosaic would not follow "
                                     "the cut); teach the part you want with --mode ceiling");
    }
    const int to = a.to < 0 ? info.final_index : a.to;
    try {
      check_trim_range(a.from, to, info.final_index);
    } catch (const std::invalid_argument& e) {
      return usage_error("trim", a.map + ": " + e.what());
    }
    std::error_code ec;
    const bool same = fs::equivalent(a.map, a.out, ec);
    if (same && !a.overwrite) {
      return usage_error("trim", "--out " + a.out +
                                     " is the input map: give another --out, or add "
                                     "--overwrite to replace the input map");
    }
    const bool out_taken = fs::exists(a.out) && !(fs::is_directory(a.out) && fs::is_empty(a.out));
    if (out_taken && !a.overwrite) {
      return usage_error("trim", "--out " + a.out +
                                     " already exists: give another --out, or add --overwrite "
                                     "to replace it");
    }
    // --overwrite replaces a map, never a folder of something else (save_map removes it all).
    if (out_taken && !fs::exists(fs::path(a.out) / "manifest.json")) {
      return usage_error("trim", "--out " + a.out +
                                     " holds files that are not a map: give another --out "
                                     "(--overwrite replaces maps only)");
    }
    const core::memory::VisualMemory map = core::memory::load_map(a.map);
    std::optional<TaughtPath> taught;
    try {
      taught = load_taught_path(a.map);
    } catch (const std::exception& e) {  // the map is what matters; its top-view path is extra
      std::cerr << "pepper_app: warning: " << e.what() << ": the trimmed map has no taught path\n";
    }
    const core::memory::VisualMemory trimmed = trim_map(map, a.from, to);
    core::memory::save_map(trimmed, a.out);  // atomic: a failure leaves the old folder
    if (taught) save_taught_path(a.out, trim_taught_path(*taught, map, a.from, to));
    std::cout << core::memory::summarize(trimmed).to_text();
    std::cout << "key images " << a.from << ".." << to << " of " << a.map << " written to "
              << a.out << "\n";
    return 0;
  } catch (const std::exception& e) {
    return report_exception(e);
  }
}

/// `map build` of a ceiling teach's recording (issue 24): the live teach's CeilingTeacher over
/// the recorded frames, saved as the live teach saves it (save_ceiling_map: one atomic rename).
int run_ceiling_map_build(const MapBuildArgs& a, const AppConfig& config, const Recording& rec) {
  if (a.every_frame_key || !a.steps_csv.empty()) {
    const std::string option = a.every_frame_key ? "--every-frame-key" : "--steps-csv";
    return usage_error("build", option +
                                    " is for forward maps: a ceiling map's key images are the "
                                    "relay images the mosaic chooses; drop it");
  }
  CeilingBuildInputs inputs;
  inputs.ceiling_height_m = config.robot.ceiling_height_m;
  inputs.head_pitch_rad = config.robot.ceiling_head_pitch_rad;
  CeilingCameraSetup setup;
  try {
    setup = ceiling_setup_for_build(rec, recording_frame_camera(rec), inputs);
  } catch (const std::invalid_argument& e) {
    return usage_error("build", e.what());
  }
  const bool recorded = rec.setup && rec.setup->ceiling;
  const bool as_recorded = recorded && setup.ceiling_height_m == rec.setup->ceiling->height_m;
  std::cerr << "map build: ceiling mode, head at " << setup.camera.head_pitch_rad
            << " rad, ceiling " << setup.ceiling_height_m << " m above the floor ("
            << setup.camera.ceiling_above_cam_m << " m above the camera; "
            << (as_recorded ? "as recorded"
                : recorded  ? "the recorded camera under robot.ceiling_height_m"
                            : "Pepper's head geometry, the recording does not give its camera")
            << ")\n";
  ProgressLine progress("ceiling mosaic");
  const CeilingBuild built = build_ceiling_map_from_recording(
      rec, setup, config.teach_options().extractor, CeilingTeachOptions{},
      config_to_json(config).dump(),
      [&](std::size_t done, std::size_t total) { progress.update(done, total); });
  progress.finish();
  const CeilingMap& cm = built.map;
  save_ceiling_map(cm, a.map);  // atomic: the map, the mosaic and the tour replace it together
  std::cout << core::memory::summarize(cm.map).to_text()
            << ceiling_summary_text({cm.mosaic, cm.tour});
  if (built.relocalisations > 0 || built.loops_closed > 0) {
    std::cout << "re-localised " << built.relocalisations << " time(s), loops closed "
              << built.loops_closed << "\n";
  }
  for (const auto& w : ceiling_warnings(cm.tour)) std::cout << "warning: " << w << "\n";
  if (cm.tour.height_check) {
    if (const auto w = ceiling_height_warning(*cm.tour.height_check)) {
      std::cout << "warning: " << *w << "\n";
    }
  }
  std::cout << "ceiling map written to " << a.map << "\n";
  return 0;
}

int run_map_build(const MapBuildArgs& a) {
  try {
    const AppConfig config = load_app_config(a.config);
    const auto camera = load_camera_option(a.camera);
    const std::optional<core::NavMode> requested =
        a.mode.empty() ? std::nullopt : std::optional<core::NavMode>(parse_mode(a.mode));
    const Recording rec = read_recording(a.recording, camera, a.fps);
    for (const auto& w : rec.warnings) std::cerr << "pepper_app: warning: " << w << "\n";
    std::cerr << "map build: " << rec.frames.size() << " frames from " << a.recording << " ("
              << rec.source << ")\n";
    core::NavMode mode = core::NavMode::kForward;
    try {
      mode = map_build_mode(rec, requested);
    } catch (const std::invalid_argument& e) {
      return usage_error("build", e.what());
    }
    if (mode == core::NavMode::kCeiling) return run_ceiling_map_build(a, config, rec);
    if (!rec.setup && !requested && rec.version > 0) {
      std::cerr << "map build: " << a.recording << " does not say which mode it was taught in "
                << "(recording format " << rec.version << ", or a replay's): built as a "
                << "forward map; for a ceiling teach's recording give --mode ceiling --set "
                << "robot.ceiling_height_m=H\n";
    }
    ProgressLine progress(a.every_frame_key ? "features" : "key-image selection");
    std::vector<core::mapping::TeachStep> steps;
    const core::memory::VisualMemory map = build_map_from_recording(
        rec, config.teach_options(), a.every_frame_key, config_to_json(config).dump(),
        [&](std::size_t done, std::size_t total) { progress.update(done, total); }, &steps);
    progress.finish();
    if (!a.steps_csv.empty()) {
      write_teach_steps_csv(steps, a.steps_csv);
      std::cerr << "per-frame teach counts written to " << a.steps_csv << "\n";
    }
    core::memory::save_map(map, a.map);
    std::cout << core::memory::summarize(map).to_text();
    std::cout << "map written to " << a.map << "\n";
    return 0;
  } catch (const std::exception& e) {
    return report_exception(e);
  }
}

}  // namespace

void register_map_command(CLI::App& app) {
  auto* map = app.add_subcommand(
      "map", "Inspect, list, show, trim and build maps (visual memories of a tour).");
  map->require_subcommand(1);

  auto info_args = std::make_shared<MapInfoArgs>();
  auto* info = map->add_subcommand(
      "info",
      "Summarise a map: key images, features, duration, distance; warnings where the tour is weak\n"
      "(as `map show`).");
  info->add_option("dir", info_args->dir, "Map folder")->required();
  info->add_flag("--full", info_args->full, "Load every file and verify checksums too");
  info->footer("Example:\n  pepper_app map info maps/lab_tour --full");
  info->callback([info_args] { exit_code() = run_map_info(*info_args); });

  auto list_args = std::make_shared<MapListArgs>();
  auto* list = map->add_subcommand(
      "list", "List the maps under a folder: one line per map with its key images, taught "
              "length, date saved and size on disk.");
  list->add_option("dir", list_args->dir, "Folder to search (and its subfolders)")
      ->required()
      ->check(CLI::ExistingDirectory);
  list->footer("Example:\n  pepper_app map list maps");
  list->callback([list_args] { exit_code() = run_map_list(*list_args); });

  auto show_args = std::make_shared<MapShowArgs>();
  auto* show = map->add_subcommand(
      "show",
      "Write an HTML page about a map: its key images as thumbnails with their line and point\n"
      "counts, the taught path when known, and warnings where the tour is weak (key images with\n"
      "few features, long gaps between key images). The warnings are printed too.");
  show->add_option("map", show_args->map, "Map folder")->required();
  show->add_option("--out", show_args->out, "HTML file to write")->required();
  show->footer("Example:\n  pepper_app map show maps/lab --out lab.html");
  show->callback([show_args] { exit_code() = run_map_show(*show_args); });

  auto trim_args = std::make_shared<MapTrimArgs>();
  auto* trim = map->add_subcommand(
      "trim",
      "Keep key images K..L of a map (tour indices, as `map info` numbers them) as a new map:\n"
      "cut a bad start or end off a teach without teaching again. The input map is never\n"
      "changed unless --out names it and --overwrite is given.");
  trim->add_option("map", trim_args->map, "Map folder to read")->required();
  trim->add_option("--from", trim_args->from, "First key image kept (default 0)");
  trim->add_option("--to", trim_args->to, "Last key image kept (default: the final one)");
  trim->add_option("--out", trim_args->out, "Map folder to write (saved atomically)")->required();
  trim->add_flag("--overwrite", trim_args->overwrite,
                 "Replace an existing map in --out (even the input map; a folder that is not a "
                 "map is never replaced)");
  trim->footer(
      "Examples:\n"
      "  pepper_app map trim maps/lab --to 12 --out maps/lab_short      # drop the key images after 12\n"
      "  pepper_app map trim maps/lab --from 2 --out maps/lab_from2     # drop the first two");
  trim->callback([trim_args] { exit_code() = run_map_trim(*trim_args); });

  auto build_args = std::make_shared<MapBuildArgs>();
  auto* build = map->add_subcommand(
      "build",
      "Build a map from a recorded teach session (or a plain folder of images in name order).\n"
      "Key images are chosen by the teach rule nL + nP < epsilon, as during a live teach. A\n"
      "ceiling teach's recording is rebuilt in ceiling mode (mosaic, relay images, ceiling tour,\n"
      "height check) as the live teach built it; recordings made before they recorded their\n"
      "mode need --mode ceiling and the ceiling's height (--set robot.ceiling_height_m=H).");
  build->add_option("--recording", build_args->recording,
                    "Recording folder (ours, or a plain image folder with --camera)")
      ->required();
  build->add_option("--map", build_args->map, "Output map folder (replaced atomically)")
      ->required();
  build->add_option("--camera", build_args->camera,
                    "Camera intrinsics: ViSP XML (.xml) or plain YAML/JSON; required for a plain "
                    "image folder, overrides a recording's own");
  build->add_flag("--every-frame-key", build_args->every_frame_key,
                  "Take every image as a key image (maps made elsewhere)");
  build->add_option("--fps", build_args->fps, "Nominal frame rate of a plain image folder")
      ->check(CLI::PositiveNumber);
  build->add_option("--mode", build_args->mode,
                    "forward or ceiling (default: the mode the recording was taught in; forward "
                    "when it does not say); the other mode than the recording's is refused")
      ->check(CLI::IsMember({"forward", "ceiling"}));
  add_config_options(build, build_args->config.file, build_args->config.preset,
                     build_args->config.sets, "key_images.epsilon=60");
  build->add_option("--steps-csv", build_args->steps_csv,
                    "Write the per-frame counts of the teach rule (nL, nP, threshold, key images) "
                    "as CSV");
  build->footer(
      "Examples:\n"
      "  pepper_app map build --recording rec/lab_tour --map maps/lab_tour\n"
      "  pepper_app map build --recording rec/lab_tour --map maps/eps60 --set key_images.epsilon=60\n"
      "  pepper_app map build --recording ../shared/data/pepper_qut_tmap/Edge_01 \\\n"
      "      --camera cameras/pepper_top_qvga.yaml --every-frame-key --map maps/edge01\n"
      "  pepper_app map build --recording rec/hall_ceiling --map maps/hall_ceiling   # its mode\n"
      "  pepper_app map build --recording rec/hall_ceiling --map maps/hall_2.6 \\\n"
      "      --set robot.ceiling_height_m=2.6        # rebuilt under a corrected ceiling height\n"
      "  pepper_app map build --recording rec/old_ceiling --map maps/old_ceiling \\\n"
      "      --mode ceiling --set robot.ceiling_height_m=2.7   # recorded before the mode was");
  build->callback([build_args] { exit_code() = run_map_build(*build_args); });
}

}  // namespace pepper::app
