#pragma once
// The navigator's outputs: the command for the base and one telemetry record per frame.
// Plain data (no behaviour) so the app, the UI and recorders can copy and serialise it.
// `overlay` is for display only (a few KB per frame at most).
// Units in names; NaN marks a value that was not computed this frame; -1 marks an absent
// key-image index. Timings are wall-clock durations (telemetry only, never used by the command).

#include <cstdint>
#include <limits>

#include "core/features/feature_overlay.hpp"

namespace pepper::core::navigator {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

enum class NavState {
  kNotLocalized,
  kNavigating,
  kHolding,
  kLost,
  kTourComplete,
  kOverdue,
  kDeadReckoning,  ///< vision sees too little: the taught path is driven on odometry
};
enum class StopReason {
  kNone,          ///< moving (not a stop)
  kNotLocalized,  ///< initial localisation has not succeeded yet
  kFeaturesLost,  ///< no usable feature for longer than the hold time
  kTourComplete,  ///< the final image was reached
  kSegmentOverdue,  ///< no key-image switch for far longer than teaching took: unsure, stopped
  kRelayBreak,  ///< ceiling mode: the next relay segment is a break of the taught relay chain
};

const char* to_string(NavState s);
const char* to_string(StopReason r);

/// A VNHV fix older than this (frame time) no longer says where the robot arrived.
inline constexpr int64_t kArrivalFixMaxAgeNs = 1'000'000'000;

struct Command {
  double v_m_s = 0.0;        ///< forward speed, base x
  double omega_rad_s = 0.0;  ///< yaw rate, > 0 turns left
  bool stop = true;          ///< true: the base must stop (v = omega = 0)
  StopReason reason = StopReason::kNotLocalized;
};

struct StageTimings {
  double extract_ms = 0.0;   ///< feature extraction of the current frame
  double localize_ms = 0.0;  ///< initial localisation / relocalisation (0 when not run)
  double match_ms = 0.0;     ///< two- and three-view matching for switching and control
  double control_ms = 0.0;   ///< control law + schedule
  double total_ms = 0.0;
  /// The current frame's matching work (features::MatchTimings of its FrameMatcher, within
  /// match_ms and localize_ms; VNHV's key-to-key segment match once per segment is not in it).
  double lines_ms = 0.0;
  double klt_ms = 0.0;
  double essential_ms = 0.0;
  double three_view_ms = 0.0;
  double wide_baseline_ms = 0.0;
};

struct Telemetry {
  int64_t t_ns = 0;
  int64_t frame_index = -1;
  NavState state = NavState::kNotLocalized;
  StopReason reason = StopReason::kNotLocalized;
  // Segment.
  int ip = -1, in = -1, inn = -1;
  bool switched = false;     ///< IP/IN/INN advanced on this frame
  int switch_streak = 0;     ///< consecutive frames a switch (or arrival) was wanted
  int switch_criterion = 0;  ///< localization::SwitchCriterion bits (rules, passed, guard)
  // Counts (verified correspondences).
  int n_lines_next = 0, n_points_next = 0;            ///< Ia vs IN
  int n_lines_next_next = 0, n_points_next_next = 0;  ///< Ia vs INN
  // The switching counts below are computed lazily (-1: not needed this frame, see navigator).
  int n_prev = -1;                 ///< n(IP, Ia)
  int n_three_view_next = -1;      ///< nL + nP (Ia, IN, INN)
  int n_three_view_prev = -1;      ///< nL + nP (IP, Ia, IN)
  double next_scale_ratio = kNaN;  ///< apparent scale of IN's points in Ia (1 = at IN)
  // Control.
  double line_err_next = kNaN, line_err_next_next = kNaN;    ///< Xa - XN, Xa - XNN
  double point_err_next = kNaN, point_err_next_next = kNaN;  ///< xa - xn, xa - xnn
  double J_L = kNaN, J_P = kNaN;
  bool used_lines = false, used_points = false;
  double vnhv_lateral_m = kNaN, vnhv_heading_rad = kNaN;
  /// Triangulated points of the VNHV model of the current segment; 0: no model (IBVS drives);
  /// -1: VNHV is not the controller.
  int vnhv_model_points = -1;
  /// The resection's rigid structures this frame (control::PlanarFix::structures; 0: none or no
  /// model) and whether the one the odometry predicts was within its gate (a fix) or none was
  /// (vnhv_fix_refused: every structure in view has moved as far as the odometry can tell).
  int vnhv_structures = 0;
  bool vnhv_fix_refused = false;
  /// This frame's own VNHV measurement (before the deviation filter), NaN without a fix; with
  /// vnhv_fix_refused, the largest structure's, which was not used.
  double vnhv_fix_lateral_m = kNaN, vnhv_fix_heading_rad = kNaN;
  /// The fix's squared Mahalanobis distance to the odometry's prediction (control::PosePrior) and
  /// its weight (1 at the prediction, 0 at the gate); NaN without a prediction.
  double vnhv_fix_d2 = kNaN, vnhv_fix_weight = kNaN;
  /// The fix's distance from IN in segment units (|IP -> IN| = 1; beyond 1 it extrapolates the
  /// segment's reconstruction); NaN without a fix.
  double vnhv_fix_r_units = kNaN;
  /// The gate's terms (docs/method/navigator.md "Right fixes refused after a blind turn"): the
  /// fix's pose minus the prediction's in IN's floor frame (x along IN's optical axis, y across
  /// it, m; yaw, rad) and the prediction's sigmas there; vnhv_fix_d2 is the sum of the squared
  /// ratios. NaN without a fix or without a prediction.
  double vnhv_gate_dx_m = kNaN, vnhv_gate_dy_m = kNaN, vnhv_gate_dyaw_rad = kNaN;
  double vnhv_gate_sigma_x_m = kNaN, vnhv_gate_sigma_y_m = kNaN, vnhv_gate_sigma_yaw_rad = kNaN;
  /// After an accepted fix with odometry: the probability that the segment's fixes come from the
  /// room rather than from a moved object (navigator/fix_error_mixture.hpp). Below one half the
  /// fix neither corrects the VNHV filter nor counts as the robot located.
  double vnhv_fix_room_probability = kNaN;
  /// The odometry estimate's deviation from the current segment (the prediction the fixes are
  /// gated against) and its sigmas across and in heading (at that gate on frames with a fix,
  /// else at the end of the step); NaN without an odometry estimate.
  double odom_lateral_m = kNaN, odom_heading_rad = kNaN;
  double odom_lateral_sigma_m = kNaN, odom_heading_sigma_rad = kNaN;
  /// How much of the lateral sigma the odometry added since the lateral position was last
  /// measured or placed (EstimateErrors::grown; the dead-reckoning bound
  /// NavigatorOptions::dead_reckoning_max_lateral_sigma_m); NaN without an odometry estimate.
  double odom_lateral_sigma_grown_m = kNaN;
  /// The odometry estimate's distance along the taught path past IN (m, < 0 before it; when IN
  /// is the final key image, along its taught heading, so also > 0 past the end) and its sigma
  /// along the robot; NaN without an odometry estimate.
  double odom_past_next_m = kNaN, odom_along_sigma_m = kNaN;
  double omega_demand_rad_s = kNaN;  ///< law output before schedule limits
  bool turning = false;
  int64_t hold_elapsed_ns = 0;  ///< time since the last usable control, when holding
  // Odometry (navigator/path_tracker.hpp). NaN where unknown.
  /// Progress along the taught path from odometry, in key-image indices (i + fraction).
  double odom_progress = kNaN;
  /// While dead reckoning, and on the frame vision takes over again: distance (m) and turn
  /// (rad) driven on odometry alone since vision was last usable.
  double dead_reckoned_m = kNaN, dead_reckoned_rad = kNaN;
  bool reacquired = false;  ///< vision drives again on this frame after dead reckoning
  /// VNHV had no estimate and the odometry's deviation from the taught path steered instead.
  bool odometry_steered = false;
  /// No VNHV fix this frame, and the lines matched with IN gave the robot's yaw relative to IN
  /// (geometry/line_yaw.hpp): that yaw (rad, CCW) and the heading correction it made to the
  /// odometry estimate (rad), and the probability that the segment's line yaws so far are the
  /// room's rather than a moved object's (navigator/fix_error_mixture.hpp); NaN otherwise.
  double line_yaw_rad = kNaN, line_yaw_correction_rad = kNaN, line_yaw_room_probability = kNaN;
  /// No VNHV fix this frame, and the lines on the floor matched with IN fixed the robot's
  /// position across them (geometry/floor_lines.hpp): the lines that agreed, and the odometry
  /// estimate's lateral offset in IN's taught frame before and after the update (m, > 0 left),
  /// what the lines alone say it is and that measurement's sigma (m), and the probability that
  /// the segment's floor lines so far are the room's rather than a moved object's
  /// (navigator/fix_error_mixture.hpp); 0 and NaN otherwise.
  int floor_lines = 0;
  double floor_lateral_before_m = kNaN, floor_lateral_after_m = kNaN;
  /// How far the first switch the image decided after a placement moved the odometry estimate
  /// along the robot (m; NaN on the other frames): the robot is at the IN it left
  /// (Navigator::correct_along_from_switch).
  double switch_along_correction_m = kNaN;
  double floor_lateral_lines_m = kNaN, floor_lateral_lines_sigma_m = kNaN;
  double floor_room_probability = kNaN;
  /// On the first frame after a blind stretch with a VNHV fix: how far that fix moved the
  /// odometry estimate, the drift corrected at re-acquisition, m and rad (else NaN).
  double drift_corrected_m = kNaN, drift_corrected_rad = kNaN;
  // Arrival (on tour-complete frames): where the robot stands in the final key image's taught
  // frame (x forward: > 0 past it; y left; yaw: robot heading - taught heading), from a VNHV
  // fix on the final segment at most kArrivalFixMaxAgeNs old (source kVision) or else from the
  // odometry carried along the taught path (kOdometry); NaN and kNone when neither exists.
  enum class ArrivalSource { kNone, kVision, kOdometry };
  double arrival_along_m = kNaN, arrival_lateral_m = kNaN, arrival_heading_rad = kNaN;
  ArrivalSource arrival_source = ArrivalSource::kNone;
  // Localisation.
  bool localization_ran = false;
  int localization_best = -1, localization_best_count = 0, localization_verified = 0;
  StageTimings timings;
  /// Current frame's verified matches with IN (overlay.key_index) at their pixel positions,
  /// taken after switching; empty when no segment was tracked this frame.
  features::FeatureOverlay overlay;
};

/// "none", "vision", "odometry".
const char* to_string(Telemetry::ArrivalSource s);

}  // namespace pepper::core::navigator
