#include "core/control/planar_pose.hpp"

#include <cmath>
#include <numbers>

namespace pepper::core::control {

double wrap_angle_rad(double angle_rad) {
  double a = std::remainder(angle_rad, 2.0 * std::numbers::pi);  // in [-pi, pi]
  if (a <= -std::numbers::pi) a += 2.0 * std::numbers::pi;
  return a;
}

PlanarPose planar_pose_from_camera(const cv::Matx33d& R_a_b, const cv::Vec3d& t_a_b) {
  // b's forward axis (cam z) expressed in a: third column of R_a_b. In a's floor frame
  // (forward = cam z, left = -cam x) its yaw is atan2(-r02, r22).
  PlanarPose pose;
  pose.yaw_rad = std::atan2(-R_a_b(0, 2), R_a_b(2, 2));
  pose.x_m = t_a_b[2];
  pose.y_m = -t_a_b[0];
  return pose;
}

PlanarPose planar_pose_from_motion(double yaw_rad, double t_x, double t_z) {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  return {-s * t_x - c * t_z, c * t_x - s * t_z, wrap_angle_rad(yaw_rad)};
}

PlanarPose inverse(const PlanarPose& c_in_r) {
  const double c = std::cos(c_in_r.yaw_rad), s = std::sin(c_in_r.yaw_rad);
  return {-(c * c_in_r.x_m + s * c_in_r.y_m), s * c_in_r.x_m - c * c_in_r.y_m,
          wrap_angle_rad(-c_in_r.yaw_rad)};
}

std::optional<SegmentDeviation> deviation_from_segment(const PlanarPose& prev_in_next,
                                                       const PlanarPose& current_in_next) {
  // Direction of travel: from prev towards next (the origin).
  const double dx = -prev_in_next.x_m;
  const double dy = -prev_in_next.y_m;
  const double seg_norm = std::hypot(dx, dy);
  if (!(seg_norm > 1e-12)) return std::nullopt;
  const double ux = dx / seg_norm;
  const double uy = dy / seg_norm;
  SegmentDeviation dev;
  // The line passes through the origin (IN) with direction u; left of it is positive.
  dev.lateral_m = ux * current_in_next.y_m - uy * current_in_next.x_m;
  dev.heading_rad = wrap_angle_rad(current_in_next.yaw_rad - std::atan2(uy, ux));
  return dev;
}

double arc_curvature(const PlanarPose& prev_in_next) {
  const double chord = std::hypot(prev_in_next.x_m, prev_in_next.y_m);
  if (!(chord > 1e-12)) return 0.0;
  return -2.0 * std::sin(0.5 * prev_in_next.yaw_rad) / chord;
}

std::optional<SegmentDeviation> deviation_from_arc(const PlanarPose& prev_in_next,
                                                   const PlanarPose& current_in_next) {
  const double chord = std::hypot(prev_in_next.x_m, prev_in_next.y_m);
  if (!(chord > 1e-12)) return std::nullopt;
  const double kappa = arc_curvature(prev_in_next);
  if (!(std::abs(kappa) * chord >= 1e-6)) return deviation_from_segment(prev_in_next, current_in_next);
  // Centre (0, 1/kappa); the arc runs counter-clockwise about it for kappa > 0.
  const double cy = 1.0 / kappa;
  const double rx = current_in_next.x_m, ry = current_in_next.y_m - cy;
  const double d = std::hypot(rx, ry);
  if (!(d > 1e-12)) return std::nullopt;
  const double sign = kappa > 0.0 ? 1.0 : -1.0;
  SegmentDeviation dev;
  dev.lateral_m = cy - sign * d;  // inside the turn is left for kappa > 0, right otherwise
  const double tangent = std::atan2(ry, rx) + sign * 0.5 * std::numbers::pi;
  dev.heading_rad = wrap_angle_rad(current_in_next.yaw_rad - tangent);
  return dev;
}

}  // namespace pepper::core::control
