#pragma once
// Closed-loop evaluation of teach and replay on the mock robot (docs/evaluation.md; issue 4):
// teach a world's tour with the product's teach session (run_teach_session, scripted drive on
// ground truth; the map is saved and loaded back), then replay it with the product's replay
// session (run_replay_session, the loop `replay` and `demo` run) from N perturbed starts,
// possibly with disturbances (disturbance.hpp), and measure how well the taught path is followed.
// The evaluation adds only the simulated robot's set-up, ground truth and metrics (a
// ReplayMonitor); whatever the replay decides (end of tour, lost, not localised, overdue) is what
// is scored.
//
// Definitions (the numbers are options, defaults documented below):
//  - taught path: the ground-truth base positions of the teach drive, one per frame;
//  - lateral deviation: signed distance of the replayed base position from the taught path
//    (metrics.hpp, > 0 left), followed along the path by a PathTracker;
//  - converged: samples after `converged_after_m` of travelled distance and after |lateral|
//    first fell below `converged_below_m`;
//  - success: the replay ended with the end of the tour, the robot stopped within
//    `end_tolerance_m` of the taught end position, and it never collided, never stayed stopped
//    after driving longer than `give_up_lost_s` and was localised within
//    `give_up_not_localised_s` (the replay session's own give-up rules, configuration `replay.*`),
//    never left the path by more than `divergence_m`, and finished before the time limit.
// Timings: the navigator step is timed with std::chrono::steady_clock (wall clock, evaluation
// only); everything else is simulated time. Deterministic in (world, options) except timings.
// Errors: invalid options throw std::invalid_argument naming the field; world, map and
// navigator exceptions propagate. Not thread-safe.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/ceiling/ceiling_navigator.hpp"
#include "core/control/ibvs_law.hpp"
#include "core/memory/visual_memory.hpp"
#include "core/mapping/key_image_selector.hpp"
#include "core/nav_mode.hpp"
#include "core/navigator/navigator.hpp"
#include "evaluation/disturbance.hpp"
#include "naoqi_bridge/mock_bridge.hpp"
#include "naoqi_bridge/robot_bridge.hpp"
#include "session/replay_session.hpp"
#include "sim/mock_robot.hpp"
#include "sim/world.hpp"

namespace pepper::app::evaluation {

struct EvaluationOptions {
  int starts = 10;                  ///< replay runs, >= 1
  /// Replay only these of the `starts` runs (1-based, same starts as in the full evaluation);
  /// empty: all. For re-running one failed start with --trace.
  std::vector<int> only_runs;
  uint64_t seed = 1;                ///< start perturbations (0: none), disturbances, noise
  int width_px = 640;               ///< camera size (VGA; 320x240 for quick runs)
  int height_px = 480;
  /// The mock's lens (`evaluate --lens`, issue 31). kPepper: the mock renders through Pepper's
  /// top-camera calibration with ViSP's distortion model
  /// (CameraIntrinsics::pepper_top_vga_with_distortion(), kud 0.0275); kNone: the pinhole
  /// calibration pepper_top_vga().
  enum class Lens { kNone, kPepper };
  Lens lens = Lens::kNone;
  /// `--lens-correction`: true, the app takes the camera model the mock reports, so a lens's
  /// features are undistorted (core/camera/distortion.hpp); false, the app takes the pinhole
  /// calibration pepper_top_vga() of the same camera whatever the lens (no correction).
  bool correct_lens = true;
  /// forward: the forward-looking method; ceiling (issue 24): teach builds the ceiling mosaic
  /// (head at `head`'s pitch, the caller's ceiling pitch) and the replay runs the ceiling
  /// navigator (session/ceiling_replay.hpp) in the same replay loop; `features` does not apply.
  core::NavMode mode = core::NavMode::kForward;
  core::ceiling::CeilingNavigatorOptions ceiling;  ///< ceiling mode's replay
  /// Lines, points or both: teach (key-image selection) and replay match only these.
  core::control::FeatureMode features = core::control::FeatureMode::kLinesAndPoints;
  /// Start perturbations (uniform, +-): replaces the world's own ranges. The start of run k is
  /// world.scenario.replay_start(k, seed') with these ranges; a start whose 0.3 m footprint
  /// touches an obstacle is redrawn (next seed').
  double perturb_lateral_m = 0.3;
  double perturb_yaw_deg = 10.0;
  double perturb_along_m = -1.0;    ///< < 0: the world's own range
  std::set<Disturbance> disturbances;
  DisturbanceOptions disturbance;
  /// Converged part of a run (deviation statistics): after converged_after_m of travelled
  /// distance AND once |lateral| has fallen below converged_below_m (0: distance rule alone).
  /// A run that completes the tour without ever converging fails ("not_converged").
  double converged_after_m = 1.5;
  double converged_below_m = 0.05;
  double end_tolerance_m = 0.3;     ///< success: final base position within this of the end
  /// The replay session's give-up times (configuration replay.give_up_lost_s and
  /// replay.give_up_not_localised_s; `evaluate` takes them from the configuration). > 0.
  double give_up_lost_s = 10.0;
  double give_up_not_localised_s = 10.0;
  /// replay.arrival_tolerance_m / _rad (the replay's "arrived" verdict).
  double arrival_tolerance_m = 0.15;
  double arrival_tolerance_rad = 0.1;
  double divergence_m = 1.0;        ///< |lateral| beyond this ends the run (failure)
  /// Time limit per run: time_limit_factor x (taught path length / 0.08 m/s) + 20 s.
  double time_limit_factor = 1.5;
  std::filesystem::path map_dir;    ///< where the taught map is saved (empty: a temp folder)
  /// The navigator (controller included); its `features` field is overridden by `features`.
  core::navigator::NavigatorOptions navigator;
  naoqi_bridge::HeadLockRequest head;  ///< teach and replay lock the head here
  core::mapping::KeyImageSelectorOptions key_images;  ///< teach: key-image selection rule
  /// When set, each run writes <trace_dir>/<world>_<features>_<disturbances>_run<k>.jsonl
  /// (disturbances: "none", or e.g. "light+person"): per frame the ground
  /// truth, the command and the navigator's telemetry (for diagnosing a failed run).
  std::filesystem::path trace_dir;

  std::vector<std::string> validate() const;
};

/// The teach drive and its map.
struct TeachResult {
  std::string world_name;
  core::memory::VisualMemory map;            ///< as loaded back from map_dir
  std::filesystem::path map_dir;
  std::vector<Eigen::Vector2d> path_m;       ///< ground-truth base positions, one per frame
  std::vector<Eigen::Vector2d> key_m;        ///< ground-truth base positions of the key images
  std::vector<double> key_yaw_rad;           ///< ... and their ground-truth base yaws
  double length_m = 0.0;                     ///< length of path_m
  int frames = 0;
  double wall_s = 0.0;                       ///< wall-clock time of the teach
};

/// One frame of a replay run.
struct RunSample {
  double t_s = 0.0;           ///< simulated time since the run started
  double x_m = 0.0, y_m = 0.0, yaw_rad = 0.0;  ///< ground truth (world frame)
  double travelled_m = 0.0;   ///< distance driven since the start
  double s_m = 0.0;           ///< progress along the taught path
  double lateral_m = 0.0;     ///< signed deviation from the taught path
  double v_m_s = 0.0, omega_rad_s = 0.0;  ///< command sent (0 when stopped)
  bool frame_received = true; ///< false: dropped by the WiFi model (no navigator step)
  int n_lines = 0, n_points = 0;  ///< verified matches with IN
  int key_next = -1;          ///< IN
  bool dead_reckoning = false;  ///< driven on odometry alone (vision blind) on this frame
  double step_ms = 0.0;       ///< wall-clock navigator step (NaN when no frame)
};

struct RunResult {
  int index = 0;
  double start_x_m = 0.0, start_y_m = 0.0, start_yaw_rad = 0.0;
  double start_lateral_m = 0.0;  ///< of the start, from the taught path
  double light_factor = 0.0;     ///< light disturbance of this run (0: none)
  bool success = false;
  std::string outcome;        ///< complete, collision, lost, diverged, timeout, wrong_end
  std::string detail;         ///< e.g. what was hit
  bool tour_complete = false;
  double travelled_m = 0.0;
  /// Verified matches with IN (RunSample::n_lines, n_points), mean over the frames received
  /// (NaN: none).
  double verified_lines_mean = std::numeric_limits<double>::quiet_NaN();
  double verified_points_mean = std::numeric_limits<double>::quiet_NaN();
  double lateral_rms_m = 0.0;  ///< converged part
  double lateral_max_m = 0.0;  ///< converged part
  double converged_from_m = -1.0;  ///< travelled distance where the converged part starts
  double first_under_5cm_m = -1.0;
  double final_error_m = 0.0;  ///< final base position to the taught end
  /// The replay's own arrival verdict at the end of the tour (ReplayResult::arrival; "" when the
  /// tour was not completed) and its estimated offset from the final key image, m (NaN: none),
  /// to compare with final_error_m.
  std::string arrival_verdict;
  std::string arrival_source;
  double arrival_offset_m = std::numeric_limits<double>::quiet_NaN();
  double omega_rate_rms_rad_s2 = 0.0;
  double step_ms_median = 0.0, step_ms_p95 = 0.0;
  int frames = 0;
  int frames_dropped = 0;
  int lost_frames = 0;         ///< frames with a stop command after the first localisation
  /// Stretches driven on odometry alone (navigator dead reckoning, issue 29): frames, and per
  /// re-acquisition the distance and turn driven blind and the drift the first VNHV fix after
  /// it corrected (NaN: no fix before the next blind stretch).
  int dead_reckoning_frames = 0;
  /// Frames where the heading from lines corrected the odometry estimate (no VNHV fix; the
  /// navigator's line-yaw Kalman update accepted the measurement).
  int line_heading_frames = 0;
  struct Reacquisition {
    double blind_m = 0.0, blind_rad = 0.0;
    double corrected_m = std::numeric_limits<double>::quiet_NaN();
    double corrected_rad = std::numeric_limits<double>::quiet_NaN();
  };
  std::vector<Reacquisition> reacquisitions;
  double sim_s = 0.0;
  double wall_s = 0.0;
  std::vector<RunSample> samples;
};

struct Summary {
  int runs = 0;
  int successes = 0;
  double success_rate = 0.0;
  double lateral_rms_m = 0.0;    ///< mean over runs of the per-run RMS (runs with samples)
  double verified_lines_mean = 0.0;   ///< mean over runs of RunResult::verified_lines_mean
  double verified_points_mean = 0.0;  ///< mean over runs of RunResult::verified_points_mean
  double lateral_max_m = 0.0;    ///< max over runs of the per-run max
  double final_error_mean_m = 0.0;
  double final_error_max_m = 0.0;
  double key_images_per_m = 0.0;
  double converged_from_max_m = 0.0;   ///< max over runs of converged_from_m (NaN if one never did)
  double omega_rate_rms_rad_s2 = 0.0;  ///< mean over runs
  /// Runs that completed the tour, and those whose arrival verdict agreed with the ground truth
  /// (arrived and final_error_m <= arrival tolerance, or not aligned / unknown and beyond it).
  int arrival_judged = 0;
  int arrival_agreed = 0;
  double step_ms_median = 0.0;   ///< over all frames of all runs
  double step_ms_p95 = 0.0;
};

struct Evaluation {
  std::string world_name;
  std::string mode;          ///< "forward", "ceiling"
  std::string features;      ///< "lines+points", "lines", "points"; "ceiling" in ceiling mode
  std::string controller;    ///< "ibvs", "vnhv"
  std::string size;          ///< "640x480"
  std::string lens;          ///< lens_label(): "none", "pepper", "pepper uncorrected"
  std::vector<std::string> disturbances;
  std::vector<std::string> disturbance_notes;
  int key_images = 0;
  double taught_length_m = 0.0;
  int teach_frames = 0;
  std::vector<RunResult> runs;
  Summary summary;
};

/// Progress lines ("start 3/10: ...") go through this callback (may be empty).
using ProgressFn = std::function<void(const std::string&)>;

/// Teaches the world's tour at the options' image size with the options' features (lines or
/// points only: a single-modality map), saves the map to options.map_dir (or a temporary
/// folder) and loads it back.
TeachResult teach_tour(const std::shared_ptr<const sim::World>& world,
                       const EvaluationOptions& options, const ProgressFn& progress = {});

/// Start pose of run k (perturbed, collision-free; see EvaluationOptions).
sim::Pose2D replay_start_pose(const sim::World& world, int k, const EvaluationOptions& options);

/// The simulated robot of replay run k: its start pose and the options that build it (lighting,
/// camera noise seed, and the latency and frame-drop disturbances). `evaluate` and `replay
/// --robot mock:W --mock-start K --seed S` both use it, so they replay the same run.
struct MockReplaySetup {
  sim::Pose2D start;
  sim::MockRobotOptions robot;
  naoqi_bridge::MockBridgeOptions bridge;
};
MockReplaySetup mock_replay_setup(const sim::World& start_world, int k, const std::string& lighting,
                                  const EvaluationOptions& options);

/// `evaluate --lens NAME --lens-correction on|off` into options.lens and correct_lens. Throws
/// std::invalid_argument naming the option and its allowed values.
void set_lens_options(const std::string& lens, const std::string& correction,
                      EvaluationOptions& options);

/// The camera the mock renders with, at VGA (options.lens).
core::CameraIntrinsics mock_camera_vga(const EvaluationOptions& options);
/// The camera model the app teaches with instead of the one the mock reports (options.lens and
/// correct_lens); std::nullopt: the mock's.
std::optional<core::CameraIntrinsics> app_camera_model(const EvaluationOptions& options);
/// "none", "pepper" (rendered through the lens, corrected) or "pepper uncorrected".
std::string lens_label(const EvaluationOptions& options);

/// The camera request of teach and replay (the options' size, the mock's 15 fps).
naoqi_bridge::CameraRequest camera_request(const EvaluationOptions& options);

/// The replay session's options for an evaluation run (no monitor set).
ReplaySessionOptions replay_session_options(const EvaluationOptions& options);

/// One replay from `start` in `replay_world` (possibly disturbed), lighting `lighting`.
RunResult replay_run(const TeachResult& teach,
                     const std::shared_ptr<const sim::World>& replay_world,
                     const std::string& lighting, const sim::Pose2D& start, int k,
                     const EvaluationOptions& options);

/// All replays of one configuration on a taught map, with summary.
Evaluation evaluate(const TeachResult& teach, const std::shared_ptr<const sim::World>& world,
                    const EvaluationOptions& options, const ProgressFn& progress = {});

/// `arrival_tolerance_m`: the replay's arrival tolerance, to judge its verdicts by ground truth.
Summary summarize(const std::vector<RunResult>& runs, int key_images, double taught_length_m,
                  double arrival_tolerance_m = 0.15);

const char* feature_label(core::control::FeatureMode mode);

/// `prefix` + feature_label(mode) + `suffix` for a single modality, "" for lines and points:
/// what names that modality's map folder and teach line.
std::string single_modality_tag(core::control::FeatureMode mode, const std::string& prefix,
                                const std::string& suffix = "");

}  // namespace pepper::app::evaluation
