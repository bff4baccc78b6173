#pragma once
// Ceiling-mode replay (issue 24; docs/method/ceiling.md "Replay"): the core's CeilingNavigator
// over a ceiling-mode map folder, as the replay loop's step (run_replay_session's StepFunction),
// so that `replay`, `demo` and `evaluate` in ceiling mode run the one replay loop with all its
// stop paths.
//
// The camera geometry is the simulated robot's where there is one (its world's ceiling), else a
// real Pepper's with the configured ceiling height (ceiling_camera_for, as in ceiling teach);
// without a height the callers refuse real robots before anything connects.
// The tour's metres are the teach's: its ceiling's distance above the camera set their scale.
// A replay under a ceiling whose distance differs by more than kCeilingScaleTolerance would run
// every distance of the tour that much too long or too short, so it is refused
// (check_taught_ceiling); a tour of format version 1 did not record its ceiling and replays with
// a warning.
// Errors: a map that is not in ceiling mode, a damaged or missing mosaic or tour (MosaicError,
// CeilingTourError, std::runtime_error naming the file), a world without a ceiling above the
// camera, or another ceiling than the teach's throw before anything moves. Not thread-safe (one
// replay).

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/ceiling/ceiling_navigator.hpp"
#include "core/memory/visual_memory.hpp"
#include "core/ceiling/ceiling_tour.hpp"
#include "session/ceiling_teach.hpp"
#include "session/replay_session.hpp"
#include "sim/mock_robot.hpp"

namespace pepper::app {

/// The replay step of a ceiling map taught in `map_dir` (whose loaded map is `map`), for the
/// mock `robot` (nullptr: a real robot, the ceiling `ceiling_height_m` above the floor) with the
/// head at `head_pitch_rad`. The navigator is shared with the returned
/// function (telemetry and tests may read it).
struct CeilingReplay {
  std::shared_ptr<core::ceiling::CeilingNavigator> navigator;
  StepFunction step;
  /// The last step's ceiling telemetry (ceiling_telemetry_to_json) for the replay's JSON lines
  /// (ReplaySessionOptions::ceiling_telemetry): the pose in the mosaic, the fix and its counts.
  std::function<nlohmann::json()> telemetry_json;
  std::vector<std::string> warnings;  ///< for the operator (a tour that cannot be checked)
};
CeilingReplay make_ceiling_replay(const sim::MockRobot* robot, double ceiling_height_m,
                                  const std::filesystem::path& map_dir,
                                  const core::memory::VisualMemory& map, double head_pitch_rad,
                                  const core::ceiling::CeilingNavigatorOptions& options = {});

/// One step's CeilingTelemetry: {"fix", "prior_used", "matches", "inliers", "pose_known",
/// "T_mosaic_base": {"x_m", "y_m", "theta_rad"} (null when no pose is known: before the first
/// fix, or coasting ended), "coasted_m", "perceive_ms", "localise_ms"}; frames and units as
/// core/ceiling (mosaic frame = the base frame of the teach's first frame, metres, radians CCW).
nlohmann::json ceiling_telemetry_to_json(const core::ceiling::CeilingTelemetry& t);

/// Largest relative difference between the teach's and the replay's ceiling distance above the
/// camera: the head pitches a replay may use move Pepper's camera by about 4 mm (0.3 % of a
/// 1.5 m distance); a ceiling measured again to within a few centimetres passes.
inline constexpr double kCeilingScaleTolerance = 0.03;

/// Throws std::invalid_argument naming `tour_file` when `setup`'s ceiling is not the one
/// `tour` was taught under (kCeilingScaleTolerance); a tour without one (format 1) passes.
void check_taught_ceiling(const core::ceiling::CeilingTour& tour, const CeilingCameraSetup& setup,
                          const std::filesystem::path& tour_file);

}  // namespace pepper::app
