// Simulated wheel odometry with drift (see wheel_odometry.hpp).
#include "sim/wheel_odometry.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace pepper::sim {

namespace {

double wrap_angle(double a) {
  a = std::remainder(a, 2.0 * M_PI);
  return a <= -M_PI ? a + 2.0 * M_PI : a;
}

}  // namespace

std::vector<std::string> WheelOdometryOptions::validate() const {
  std::vector<std::string> errors;
  auto check = [&](const char* name, double v, double lo, double hi) {
    if (!(std::isfinite(v) && v >= lo && v <= hi)) {
      std::ostringstream os;
      os << name << " = " << v << " must be in [" << lo << ", " << hi << "]";
      errors.push_back(os.str());
    }
  };
  // Beyond these a "robot" would not be a robot whose odometry anyone uses.
  check("distance_scale_error", distance_scale_error, -0.2, 0.2);
  check("yaw_scale_error", yaw_scale_error, -0.2, 0.2);
  check("yaw_bias_rad_s", yaw_bias_rad_s, -0.1, 0.1);
  check("noise_distance_rel", noise_distance_rel, 0.0, 0.5);
  check("noise_yaw_rad_sqrt_s", noise_yaw_rad_sqrt_s, 0.0, 0.5);
  return errors;
}

WheelOdometry::WheelOdometry(WheelOdometryOptions options) : options_(options) {
  const auto errors = options_.validate();
  if (!errors.empty()) throw std::invalid_argument("WheelOdometryOptions: " + errors.front());
  rng_state_ = options_.seed * 0xD1B54A32D192ED03ULL + 0x7F4A7C15ULL;
}

double WheelOdometry::gaussian() {
  // splitmix64 -> two uniforms -> Box-Muller (one of the pair is enough here).
  auto uniform = [this] {
    uint64_t z = (rng_state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return (static_cast<double>(z >> 11) + 0.5) * 0x1.0p-53;
  };
  const double r = std::sqrt(-2.0 * std::log(uniform()));
  return r * std::cos(2.0 * M_PI * uniform());
}

void WheelOdometry::on_step(const Pose2D& before, const Pose2D& after, double dt_s) {
  if (!(dt_s >= 0.0 && std::isfinite(dt_s))) {
    throw std::invalid_argument("WheelOdometry::on_step: dt_s must be finite and >= 0");
  }
  // The true motion in the base frame at `before`.
  const double dxw = after.x_m - before.x_m, dyw = after.y_m - before.y_m;
  const double c = std::cos(before.yaw_rad), s = std::sin(before.yaw_rad);
  double dx = c * dxw + s * dyw;
  double dy = -s * dxw + c * dyw;
  double dyaw = wrap_angle(after.yaw_rad - before.yaw_rad);
  const bool moving = dx != 0.0 || dy != 0.0 || dyaw != 0.0;
  if (!moving) return;  // wheels at rest: no reading changes, no drift
  const double k_distance =
      (1.0 + options_.distance_scale_error) * (1.0 + options_.noise_distance_rel * gaussian());
  dx *= k_distance;
  dy *= k_distance;
  dyaw = dyaw * (1.0 + options_.yaw_scale_error) + options_.yaw_bias_rad_s * dt_s +
         options_.noise_yaw_rad_sqrt_s * std::sqrt(dt_s) * gaussian();
  // The step's translation, measured in the base frame, is laid down along the odometry's own
  // heading: that is how a heading error turns into a lateral drift.
  const double co = std::cos(yaw_rad_), so = std::sin(yaw_rad_);
  x_m_ += co * dx - so * dy;
  y_m_ += so * dx + co * dy;
  yaw_rad_ += dyaw;
}

core::OdometryPose WheelOdometry::pose() const { return {x_m_, y_m_, wrap_angle(yaw_rad_)}; }

}  // namespace pepper::sim
