#pragma once
// Poses in the floor plane and the deviation of a pose from a directed segment, the geometry of
// the VNHV controller (vnhv_law.hpp, segment_pose.hpp). Frames: docs/conventions.md.
// Pure functions, thread-safe.

#include <opencv2/core/matx.hpp>
#include <optional>

namespace pepper::core::control {

/// A pose in the floor plane: x forward, y left (base axes), yaw CCW from x.
struct PlanarPose {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

/// Planar pose of camera b in camera a's floor frame from the camera-frame transform T_a_b =
/// (R_a_b, t_a_b) (maps points in b to a; cam axes x right, y down, z forward). The yaw is taken
/// from the rotation about the camera's vertical axis, the position from (z, -x) of t_a_b.
PlanarPose planar_pose_from_camera(const cv::Matx33d& R_a_b, const cv::Vec3d& t_a_b);

/// Planar pose of camera C in camera R's floor frame from the planar motion X_C = R_y(yaw) X_R +
/// (t_x, 0, t_z) of planar_trifocal.hpp (R_y(a) = [[cos a, 0, sin a], [0, 1, 0], [-sin a, 0,
/// cos a]]): yaw is C's yaw (left turn > 0), the position -R_y(yaw)^T t read in R's floor frame.
PlanarPose planar_pose_from_motion(double yaw_rad, double t_x, double t_z);

/// Pose of R in C's floor frame from the pose of C in R's.
PlanarPose inverse(const PlanarPose& c_in_r);

struct SegmentDeviation {
  double lateral_m = 0.0;    ///< > 0 left of the line, seen along the direction of travel
  double heading_rad = 0.0;  ///< relative to the direction of travel, > 0 to the left, (-pi, pi]
};

/// Deviation of the current pose from the directed line prev -> next, all poses in IN's planar
/// frame (next is the origin) and in one length unit (the lateral offset is in that unit).
/// Returns nullopt when prev coincides with IN (no direction).
std::optional<SegmentDeviation> deviation_from_segment(const PlanarPose& prev_in_next,
                                                       const PlanarPose& current_in_next);

/// The taught path of a turning segment under the arc model (segment_pose.hpp): the circular
/// arc that leaves prev with prev's heading and ends at IN (the origin) heading along +x.
/// Curvature in 1/(length unit), > 0 for a left turn: kappa = -2 sin(yaw_prev / 2) / |prev|
/// (the centre is at (0, 1 / kappa)); 0 when prev coincides with IN.
double arc_curvature(const PlanarPose& prev_in_next);

/// Deviation of the current pose from that arc (lateral > 0 left of the arc seen along the
/// direction of travel, heading relative to the arc's tangent at the nearest point). Falls back
/// to deviation_from_segment when the arc is (almost) straight (|kappa| |prev| < 1e-6). Returns
/// nullopt when prev coincides with IN or the pose is at the arc's centre.
std::optional<SegmentDeviation> deviation_from_arc(const PlanarPose& prev_in_next,
                                                   const PlanarPose& current_in_next);

double wrap_angle_rad(double angle_rad);

}  // namespace pepper::core::control
