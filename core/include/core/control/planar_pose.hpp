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

double wrap_angle_rad(double angle_rad);

}  // namespace pepper::core::control
