#pragma once
// Robot-free jobs over recordings: build a map from a recorded teach session (`map build`) and
// run the navigator over recorded frames to see what it would have commanded (`replay-log`).
// Frames are streamed from disk one at a time, so long recordings need little memory (a ceiling
// rebuild keeps every grey frame until the end, as the live ceiling teach does).

#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/mapping/teacher.hpp"
#include "core/memory/visual_memory.hpp"
#include "core/nav_mode.hpp"
#include "core/navigator/navigator.hpp"
#include "session/ceiling_teach.hpp"
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

/// The mode `map build` builds `recording` in (issue 24): `requested` (--mode) when given, else
/// the mode the recording says it was taught in, else forward (recordings that do not say:
/// format version 1, replay's, plain image folders). Throws std::invalid_argument naming both
/// modes when --mode contradicts the recording's: the head looked up at the ceiling in one and
/// ahead in the other, so the frames cannot make a map of the other mode.
core::NavMode map_build_mode(const Recording& recording, std::optional<core::NavMode> requested);

/// What the operator gives `map build --mode ceiling` (map build's configuration).
struct CeilingBuildInputs {
  /// robot.ceiling_height_m (m): > 0 replaces the recorded ceiling height (a rebuild under a
  /// corrected height, the camera's height on the base staying the recorded one); needed for a
  /// recording that does not record its ceiling. 0: not given.
  double ceiling_height_m = 0.0;
  /// robot.ceiling_head_pitch_rad: the head pitch of a recording that records neither it nor
  /// a configuration holding it.
  double head_pitch_rad = -0.7;
};

/// The camera geometry to rebuild `recording` in ceiling mode with (`camera`: the intrinsics
/// the frames are read with). A teach's recording of format version 2 gives it as the live teach
/// ran (a mock robot's mount and world included); one that does not record it (version 1, a
/// replay's, a plain image folder) takes a real Pepper's head geometry at the head pitch of the
/// recorded configuration (else `inputs.head_pitch_rad`) under `inputs.ceiling_height_m` (else
/// the recorded configuration's robot.ceiling_height_m). Throws std::invalid_argument naming
/// what is missing (the ceiling's height: --set robot.ceiling_height_m=H) or wrong.
CeilingCameraSetup ceiling_setup_for_build(const Recording& recording,
                                           const core::CameraIntrinsics& camera,
                                           const CeilingBuildInputs& inputs);

/// A ceiling map rebuilt from a recording, with what the live teach reported while teaching.
struct CeilingBuild {
  CeilingMap map;
  int relocalisations = 0;  ///< frames the mosaic builder re-localised after a loss
  int loops_closed = 0;
};

/// The live ceiling teach over the recorded frames: the same CeilingTeacher (ceiling_teach.hpp)
/// fed every frame with the distance the teach measured (drive_odometer.hpp over the recorded
/// odometry and commands), so a teach's recording gives back its map: the same mosaic, relay
/// images, tour and height check (bit for bit: the pipeline is deterministic). `setup`'s
/// intrinsics must be the frames' (ceiling_setup_for_build). Frames whose size differs from the
/// first frame's are an error naming the file; finish()'s errors (fewer than 2 frames, no
/// landmark) are passed on.
CeilingBuild build_ceiling_map_from_recording(
    const Recording& recording, const CeilingCameraSetup& setup,
    const core::features::FeatureExtractorOptions& extractor, const CeilingTeachOptions& options,
    const std::string& parameters_json, const ProgressFn& progress = {});

/// The intrinsics the frames of `recording` are read with: its camera scaled to the first
/// frame's size when that differs.
core::CameraIntrinsics recording_frame_camera(const Recording& recording);

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
