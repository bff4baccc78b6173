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
// Deviations come from planar two-view geometry: the relative poses (rotation, translation
// direction) of IP and of the current image with respect to IN, e.g. from the essential matrices
// E(IP, IN) and E(Ia, IN). Two-view translations have no scale, so the distance from the current
// image to IN is a parameter (nominal_distance_to_next_m); theta needs no scale.
//
// Pure functions, thread-safe. vnhv_omega returns nullopt when |theta| >= max_abs_theta_rad (the
// chained form is singular at pi/2): the navigator then falls back to stopping.

#include <opencv2/core/matx.hpp>
#include <optional>
#include <string>
#include <vector>

namespace pepper::core::control {

struct VnhvOptions {
  double kp_1_m2 = 4.0;  ///< Kp, 1/m^2, > 0: natural "frequency" in distance sqrt(Kp) = 2 /m
  double kd_1_m = 4.0;   ///< Kd, 1/m, > 0: 2 sqrt(Kp) = critically damped (settles in ~2.4 m)
  double max_abs_theta_rad = 1.2;           ///< validity bound on |theta|, in (0, pi/2)
  double nominal_distance_to_next_m = 0.5;  ///< scale of the current-to-IN translation, > 0

  std::vector<std::string> validate() const;
};

/// The law above. Throws std::invalid_argument for invalid options or non-finite inputs.
std::optional<double> vnhv_omega(double v_m_s, double lateral_m, double heading_rad,
                                 const VnhvOptions& options);

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

struct SegmentDeviation {
  double lateral_m = 0.0;    ///< y above
  double heading_rad = 0.0;  ///< theta above, wrapped to (-pi, pi]
};

/// Deviation of the current pose from the directed line prev -> next, all poses in IN's planar
/// frame (next is the origin). prev and current positions may have any scale: only the direction
/// of prev matters, current is rescaled so that its distance to IN is distance_to_next_m (pass a
/// non-positive value to keep the given scale). Returns nullopt when prev or current coincides
/// with IN (no direction).
std::optional<SegmentDeviation> deviation_from_segment(const PlanarPose& prev_in_next,
                                                       const PlanarPose& current_in_next,
                                                       double distance_to_next_m);

double wrap_angle_rad(double angle_rad);

}  // namespace pepper::core::control
