#pragma once
// The replay session loop (METHOD.md "Replay"; issue 6): connect, lock the head, start the camera,
// check the map's intrinsics against the camera's, then per frame Navigator::step -> bridge.move,
// or bridge.stop with the reason. Telemetry is written per frame as JSON lines (optional), the
// frames optionally recorded (RecordingWriter).
//
// Stops whenever unsure: the navigator says stop (not localised, features lost: it keeps
// stepping; tour complete: the session ends), no frame for frame_timeout_ms (ends, "frame_timeout"),
// an exception from the core or the bridge ("error"), Ctrl-C ("interrupted"), the UI's STOP
// ("ui_stop"), a lost connection ("connection_lost"), the frame cap ("max_frames"), stopped too long
// after driving ("lost", give_up_lost_s), never localised ("not_localised",
// give_up_not_localised_s), a collision of the simulated robot ("collision"), a head lock the
// robot does not let us hold ("head_lock_lost", RobotBridge::supervise), or a ReplayMonitor's
// end. Every way out sends bridge.stop() first. Move failures the robot shows (a velocity it does
// not execute) are reported as "robot_warning" events and in the telemetry's "robot" key.
// This loop is the only replay loop of the product: `replay`, `demo` and `evaluate` run it (the
// evaluation adds its ground truth and metrics through a ReplayMonitor).
// On the mock robot the ground-truth base positions are collected (top view, evaluation). The UI's
// live image carries the navigator's matches with IN (Telemetry::overlay).
// Threads: none of its own. Errors end in ReplayResult (never thrown) after the stop.

#include <cstdint>
#include <exception>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/memory/visual_memory.hpp"
#include "core/navigator/navigator.hpp"
#include "naoqi_bridge/robot_bridge.hpp"
#include "session/robot_connection.hpp"
#include "session/session_link.hpp"

namespace pepper::app {

struct ReplaySample;

/// Why a monitor ends the replay (outcome: a short name, detail: one sentence).
struct ReplayEnd {
  std::string outcome;
  std::string detail;
};

/// Sees every iteration of the replay loop and may end it. The evaluation uses one to record
/// ground truth and to end runs that left the taught path (diverged, overshot, time limit); the
/// loop itself, with every decision and stop path, is the one users run.
class ReplayMonitor {
 public:
  virtual ~ReplayMonitor() = default;
  /// Called after each frame request, once the command (if any) has been sent. `step` and
  /// `sample` are null when no frame arrived (dropped or late). Returning an end stops the base
  /// and ends the session with that outcome.
  virtual std::optional<ReplayEnd> after_iteration(const core::navigator::StepResult* step,
                                                   const ReplaySample* sample) = 0;
};

struct ReplaySessionOptions {
  naoqi_bridge::CameraRequest camera;
  /// The calibration file's camera (`replay --camera`), scaled to the started camera's size, in
  /// place of the intrinsics the bridge reports; it must match the map's camera, projection
  /// model included. Unset: the bridge's pinhole intrinsics are checked against the map's, and
  /// the navigator normalises with the map's camera.
  std::optional<core::CameraIntrinsics> camera_model;
  naoqi_bridge::HeadLockRequest head;
  core::navigator::NavigatorOptions navigator;
  int frame_timeout_ms = 1000;       ///< no frame this long: stop and end ("frame_timeout")
  int64_t max_frames = 0;            ///< > 0: stop and end after this many frames
  std::filesystem::path telemetry_jsonl;  ///< non-empty: one JSON line per frame
  /// Ceiling mode: the last step's ceiling telemetry (CeilingReplay::telemetry_json), added to
  /// each telemetry_jsonl line as "ceiling"; empty in forward mode.
  std::function<nlohmann::json()> ceiling_telemetry;
  std::filesystem::path record_dir;  ///< non-empty: record the frames here
  double pace_hz = 0.0;              ///< > 0: at most this many frames per second
  bool wait_for_start = false;       ///< wait for the UI's start_replay before moving
  /// > 0: end ("lost") after the navigator has commanded a stop this long (frame time) once it
  /// had been driving, whatever the stop reason (other than the end of the tour); 0 = keep
  /// trying to relocalise until stopped by the operator.
  double give_up_lost_s = 0.0;
  /// > 0: end ("not_localised") when the first localisation has not succeeded after this long
  /// (frame time since the first frame); 0 = wait until stopped by the operator.
  double give_up_not_localised_s = 0.0;
  /// At the end of the tour the robot "arrived" when its estimated offset from the final key
  /// image's taught pose is within these (m, rad); otherwise it reached the last key image "not
  /// aligned" (docs/user_guide.md, "How a replay ends"). > 0.
  double arrival_tolerance_m = 0.15;
  double arrival_tolerance_rad = 0.1;
  /// Not owned; may be null. See ReplayMonitor.
  ReplayMonitor* monitor = nullptr;
  std::string config_json = "{}";
  /// Mock only, shown in the UI's top view: the taught ground-truth path and key-image positions
  /// (world frame), sent once as the state key "taught_path".
  std::vector<Eigen::Vector2d> taught_path_m;
  std::vector<Eigen::Vector2d> taught_keys_m;
  std::vector<std::string> validate() const;
};

/// One replayed frame (for plots and the report).
struct ReplaySample {
  double t_s = 0.0;               ///< frame time since the first frame
  double step_ms = 0.0;           ///< wall-clock time of the navigator step
  double v_m_s = 0.0, omega_rad_s = 0.0;
  bool stop = true;
  int in = -1;
  int n_lines = 0, n_points = 0;
  bool dead_reckoning = false;  ///< driven on odometry alone (vision blind) on this frame
  bool has_pose = false;
  double x_m = 0.0, y_m = 0.0, yaw_rad = 0.0;  ///< mock ground truth
};

/// How the robot stands at the end of the tour, from the navigator's own estimate
/// (Telemetry::arrival_*): no ground truth is needed, so a real Pepper reports it too.
struct Arrival {
  std::string verdict = "unknown";  ///< arrived, not_aligned, unknown (no estimate)
  std::string source = "none";      ///< vision (a VNHV fix on the final segment), odometry, none
  double along_m = 0.0;    ///< > 0: past the final key image
  double lateral_m = 0.0;  ///< > 0: left of it
  double heading_rad = 0.0;
  double offset_m = 0.0;   ///< hypot(along, lateral)
};

/// The verdict for an estimate and the tolerances (pure; tested).
Arrival judge_arrival(const core::navigator::Telemetry& final_frame, double tolerance_m,
                      double tolerance_rad);

struct ReplayResult {
  std::string outcome;  ///< tour_complete, interrupted, ui_stop, frame_timeout, connection_lost,
                        ///< error, max_frames, lost, not_localised, overdue, collision (mock),
                        ///< head_lock_lost, relay_break (ceiling mode),
                        ///< or a ReplayMonitor's outcome
  std::string detail;   ///< one sentence on why it ended
  std::string error;
  std::exception_ptr error_exception;  ///< the exception behind `error` (its type gives advice)
  int64_t frames = 0;
  int key_image_count = 0;
  int max_key_reached = -1;
  bool tour_complete = false;
  Arrival arrival;  ///< meaningful when tour_complete
  std::vector<ReplaySample> samples;
};

/// Replaces Navigator::step (tests inject faults); empty = a Navigator over the map.
using StepFunction = std::function<core::navigator::StepResult(const core::Frame&)>;

/// Runs a replay of `map` on `robot` (opened, not connected). Throws std::invalid_argument for
/// invalid options before anything moves; everything else ends in the result after a stop.
ReplayResult run_replay_session(RobotConnection& robot, core::memory::VisualMemory map,
                                const ReplaySessionOptions& options, SessionLink& link,
                                StepFunction step_override = {});

}  // namespace pepper::app
