// `pepper_app replay-log --recording DIR --map DIR [--json OUT]`: what the navigator would have
// commanded on recorded frames, without a robot.
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>

#include "commands/cli_util.hpp"
#include "commands/commands.hpp"
#include "config/app_config.hpp"
#include "offline/offline_jobs.hpp"
#include "session/session_cli.hpp"

namespace pepper::app {
namespace {

struct ReplayLogArgs {
  std::string recording;
  std::string map;
  std::string camera;
  std::string json_out;
  double fps = 15.0;
  bool quiet = false;
  ConfigSources config;
};

int run_replay_log(const ReplayLogArgs& a) {
  try {
    const AppConfig config = load_app_config(a.config);
    core::memory::VisualMemory map = core::memory::load_map(a.map);
    // The frames come from the recording at the map's size: a camera size asked for explicitly
    // would be ignored, so it is refused as in replay.
    refuse_camera_size_other_than_map(a.config.file, a.config.sets, config, map.camera);
    const auto camera = load_camera_option(a.camera);
    const Recording rec = read_recording(a.recording, camera ? camera : map.camera, a.fps);
    for (const auto& w : rec.warnings) std::cerr << "pepper_app: warning: " << w << "\n";
    ProgressLine progress("replay-log");
    const ReplayLogResult result =
        replay_log(rec, std::move(map), config.navigator_options(),
                   [&](std::size_t done, std::size_t total) { progress.update(done, total); });
    progress.finish();
    if (result.downscale > 1) {
      std::cerr << "replay-log: the recording's frames are " << result.downscale
                << " times the map's size (" << result.frames.size()
                << " frames): each was scaled down to the map's by pixel-area averaging\n";
    }
    if (!a.quiet) {
      std::cout << "frame  state          IP  IN INN  v_m_s  omega_rad_s  stop_reason\n";
      for (const auto& f : result.frames) {
        const auto& t = f.telemetry;
        std::cout << std::setw(5) << f.frame_index << "  " << std::left << std::setw(14)
                  << core::navigator::to_string(t.state) << std::right << std::setw(3) << t.ip
                  << std::setw(4) << t.in << std::setw(4) << t.inn << std::fixed
                  << std::setprecision(3) << std::setw(7) << f.command.v_m_s << std::setw(13)
                  << f.command.omega_rad_s << "  "
                  << (f.command.stop ? core::navigator::to_string(f.command.reason) : "-") << "\n";
      }
    }
    std::cout << "summary: " << result.frames.size() << " frames, furthest key image "
              << result.max_key_image_reached << " of " << result.key_image_count - 1 << ", "
              << (result.reached_end ? "end of tour reached" : "end of tour NOT reached") << "\n";
    if (!a.json_out.empty()) {
      std::ofstream out(a.json_out);
      out << result.to_json().dump(1) << "\n";
      if (!out) {
        return report_error(a.json_out +
                            ": cannot write: check that its folder exists and is writable");
      }
      std::cout << "per-frame log written to " << a.json_out << "\n";
    }
    return 0;
  } catch (const std::exception& e) {
    return report_exception(e);
  }
}

}  // namespace

void register_replay_log_command(CLI::App& app) {
  auto args = std::make_shared<ReplayLogArgs>();
  auto* cmd = app.add_subcommand(
      "replay-log",
      "Run the navigator over recorded frames and report what it would have commanded: per frame\n"
      "the key images in use (IP/IN/INN), the command and any stop reason; in summary whether the\n"
      "end of the tour was reached. No robot is involved.");
  cmd->add_option("--recording", args->recording, "Recording folder or plain image folder")
      ->required();
  cmd->add_option("--map", args->map, "Map folder")->required();
  cmd->add_option("--camera", args->camera,
                  "Intrinsics for a plain image folder (default: the map's camera)");
  cmd->add_option("--json", args->json_out, "Write the per-frame log and summary as JSON here");
  cmd->add_option("--fps", args->fps, "Nominal frame rate of a plain image folder")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("-q,--quiet", args->quiet, "Print the summary only");
  add_config_options(cmd, args->config.file, args->config.preset, args->config.sets,
                     "navigator.features=lines");
  cmd->footer("Example:\n  pepper_app replay-log --recording rec/replay1 --map maps/lab_tour "
              "--json replay1.json");
  cmd->callback([args] { exit_code() = run_replay_log(*args); });
}

}  // namespace pepper::app
