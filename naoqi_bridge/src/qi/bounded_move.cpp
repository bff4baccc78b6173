// Constant-twist <-> relative-pose conversion for the bounded-horizon moveTo (see the header).
#include "naoqi_bridge/qi/bounded_move.hpp"

#include <cmath>
#include <stdexcept>

namespace pepper::naoqi_bridge::qi {

namespace {

// Below this turn angle the arc is a straight line to well under a micrometre at our speeds;
// the closed form would divide by ~0.
constexpr double kStraightRad = 1e-9;

void check(bool finite, double horizon_s, const char* what) {
  if (!finite) throw std::invalid_argument(std::string(what) + ": non-finite value");
  if (!(horizon_s > 0.0) || !std::isfinite(horizon_s)) {
    throw std::invalid_argument(std::string(what) + ": horizon must be > 0 s, got " +
                                std::to_string(horizon_s));
  }
}

}  // namespace

RelativePose pose_after(const core::BaseVelocity& v, double horizon_s) {
  check(std::isfinite(v.v_x_m_s) && std::isfinite(v.v_y_m_s) && std::isfinite(v.omega_rad_s),
        horizon_s, "pose_after");
  RelativePose p;
  p.theta_rad = v.omega_rad_s * horizon_s;
  if (std::fabs(p.theta_rad) < kStraightRad) {
    p.x_m = v.v_x_m_s * horizon_s;
    p.y_m = v.v_y_m_s * horizon_s;
    return p;
  }
  const double s = std::sin(p.theta_rad);
  const double c1 = 1.0 - std::cos(p.theta_rad);
  p.x_m = (v.v_x_m_s * s - v.v_y_m_s * c1) / v.omega_rad_s;
  p.y_m = (v.v_x_m_s * c1 + v.v_y_m_s * s) / v.omega_rad_s;
  return p;
}

core::BaseVelocity velocity_reaching(const RelativePose& p, double horizon_s) {
  check(std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad), horizon_s,
        "velocity_reaching");
  core::BaseVelocity v;
  v.omega_rad_s = p.theta_rad / horizon_s;
  if (std::fabs(p.theta_rad) < kStraightRad) {
    v.v_x_m_s = p.x_m / horizon_s;
    v.v_y_m_s = p.y_m / horizon_s;
    return v;
  }
  // Invert [[s, -c1], [c1, s]] / omega; its determinant is (s^2 + c1^2) / omega^2 > 0 for
  // 0 < |theta| < 2 pi.
  const double s = std::sin(p.theta_rad);
  const double c1 = 1.0 - std::cos(p.theta_rad);
  const double det = s * s + c1 * c1;
  v.v_x_m_s = v.omega_rad_s * (s * p.x_m + c1 * p.y_m) / det;
  v.v_y_m_s = v.omega_rad_s * (-c1 * p.x_m + s * p.y_m) / det;
  return v;
}

}  // namespace pepper::naoqi_bridge::qi
