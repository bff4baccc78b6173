#pragma once
// Alternative controller: the "virtual non-holonomic vehicle" path-following law of Blanc et al.
// 2004 (METHOD.md, last section; seeds/003), adapted to a forward-looking camera: the robot
// follows the straight floor segment from the previous key image IP to the next one IN.
//
//   omega = -V cos^3(theta) Kp y - |V cos^3(theta)| Kd tan(theta)
//
// y: lateral deviation from the segment, m, > 0 when the robot is left of it (seen along the
// direction of travel); theta: heading of the robot relative to the segment direction, rad, > 0
// when it points to the left of it; V: forward speed, m/s. With y' = V sin(theta) and
// theta' = omega this gives y'' + Kd y' + Kp y = 0 with ' = d/ds (distance travelled): the
// settling distance depends on Kp, Kd only (chained form; docs/method/control.md).
//
// Deviations (navigator): the current camera is located in the segment's own reconstruction
// (segment_pose.hpp: IP, IN and the current image share one scale, the segment unit |IP - IN|),
// the lateral offset in segment units times the metres per unit (the taught length IP -> IN,
// Navigator::segment_taught_m, is the chord's length, or the arc's on a turning segment) is y; (y, theta) are filtered with the robot's commands
// (deviation_filter.hpp). A scale error in the segment length only changes the effective Kp.
//
// Pure functions, thread-safe. vnhv_omega returns nullopt when |theta| >= max_abs_theta_rad (the
// chained form is singular at pi/2): the navigator then falls back to the IBVS law.

#include <optional>
#include <string>
#include <vector>

#include "core/control/deviation_filter.hpp"
#include "core/control/planar_pose.hpp"
#include "core/control/segment_pose.hpp"

namespace pepper::core::control {

struct VnhvOptions {
  /// Kp, 1/m^2, > 0: natural "frequency" in distance sqrt(Kp) = 3 /m. Why not 4 (2 /m): with
  /// the turning segments on their arcs (max_arc_turn_rad), in robotics_room's corners the
  /// robot entered each arc 0.2-0.3 rad off its tangent and 4 / 4 left it 13 cm outside (VGA,
  /// seed 1, runs 1 3 9: lateral RMS 5.2 cm, max 13.0; with 9 / 6: 3.6 / 9.0;
  /// docs/method/control.md "Turns").
  double kp_1_m2 = 9.0;
  double kd_1_m = 6.0;  ///< Kd, 1/m, > 0: 2 sqrt(Kp) = critically damped (settles in ~1.6 m)
  double max_abs_theta_rad = 1.2;  ///< validity bound on |theta|, in (0, pi/2)
  /// Forward speed of the teach drive, m/s, > 0, for maps without odometry: there the metric
  /// length of a segment is its taught duration (key image t_ns) times this. Maps taught by this
  /// app keep the distance driven (KeyImage::travelled_m), which the navigator uses instead.
  double teach_speed_m_s = 0.2;
  /// Segments whose taught heading change (the arc model's |yaw of IP in IN's frame|) exceeds
  /// this are "turning": they follow their arc (max_arc_turn_rad) or, beyond that or with it
  /// 0, are driven by IBVS. The chord of a turning segment is a poor reference. Measured (room_corridor_room, VGA, seed 1, runs 1, 3, 4 of
  /// 10): with VNHV on every segment it can model all three hit the wall at the lab doorway
  /// (16.4-17.0 m); with 0.1 rad all three complete (lateral RMS 6.9-7.8 cm). rad, > 0 (large:
  /// VNHV on every segment it can model).
  double max_segment_turn_rad = 0.1;
  /// Segments turning by more than max_segment_turn_rad and at most this follow the arc model's
  /// circular arc (deviation from the arc, curvature fed forward) instead of going to IBVS;
  /// 0: IBVS drives every turning segment. rad, >= 0. Measured (VGA, seed 1, 10 starts, VNHV):
  /// room_corridor_room 10/10 at lateral RMS 2.8 cm, max 11.8 (0 and Kp 4, Kd 4: 6.5 / 23.0);
  /// robotics_room 10/10, 3.5 / 10.8 (3.4 / 9.8); README "Closed-loop evaluation".
  double max_arc_turn_rad = 1.0;
  /// Reconstruction and resection (segment_pose.hpp) of turning segments (followed on their
  /// arc); straight segments relax two of its settings, below.
  SegmentPoseOptions pose;
  /// Long straight segments (|turn| <= max_segment_turn_rad, taught length >=
  /// straight_min_length_m): triangulation parallax, rad, > 0, and points (model and resection
  /// inliers), >= 3, instead of pose's. Why lower: in white_corridor, whose corners are mostly
  /// far down the corridor, 3-7 of a segment's 16-25 points had pose's 0.02 rad, no segment had a
  /// model, IBVS drove the whole tour and a 17 cm start offset came within 5 cm only after 20 m
  /// (VGA, seed 1, run 2 of 10; with these 1.7 m). Why not on every segment: robotics_room's
  /// first corner is cut into 0.08 m key-image steps before the turn; with the light change they
  /// got models from few points, VNHV held the robot straight there (IBVS already turns towards
  /// INN), the switches came late and 8 of 10 runs were lost at 5.8-6.2 m. 0.01 rad is 5.6 px
  /// at VGA. README "Closed-loop evaluation".
  double straight_min_parallax_rad = 0.01;
  int straight_min_points = 6;
  double straight_min_length_m = 0.5;  ///< m, >= 0
  DeviationFilterOptions filter;

  std::vector<std::string> validate() const;
};

/// The law above. With a curved reference path (curvature_1_m != 0, > 0 turning left; the
/// deviation is then measured from the arc, planar_pose.hpp deviation_from_arc) the path's own
/// turn rate is fed forward: omega += kappa v cos(theta) / (1 - kappa y) (Samson's path
/// coordinates: theta' = omega - kappa s', s' = v cos(theta) / (1 - kappa y)); nullopt when
/// 1 - kappa y <= 0.1 (at or beyond the centre of the turn). Throws std::invalid_argument for
/// invalid options or non-finite inputs.
std::optional<double> vnhv_omega(double v_m_s, double lateral_m, double heading_rad,
                                 const VnhvOptions& options, double curvature_1_m = 0.0);

}  // namespace pepper::core::control
