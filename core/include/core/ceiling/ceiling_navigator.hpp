#pragma once
// Ceiling-mode replay (issue 24; Blanc et al. 2004, section 3; docs/method/ceiling.md
// "Replay"): one call per frame, the base command and a telemetry record out, as
// navigator::Navigator does for forward mode.
//
// Per frame: canonical view (CanonicalView::warp) -> landmarks (extract_landmarks, observe) ->
// the base pose T_mosaic_base (MosaicLocaliser: without a prior until the first fix, so a replay
// may start anywhere on the tour; then with the previous pose, or the odometry's prediction of
// it) -> the relay segment (IP, IN) = relay images (i, i + 1) of the ceiling tour -> the VNHV
// chained-form law (control::vnhv_omega) on the robot's lateral offset and heading relative to
// the line IP -> IN (or, on a segment that turns by more than arc_min_turn_rad, to the arc from
// IP to IN, control::deviation_from_arc, its curvature fed forward) -> the velocity schedule.
//
// Switching: IN is passed once the robot's projection along the segment reaches IN (the normal
// to the chord through IN; on an arc segment, the normal to IN's heading); the next segment
// begins there, so the reference is continuous at the hand-over. Past the final relay image:
// tour complete (stop, for good). Why not the paper's image-error convergence: the law drives a
// moving vehicle (V != 0, chained form) that never converges on a relay image; and why not
// earlier: on a turning tour, IP -> IN's line leads straight on past IN while the taught path
// turns, and switching at the normal hands the robot to the line that turns with the path.
//
// Localisation lost (no fix): with odometry in the frames the robot coasts on the odometry's
// prediction of its pose from the last fix while the odometry's error model says that prediction
// is within coast_max_error_m, and for at most coast_max_s, then stops
// (state kLost, reason kFeaturesLost) and localises without a prior on every frame until a fix;
// without odometry it stops at once. A relay segment listed in the tour's breaks (the teach's
// chain was cut there: no landmark and no odometry links the two relay images) is never driven:
// stop for good,
// reason kRelayBreak, state kLost, on every further frame.
//
// Frames and units: the mosaic frame (mosaic.hpp), base frame x forward, y left, metres,
// radians counter-clockwise; docs/conventions.md. Determinism: the command is a function of the
// frames and the options (seeded RANSAC); wall-clock durations appear only in the timings.
// Errors: bad options, a tour with fewer than 2 relay images or an empty mosaic throw
// std::invalid_argument at construction; a frame that is empty, not CV_8UC1, of another size
// than the camera's, or older than the previous one throws std::invalid_argument (the app stops
// the robot). Not thread-safe: one per replay.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/ceiling/canonical_view.hpp"
#include "core/ceiling/ceiling_tour.hpp"
#include "core/ceiling/landmarks.hpp"
#include "core/ceiling/mosaic.hpp"
#include "core/ceiling/mosaic_localiser.hpp"
#include "core/ceiling/observation.hpp"
#include "core/control/velocity_schedule.hpp"
#include "core/control/vnhv_law.hpp"
#include "core/frame.hpp"
#include "core/navigator/navigator.hpp"

namespace pepper::core::ceiling {

struct CeilingNavigatorOptions {
  /// The canonical view ends this far ahead of the optical centre, m, > 0: the teach's
  /// (CeilingTeachOptions::max_forward_m); the scale is the mosaic's own px_per_m.
  double max_forward_m = 3.5;
  LandmarkOptions landmarks;
  LocaliserOptions localiser;
  /// The law's gains (kp_1_m2, kd_1_m) and validity bound (max_abs_theta_rad); the forward
  /// navigator's segment-model fields are not used here.
  control::VnhvOptions vnhv;
  control::VelocityScheduleOptions schedule;
  /// Relay segments whose taught heading change (IP's yaw in IN's frame) exceeds this follow the
  /// arc IP -> IN instead of the chord, rad, >= 0 (large: chords only). Relay images are
  /// 0.3-0.7 m apart in turns (docs/method/ceiling.md), so the chord cuts inside the turn.
  double arc_min_turn_rad = 0.1;
  /// |heading| beyond vnhv.max_abs_theta_rad (the chained form is singular at pi/2): turn on the
  /// spot towards the segment's direction at this gain, 1/s, > 0.
  double turn_in_place_gain_1_s = 1.0;
  /// Coasting on odometry without a fix: while the odometry's error since the last fix may have
  /// moved the robot at most coast_max_error_m, m, >= 0 (0: stop at once), and for at most
  /// coast_max_s, s, >= 0. The error is the odometry's error model (core/odometry.hpp): its
  /// heading error grows with every radian turned and metre driven, and every metre driven adds
  /// that heading error plus the distance error. A turn on the spot adds heading error but no
  /// position error until the robot drives on; 3 cm allow about 0.9 m straight on, or 0.4 m on
  /// after a blind quarter turn (a corridor's end where the view is a wall). Time does not make
  /// odometry drift: coast_max_s only bounds how long a robot may act on a stale fix (a U-turn
  /// on the spot takes about 8 s).
  double coast_max_error_m = 0.03;
  double coast_max_s = 8.0;

  std::vector<std::string> validate() const;
};

/// What the forward telemetry has no field for.
struct CeilingTelemetry {
  bool fix = false;            ///< the localiser found the pose on this frame
  bool prior_used = false;     ///< it was searched around a prior (else over the whole mosaic)
  int matches = 0, inliers = 0;  ///< the localiser's counts (MosaicFix)
  bool pose_known = false;     ///< T_mosaic_base below is this frame's (fix or coast)
  PlanarPose T_mosaic_base;    ///< the robot's pose used by the law
  double coasted_m = 0.0;      ///< odometry distance since the last fix
  double coast_error_m = 0.0;  ///< the odometry's possible position error since the last fix
  double perceive_ms = 0.0, localise_ms = 0.0;  ///< wall clock, telemetry only
  /// The localiser's inlier landmarks (MosaicFix::inlier_observations) when it found the pose.
  std::vector<int> inlier_observations;
};

struct CeilingStepResult {
  /// The command, and the forward Telemetry's fields where they mean the same: ip / in / inn are
  /// relay indices, n_points_next the localiser's inliers, vnhv_* the deviation from the
  /// segment, dead_reckoned_m the coasted distance (docs/method/ceiling.md "Replay"); step()
  /// also draws the inlier landmarks in the camera image (overlay.points_px, undistorted pixels,
  /// key_index the IN relay).
  navigator::StepResult step;
  CeilingTelemetry ceiling;
};

class CeilingNavigator {
 public:
  /// `camera`: intrinsics, head pitch and the ceiling's height above the optical centre;
  /// `cam_in_base_m`: the optical centre's horizontal offset from the base's rotation axis.
  /// Throws std::invalid_argument (see above).
  CeilingNavigator(Mosaic mosaic, CeilingTour tour, const CeilingCamera& camera,
                   const cv::Point2d& cam_in_base_m, const CeilingNavigatorOptions& options = {});

  CeilingStepResult step(const Frame& frame);
  /// The same after perception: one frame's landmarks in the base frame (unit tests drive the
  /// navigator with synthetic observations).
  CeilingStepResult step_observation(const CeilingObservation& observation, int64_t t_ns,
                                     const std::optional<OdometryPose>& odom);

  navigator::NavState state() const { return state_; }
  /// The current segment's IN (relay index), -1 before the first fix.
  int next_relay() const { return next_; }
  const CeilingTour& tour() const { return tour_; }

 private:
  /// The segment i -> i + 1 nearest to the pose (first fix): its index i.
  int nearest_segment(const PlanarPose& T_mosaic_base) const;
  /// Whether the pose has passed relay `next` along segment next - 1 -> next.
  bool passed(int next, const PlanarPose& T_mosaic_base) const;
  bool arc_segment(int next) const;
  /// Whether the chord IP -> IN of a straight segment gives its direction: at least 3 cm long
  /// and within 90 degrees of IN's taught heading. Shorter, relay poses' noise in the mosaic (a
  /// few centimetres) can turn it round (room_corridor_room's relays 15 and 16, 1.7 cm apart,
  /// pointed backwards and the robot turned on the spot into a door frame: docs/method/
  /// ceiling.md, session 38); then IN's own pose is the reference, as for a turn taught on the
  /// spot.
  bool chord_usable(int next) const;
  /// The law's yaw-rate demand on the segment (telemetry filled); v_in_place set when the robot
  /// must turn on the spot.
  double demand(const PlanarPose& T_mosaic_base, navigator::Telemetry& tel, bool& in_place);
  navigator::Command stop(navigator::StopReason reason, navigator::NavState state);
  void fill_arrival(const PlanarPose& T_mosaic_base, bool from_fix, navigator::Telemetry& tel) const;

  CeilingTour tour_;
  CeilingNavigatorOptions options_;
  std::unique_ptr<CanonicalView> view_;
  cv::Point2d cam_in_base_m_;
  MosaicLocaliser localiser_;
  control::VelocitySchedule schedule_;
  navigator::NavState state_ = navigator::NavState::kNotLocalized;
  int next_ = -1;  ///< IN; the segment is (next_ - 1, next_)
  std::optional<int64_t> last_t_ns_;
  double last_v_m_s_ = 0.0;
  /// The last fix: pose, frame time and the odometry read with it (coasting).
  std::optional<PlanarPose> last_fix_;
  int64_t last_fix_t_ns_ = 0;
  std::optional<OdometryPose> last_fix_odom_;
  /// The odometry's possible errors since the last fix (coasting), and the previous reading.
  double coast_heading_error_rad_ = 0.0;
  double coast_error_m_ = 0.0;
  std::optional<OdometryPose> prev_odom_;
  /// The pose of the previous frame (fix or coast): the next localisation's prior.
  std::optional<PlanarPose> last_pose_;
  bool broken_ = false;  ///< a relay break was reached: stopped for good
};

}  // namespace pepper::core::ceiling
