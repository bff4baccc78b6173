#include "core/control/vnhv_law.hpp"

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace pepper::core::control {

std::vector<std::string> VnhvOptions::validate() const {
  std::vector<std::string> errors;
  auto check = [&](bool ok, const char* name, double value, const char* range) {
    if (!ok) {
      std::ostringstream os;
      os << "control.vnhv." << name << " = " << value << " must be " << range;
      errors.push_back(os.str());
    }
  };
  check(std::isfinite(kp_1_m2) && kp_1_m2 > 0.0, "kp_1_m2", kp_1_m2, "> 0");
  check(std::isfinite(kd_1_m) && kd_1_m > 0.0, "kd_1_m", kd_1_m, "> 0");
  check(std::isfinite(max_abs_theta_rad) && max_abs_theta_rad > 0.0 &&
            max_abs_theta_rad < std::numbers::pi / 2.0,
        "max_abs_theta_rad", max_abs_theta_rad, "in (0, pi/2)");
  check(std::isfinite(nominal_distance_to_next_m) && nominal_distance_to_next_m > 0.0,
        "nominal_distance_to_next_m", nominal_distance_to_next_m, "> 0");
  return errors;
}

std::optional<double> vnhv_omega(double v_m_s, double lateral_m, double heading_rad,
                                 const VnhvOptions& options) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument("vnhv_omega: " + errors.front());
  }
  if (!std::isfinite(v_m_s) || !std::isfinite(lateral_m) || !std::isfinite(heading_rad)) {
    throw std::invalid_argument("vnhv_omega: non-finite input");
  }
  const double theta = wrap_angle_rad(heading_rad);
  if (std::abs(theta) >= options.max_abs_theta_rad) return std::nullopt;
  const double c = std::cos(theta);
  const double vc3 = v_m_s * c * c * c;
  return -vc3 * options.kp_1_m2 * lateral_m - std::abs(vc3) * options.kd_1_m * std::tan(theta);
}

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

std::optional<SegmentDeviation> deviation_from_segment(const PlanarPose& prev_in_next,
                                                       const PlanarPose& current_in_next,
                                                       double distance_to_next_m) {
  // Direction of travel: from prev towards next (the origin).
  const double dx = -prev_in_next.x_m;
  const double dy = -prev_in_next.y_m;
  const double seg_norm = std::hypot(dx, dy);
  double cx = current_in_next.x_m;
  double cy = current_in_next.y_m;
  const double cur_norm = std::hypot(cx, cy);
  constexpr double kTiny = 1e-12;
  if (seg_norm < kTiny || (distance_to_next_m > 0.0 && cur_norm < kTiny)) return std::nullopt;
  if (distance_to_next_m > 0.0) {
    cx *= distance_to_next_m / cur_norm;
    cy *= distance_to_next_m / cur_norm;
  }
  const double ux = dx / seg_norm;
  const double uy = dy / seg_norm;
  SegmentDeviation dev;
  // The line passes through the origin (IN) with direction u; left of it is positive.
  dev.lateral_m = ux * cy - uy * cx;
  dev.heading_rad = wrap_angle_rad(current_in_next.yaw_rad - std::atan2(uy, ux));
  return dev;
}

}  // namespace pepper::core::control
