#pragma once
// The teach session loop (METHOD.md "Teach"; issue 6): connect, lock the head (read-back
// reported), start the camera, then per frame: record it (RecordingWriter, crash-safe), feed
// core::mapping::Teacher online, and drive the base from the operator (teach UI drive intents
// with a dead-man: a drive not refreshed within drive_timeout_s stops the base) or, on the mock
// robot, from a scripted TeachDriver along the world's waypoints. The tour ends on the UI's
// "finish" intent, when the scripted drive is done, or at max_distance_m / max_frames; the map
// is then saved atomically (core::memory::save_map) and summarised, with a warning for each key
// image with few features (lines + points < min_key_features). On the mock robot the ground-truth
// path goes next to it (taught_path.hpp). The UI's live image carries the frame's detected lines
// and corners while recording, and live warnings (teach_feedback.hpp) when the view is too poor
// or the turn too fast for the replay.
//
// Ceiling mode (mode = kCeiling, issue 24): the head is locked at the ceiling pitch (the caller's
// `head`), and where the forward teacher runs, a CeilingTeacher (ceiling_teach.hpp) builds the
// mosaic from the canonical ceiling view of every taught frame; at the end the relay images are
// chosen and the map (mode ceiling, key images = relay images), the mosaic and the ceiling tour
// are saved (ceiling_map.hpp). The ceiling's height is the simulated world's on a mock robot and
// ceiling_height_m on a real one. The forward-view live warnings and overlay are not shown in ceiling mode.
//
// Safety: every way out (finish, Ctrl-C flag, exception, lost connection, stalled frames) sends
// bridge.stop() FIRST; then the recording is kept (it can become a map with `map build`); then
// the map is saved if the teacher saw at least 2 frames. Stalled frames (none for
// frame_timeout_ms) stop the base; teach then keeps waiting (the operator may resume).
// Threads: none of its own. Errors are reported in TeachResult (never thrown) after the stop.

#include <Eigen/Core>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/mapping/teacher.hpp"
#include "core/nav_mode.hpp"
#include "naoqi_bridge/robot_bridge.hpp"
#include "session/ceiling_teach.hpp"
#include "session/robot_connection.hpp"
#include "session/session_link.hpp"
#include "session/teach_feedback.hpp"

namespace pepper::app {

struct TeachSessionOptions {
  std::filesystem::path map_dir;        ///< required; written atomically at the end
  /// Where the frames are recorded (must not exist or be empty); empty: no recording (the
  /// evaluation, which re-teaches from the world file). The CLI always records.
  std::filesystem::path recording_dir;
  naoqi_bridge::CameraRequest camera;
  /// The camera model the features are normalised with, instead of the one the bridge reports
  /// (scaled to the started camera's size); recorded in the map and the recording. The
  /// evaluation's `--lens-correction off` gives the pinhole model of a lens the mock renders.
  std::optional<core::CameraIntrinsics> camera_model;
  naoqi_bridge::HeadLockRequest head;
  core::mapping::TeachOptions teach;
  core::NavMode mode = core::NavMode::kForward;  ///< kCeiling: mock: robots only (see above)
  CeilingTeachOptions ceiling;                   ///< ceiling mode's mosaic and relay images
  /// Ceiling mode on a real robot: the ceiling's height above the floor (m; robot.
  /// ceiling_height_m). Mock robots take their world's.
  double ceiling_height_m = 0.0;
  std::string config_json = "{}";       ///< effective configuration, stored in map + recording
  bool scripted = false;                ///< drive with the mock world's TeachDriver (mock: only)
  double max_distance_m = 0.0;          ///< > 0: end the tour after this much driving
  int64_t max_frames = 0;               ///< > 0: end the tour after this many frames
  int frame_timeout_ms = 1000;          ///< no frame this long: stop the base
  double drive_timeout_s = 0.5;         ///< app-side dead-man for UI drive intents
  bool record_from_start = true;        ///< else wait for the UI's start_recording
  double pace_hz = 0.0;                 ///< > 0: at most this many loop iterations per second
  int min_key_features = 40;            ///< key images with fewer lines + points are "weak"
  /// Live warnings while recording (teach_feedback.hpp), sent to the UI as `teach_feedback` and
  /// to the events file; half_view_rad is replaced by the started camera's.
  TeachFeedbackLimits feedback;
  double max_v_m_s = 0.25;              ///< clamp for UI drive intents
  double max_omega_rad_s = 0.5;
  std::vector<std::string> validate() const;
};

struct TeachResult {
  std::string outcome;  ///< "finished", "interrupted", "failed"
  std::string error;    ///< what failed ("" otherwise)
  std::exception_ptr error_exception;  ///< the exception behind `error` (its type gives advice)
  int64_t frames_recorded = 0;  ///< frames taught (and written, when recording)
  int64_t frames_seen = 0;
  int key_images = 0;  ///< ceiling mode: the relay images
  /// Ceiling mode: the mosaic's landmarks, the frames without a pose, and the tour's warnings
  /// (also in `warnings`).
  int64_t ceiling_landmarks = 0;
  int64_t ceiling_unlocalised_frames = 0;
  bool map_saved = false;
  double distance_m = 0.0;  ///< driven (ground truth on the mock, else the map's measure)
  /// The saved map's driven length (last key image's travelled_m minus the first's, as
  /// `map info` prints it); what the UI's teach panel and "Map saved" box show. 0 when unsaved.
  double map_length_m = 0.0;
  /// Of the map's driven distance, the part the robot's odometry measured (the rest: commanded
  /// speeds, for frames without odometry).
  double distance_from_odometry_m = 0.0;
  int heading_key_images = 0;  ///< key images taken by the heading rule (turns)
  /// Recorded frames on which each live warning was shown (index: TeachWarningKind).
  int64_t feedback_frames[3] = {0, 0, 0};
  std::vector<std::string> warnings;
  std::vector<Eigen::Vector2d> path_m;  ///< mock only: ground-truth base positions per frame
  std::vector<Eigen::Vector2d> key_m;   ///< mock only: base positions of the key images
  std::vector<double> path_yaw_rad;     ///< mock only: ground-truth base yaw per frame
  std::vector<double> key_yaw_rad;      ///< mock only: base yaw of the key images
  bool ok() const { return outcome == "finished" && map_saved; }
};

/// Runs a teach session on `robot` (already opened, not connected). Never throws for robot or
/// core failures (they end in TeachResult::outcome "failed" after a stop); throws
/// std::invalid_argument for invalid options before anything moves.
TeachResult run_teach_session(RobotConnection& robot, const TeachSessionOptions& options,
                              SessionLink& link);

}  // namespace pepper::app
