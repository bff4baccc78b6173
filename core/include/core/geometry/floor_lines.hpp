#pragma once
// The robot's position relative to a key image from matched line segments that lie on the floor
// (issue 26: white_corridor under light x1.4, where the walls and the ceiling saturate and the
// two floor-wall edges are all the view keeps). The camera's height above the floor and its
// pitch are known (the head is locked), so a segment on the floor back-projects to a 2D line on
// the floor in each view; the same line seen from two poses says how far the second pose is
// from the first across that line. Parallel lines (a corridor's floor edges) fix the lateral
// position only; lines of two directions fix both coordinates.
//
// Frames and signs (docs/conventions.md; line_yaw.hpp for the camera model): a view's floor
// frame has its origin on the floor below the optical centre, x forward (the camera's
// horizontal viewing direction), y left. The camera is pitched by `pitch_rad` (> 0 looks down)
// about its x axis: a normalised image point (u, v) is the ray R_x(-pitch) (u, v, 1) in the
// level frame (x right, y down, z forward), which meets the floor `height_m` below the centre.
// A view b's pose in view a's floor frame is (t, yaw): p_a = R(yaw) p_b + t.
//
// Model: a floor line is n . p = c in a view's floor frame (n its unit normal, c its signed
// distance). Seen from a and b, n_a = s R(yaw) n_b (s = +-1) and
//   n_a . t = c_a - s c_b,
// one linear equation in t per line. Its noise sigma is propagated numerically from the
// segments' endpoints (endpoint_sigma, normalised) and the base's sway (sway_sigma_rad, a pitch
// error in each view). A horizontal line above the floor (a skirting's top edge) reads as a floor
// line farther away: it scales the equation's right side by h / (h - z), 7 % for an 8 cm
// skirting on Pepper, so it still pulls the right way. Lines that are not horizontal or not seen
// below the horizon in both views are not usable. Mismatches and lines of moved objects are
// outliers: each usable line inside the prior's gate proposes the position its own equation
// gives with the prior (a one-line Kalman update), the proposal (or the prior itself) whose
// agreeing lines carry the most information wins, and the fix is the information-form least
// squares of the prior and those lines. Deterministic, pure; no usable or agreeing line: nullopt.

#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/types.hpp>

#include "core/geometry/planar_trifocal.hpp"  // NormSegment

namespace pepper::core::geometry {

/// The camera above the floor: its optical centre's height (m, > 0) and its pitch (rad, > 0
/// looks down, |pitch| < 1).
struct FloorCamera {
  double height_m = 0.0;
  double pitch_rad = 0.0;
};

/// Where a normalised image point's ray meets the floor, in the view's floor frame (x forward,
/// y left, metres); nullopt at or above the horizon, or farther than `max_range_m` ahead.
std::optional<Eigen::Vector2d> floor_point(const cv::Point2d& norm, const FloorCamera& camera,
                                           double max_range_m);

/// Pepper's top camera (PEPPER.md, the URDF, as sim::CameraMount): its optical centre's height
/// above the floor (m) and its forward offset from the base's rotation axis (m) with the head at
/// `head_pitch_rad` (> 0 looks down) and HeadYaw 0. CameraTop sits at (0.08601, 0, 0.16284) m in
/// the head frame; with all joints at zero it is 1.153 m high and 0.048 m ahead, so the head's
/// pitch axis is 0.99016 m high and 0.03801 m behind the base's axis.
struct CameraOnBase {
  double height_m = 0.0;
  double forward_m = 0.0;
};
CameraOnBase pepper_top_camera(double head_pitch_rad);

struct FloorLineOptions {
  /// Both endpoints' floor points must lie within this range (m, > 0): farther, a pixel is
  /// decimetres on the floor.
  double max_range_m = 6.0;
  /// Endpoint noise across the line, normalised units (px / focal), > 0 (as line_yaw.hpp).
  double endpoint_sigma = 0.001;
  /// The base's sway between the views (pitch), rad, >= 0.
  double sway_sigma_rad = 0.006;
  /// A line's direction must agree with the yaw within this (rad, > 0): a floor line seen from
  /// both views after turning by the yaw is the same direction.
  double max_direction_error_rad = 0.05;
  /// A line agrees with a position when its residual is within this many of its sigmas, > 0;
  /// the prior's gate uses the same number of sigmas.
  double gate_sigmas = 3.0;
  /// Only lines whose floor direction in view a is within this angle of a's forward axis are
  /// used (rad, (0, pi/2]; pi/2: all). A caller that wants the lateral position only sets it
  /// low: lines across the view (a tile edge, but also a lamp's reflection in a shiny floor,
  /// which back-projects to a third of its distance) say little about it.
  double max_angle_to_forward_rad = M_PI / 2;
  /// A segment's interpretation plane (the camera centre and the segment) needs a unit normal
  /// with at least this vertical component in both views, (0, 1): below, the segment is (nearly)
  /// vertical in the level frame, the image of a vertical 3D line (a door frame, or its
  /// reflection in a shiny floor) that back-projects to a floor line through the camera itself
  /// and would always say "no lateral offset". A floor line at lateral distance d from the
  /// camera has d / sqrt(d^2 + h^2): 0.2 leaves out lines within 0.24 m of Pepper's camera.
  double min_leverage = 0.2;
  /// Agreeing lines needed for a fix, >= 1.
  int min_inliers = 2;
  std::vector<std::string> validate() const;
};

/// What odometry predicts: view b's position in a's floor frame (m) with its covariance (m^2),
/// and b's yaw in a (rad: line_yaw.hpp or odometry) with its sigma (rad, >= 0; it widens the
/// direction gate only: a yaw error leaves a line's distance, hence the equation, unchanged).
struct FloorPrior {
  Eigen::Vector2d t_m = Eigen::Vector2d::Zero();
  Eigen::Matrix2d cov_m2 = Eigen::Matrix2d::Identity();
  double yaw_rad = 0.0;
  double yaw_sigma_rad = 0.0;
};

struct FloorFix {
  Eigen::Vector2d t_m = Eigen::Vector2d::Zero();  ///< posterior position of b in a (m)
  Eigen::Matrix2d cov_m2 = Eigen::Matrix2d::Zero();  ///< its covariance (prior and lines)
  /// The lines' information alone (1/m^2): its eigenvector of the larger eigenvalue is the
  /// direction the lines fix (across a corridor's edges).
  Eigen::Matrix2d info_1_m2 = Eigen::Matrix2d::Zero();
  /// The lines' information vector (sum of n z / sigma^2, 1/m): with info_1_m2, what the lines
  /// alone say of the position (info_1_m2 t = info_vec_1_m), without the prior.
  Eigen::Vector2d info_vec_1_m = Eigen::Vector2d::Zero();
  int inliers = 0;  ///< lines agreeing with the fix
  int usable = 0;   ///< lines on the floor, horizontal, below the horizon in both views
};

/// One usable line's equation n . t = z with its sigma; exposed for tests.
struct FloorLineEquation {
  Eigen::Vector2d n;
  double z_m = 0.0;
  double sigma_m = 0.0;
};
/// The equation of the pair (seg_a in view a, seg_b in view b) under `yaw_rad`; nullopt when
/// the pair is not usable.
std::optional<FloorLineEquation> floor_line_equation(const NormSegment& seg_a,
                                                     const NormSegment& seg_b, double yaw_rad,
                                                     const FloorCamera& camera,
                                                     const FloorLineOptions& options,
                                                     double yaw_sigma_rad = 0.0);

std::optional<FloorFix> estimate_floor_position(
    const std::vector<std::pair<NormSegment, NormSegment>>& pairs, const FloorCamera& camera,
    const FloorPrior& prior, const FloorLineOptions& options = {});

}  // namespace pepper::core::geometry
