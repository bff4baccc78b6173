#pragma once
// Robot-free jobs over recordings: build a map from a recorded teach session (`map build`) and
// run the navigator over recorded frames to see what it would have commanded (`replay-log`).
// Frames are streamed from disk one at a time, so long recordings need little memory.

#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/mapping/teacher.hpp"
#include "core/memory/visual_memory.hpp"
#include "core/navigator/navigator.hpp"
#include "session/recording.hpp"

namespace pepper::app {

/// Called every few frames with (frames done, frames total) for progress display.
using ProgressFn = std::function<void(std::size_t done, std::size_t total)>;

/// Key images by the teach rule (core/mapping) over the recording's frames, or every frame a key
/// image when `every_frame_key` (maps made elsewhere). Frames whose size differs from the first
/// frame's are an error naming the file. The camera is scaled to the frames' size when needed.
/// `steps`, when given, receives the teach rule's per-frame counts (not with every_frame_key).
core::memory::VisualMemory build_map_from_recording(
    const Recording& recording, const core::mapping::TeachOptions& options, bool every_frame_key,
    const std::string& parameters_json, const ProgressFn& progress = {},
    std::vector<core::mapping::TeachStep>* steps = nullptr);

/// The teach steps as CSV: frame,n_lines_3v,n_points_2v,count,reference,new_key,key_images.
void write_teach_steps_csv(const std::vector<core::mapping::TeachStep>& steps,
                           const std::string& path);

struct ReplayLogFrame {
  int64_t frame_index = 0;
  std::optional<core::OdometryPose> odom;  ///< the recorded odometry the navigator was given
  core::navigator::Command command;
  core::navigator::Telemetry telemetry;
};

struct ReplayLogResult {
  std::vector<ReplayLogFrame> frames;
  bool reached_end = false;        ///< the navigator reported the tour complete
  int max_key_image_reached = -1;  ///< largest IN seen
  int key_image_count = 0;
  /// The recording's frames were this many times the map's size in each direction and were
  /// scaled down to it (1: used as recorded).
  int downscale = 1;
  nlohmann::json to_json() const;  ///< {"summary": {...}, "frames": [...]}
};

/// Runs a Navigator over the recording's frames (no robot). Frames an integer number of times
/// the map's size in both directions (a VGA recording, a QVGA map) are scaled down to it by
/// pixel-area averaging, as the camera's own lower resolution delivers them; any other size is
/// refused. Throws RecordingError / MapError / std::invalid_argument with a clear message.
ReplayLogResult replay_log(const Recording& recording, core::memory::VisualMemory map,
                           const core::navigator::NavigatorOptions& options,
                           const ProgressFn& progress = {});

}  // namespace pepper::app
