#pragma once
// Relative yaw of two views from matched line segments of horizontal 3D lines (issue 29: the
// heading through feature-poor stretches, where the view keeps a skirting board, a door's lintel
// or the edges of floor and ceiling tiles and no trackable point).
//
// Model (docs/conventions.md; planar_trifocal.hpp): the camera moves on the floor plane, pitched
// by `pitch_rad` (> 0 looks down) about its x axis, x_level = R_x(-pitch) x_cam. In the level
// frame view b sees directions d_b = R_y(yaw) d_a, with yaw the yaw of b in a's floor frame
// (counter-clockwise seen from above, as control::PlanarPose) and
// R_y(a) = [[cos a, 0, sin a], [0, 1, 0], [-sin a, 0, cos a]].
//
// A segment in view a spans, with the camera centre, a plane of normal n_a (the cross product of
// its endpoints' rays). If the 3D line is horizontal its direction is the horizontal direction in
// that plane, d_a = n_a x (0, 1, 0). The same line seen in b lies in the plane of normal n_b, so
//   n_b . R_y(yaw) d_a = 0,
// one equation in yaw per line, whatever the translation between the views (the vanishing point
// of a direction depends on the rotation only). It has two roots yaw and yaw + pi; the one with
// |yaw| < pi / 2 is taken (a key image and the current view face the same way). A vertical 3D
// line's plane contains the vertical, so its n_a has no vertical component and it says nothing
// about yaw: segments whose normals are within `min_leverage` of horizontal are skipped, in both
// views. A line that is neither horizontal nor vertical (a staircase rail) gives a wrong root and
// is an outlier like a mismatch.
//
// Estimation, maximum likelihood on f_i(yaw) = n_b . R_y(yaw) d_a (unit vectors): a line's noise
// sigma_i is the endpoint noise over the segment's length in each view plus the base's sway, its
// information f_i'(yaw)^2 / sigma_i^2. Every usable match proposes its root; the proposal whose
// agreeing matches (|f_i| within gate_sigmas sigma_i) carry the most information wins (a wall
// seen face-on has f_i' near zero: it agrees with almost any yaw and must not outvote the lines
// that pin it; counting lines did, on Pepper's key images), then weighted Gauss-Newton on its
// agreeing matches. The estimate's sigma is 1 / sqrt(their information); above max_sigma_rad
// there is no estimate. Reported residual of a match (rms_residual_rad, line_yaw_residual_rad):
// the dihedral angle between b's plane and the plane through the camera centre, b's midpoint and
// the predicted vanishing point R_y(yaw) d_a, about the image angle between the segment and the
// direction from its midpoint to that point (defined when the vanishing point is at infinity).
// Deterministic, pure; too few usable or agreeing matches: nullopt.

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/geometry/planar_trifocal.hpp"  // NormSegment

namespace pepper::core::geometry {

struct LineYawOptions {
  /// A segment's plane normal needs at least this vertical component (unit normal, both views):
  /// below, the line is (nearly) vertical and leaves the yaw free. (0, 1).
  double min_leverage = 0.2;
  /// A segment's noise across its line at each end, normalised units (px / focal), > 0: a plane
  /// normal errs by about this over the segment's normalised length (EDLines fits its line to
  /// every edge pixel: ~0.3 px at QVGA).
  double endpoint_sigma = 0.001;
  /// The base's sway between the views (roll and pitch), rad, >= 0: added to every line's noise.
  double sway_sigma_rad = 0.006;
  /// A line agrees with a yaw when its equation's value is within this many of its sigmas, > 0.
  double gate_sigmas = 3.0;
  /// Agreeing matches needed for an estimate, >= 1.
  int min_inliers = 2;
  /// No estimate when its sigma is above this (rad, > 0): face-on walls only, or too few lines.
  double max_sigma_rad = 0.02;
  std::vector<std::string> validate() const;
};

struct LineYaw {
  double yaw_rad = 0.0;      ///< yaw of view b in view a's floor frame (CCW), |yaw| < pi / 2
  int inliers = 0;           ///< matches within max_residual_rad of it
  int usable = 0;            ///< matches with leverage in both views
  double rms_residual_rad = 0.0;
  /// 1 / sqrt(the inliers' information), rad.
  double sigma_rad = 0.0;
};

/// Residual (rad) of the segment pair (seg_a in view a, seg_b in view b) under `yaw_rad`; pi / 2
/// for an unusable pair. Exposed for tests.
double line_yaw_residual_rad(const NormSegment& seg_a, const NormSegment& seg_b, double yaw_rad,
                             double pitch_rad);

/// What odometry predicts for the yaw (rad) and its sigma (rad, > 0).
struct YawPrior {
  double yaw_rad = 0.0;
  double sigma_rad = 1.0;
};
/// pairs: (segment in view a, segment in view b), normalised coordinates. With a prior, only the
/// proposals within gate_sigmas of its sigma compete:
/// a moved shelf's boards are as straight and horizontal as the room's skirting, and when they
/// outnumber it their consensus is the largest (room_corridor_room, furniture; the resection's
/// PosePrior in control/segment_pose.hpp is the same idea). Throws std::invalid_argument for
/// invalid options, a non-finite pitch or a prior whose sigma is not > 0.
std::optional<LineYaw> estimate_line_yaw(const std::vector<std::pair<NormSegment, NormSegment>>& pairs,
                                         double pitch_rad, const LineYawOptions& options = {},
                                         const YawPrior* prior = nullptr);

}  // namespace pepper::core::geometry
