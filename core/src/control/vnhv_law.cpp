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
  check(max_segment_turn_rad > 0.0, "max_segment_turn_rad", max_segment_turn_rad, "> 0");
  check(std::isfinite(max_arc_turn_rad) && max_arc_turn_rad >= 0.0, "max_arc_turn_rad",
        max_arc_turn_rad, ">= 0");
  check(std::isfinite(teach_speed_m_s) && teach_speed_m_s > 0.0, "teach_speed_m_s", teach_speed_m_s,
        "> 0");
  check(std::isfinite(straight_min_parallax_rad) && straight_min_parallax_rad > 0.0,
        "straight_min_parallax_rad", straight_min_parallax_rad, "> 0");
  check(straight_min_points >= 3, "straight_min_points", straight_min_points, ">= 3");
  check(std::isfinite(straight_min_length_m) && straight_min_length_m >= 0.0,
        "straight_min_length_m", straight_min_length_m, ">= 0");
  for (auto& e : pose.validate()) errors.push_back(std::move(e));
  for (auto& e : filter.validate()) errors.push_back(std::move(e));
  return errors;
}

std::optional<double> vnhv_omega(double v_m_s, double lateral_m, double heading_rad,
                                 const VnhvOptions& options, double curvature_1_m) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument("vnhv_omega: " + errors.front());
  }
  if (!std::isfinite(v_m_s) || !std::isfinite(lateral_m) || !std::isfinite(heading_rad) ||
      !std::isfinite(curvature_1_m)) {
    throw std::invalid_argument("vnhv_omega: non-finite input");
  }
  const double theta = wrap_angle_rad(heading_rad);
  if (std::abs(theta) >= options.max_abs_theta_rad) return std::nullopt;
  const double c = std::cos(theta);
  const double vc3 = v_m_s * c * c * c;
  const double law = -vc3 * options.kp_1_m2 * lateral_m - std::abs(vc3) * options.kd_1_m * std::tan(theta);
  if (curvature_1_m == 0.0) return law;
  const double along = 1.0 - curvature_1_m * lateral_m;
  if (!(along > 0.1)) return std::nullopt;
  return law + curvature_1_m * v_m_s * c / along;
}

}  // namespace pepper::core::control
