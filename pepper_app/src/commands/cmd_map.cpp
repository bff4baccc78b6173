// `pepper_app map info DIR` and `pepper_app map build --recording DIR --map DIR`.
#include <iostream>
#include <memory>

#include "commands/cli_util.hpp"
#include "commands/commands.hpp"
#include "config/app_config.hpp"
#include "core/memory/visual_memory.hpp"
#include "offline/offline_jobs.hpp"

namespace pepper::app {
namespace {

struct MapInfoArgs {
  std::string dir;
  bool full = false;
};

struct MapBuildArgs {
  std::string recording;
  std::string map;
  std::string camera;
  bool every_frame_key = false;
  double fps = 15.0;
  ConfigSources config;
  std::string steps_csv;
};

int run_map_info(const MapInfoArgs& a) {
  try {
    // --full loads and checks every file (checksums); default reads the manifest only.
    const core::memory::MapSummary summary =
        a.full ? core::memory::summarize(core::memory::load_map(a.dir))
               : core::memory::read_map_info(a.dir);
    std::cout << summary.to_text();
    if (a.full) std::cout << "all files present and checksums verified\n";
    return 0;
  } catch (const std::exception& e) {
    return report_exception(e);
  }
}

int run_map_build(const MapBuildArgs& a) {
  try {
    const AppConfig config = load_app_config(a.config);
    const auto camera = load_camera_option(a.camera);
    const Recording rec = read_recording(a.recording, camera, a.fps);
    for (const auto& w : rec.warnings) std::cerr << "pepper_app: warning: " << w << "\n";
    std::cerr << "map build: " << rec.frames.size() << " frames from " << a.recording << " ("
              << rec.source << ")\n";
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
  auto* map = app.add_subcommand("map", "Inspect and build maps (visual memories of a tour).");
  map->require_subcommand(1);

  auto info_args = std::make_shared<MapInfoArgs>();
  auto* info = map->add_subcommand("info", "Summarise a map: key images, features, duration.");
  info->add_option("dir", info_args->dir, "Map folder")->required();
  info->add_flag("--full", info_args->full, "Load every file and verify checksums too");
  info->footer("Example:\n  pepper_app map info maps/lab_tour --full");
  info->callback([info_args] { exit_code() = run_map_info(*info_args); });

  auto build_args = std::make_shared<MapBuildArgs>();
  auto* build = map->add_subcommand(
      "build",
      "Build a map from a recorded teach session (or a plain folder of images in name order).\n"
      "Key images are chosen by the teach rule nL + nP < epsilon, as during a live teach.");
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
      "      --camera cameras/pepper_top_qvga.yaml --every-frame-key --map maps/edge01");
  build->callback([build_args] { exit_code() = run_map_build(*build_args); });
}

}  // namespace pepper::app
