// Scripted teach drive on ground truth (see teach_driver.hpp).
#include "sim/teach_driver.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pepper::sim {

std::vector<std::string> TeachDriverOptions::validate() const {
  std::vector<std::string> errors;
  if (!(lookahead_m > 0.05 && lookahead_m < 5.0))
    errors.push_back("lookahead_m must be in (0.05, 5) m");
  if (!(max_omega_rad_s > 0.0)) errors.push_back("max_omega_rad_s must be > 0");
  if (!(turn_in_place_rad > 0.0)) errors.push_back("turn_in_place_rad must be > 0");
  if (!(goal_tolerance_m > 0.0)) errors.push_back("goal_tolerance_m must be > 0");
  return errors;
}

TeachDriver::TeachDriver(const Scenario& scenario, TeachDriverOptions options)
    : scenario_(scenario), options_(options) {
  const auto errors = options_.validate();
  if (!errors.empty()) throw std::invalid_argument("TeachDriverOptions: " + errors.front());
  if (scenario_.waypoints_m.size() < 2 && scenario_.velocity_script.empty())
    throw std::invalid_argument("TeachDriver: the scenario has neither waypoints nor a script");
  cum_m_.push_back(0.0);
  for (size_t i = 1; i < scenario_.waypoints_m.size(); ++i)
    cum_m_.push_back(cum_m_.back() +
                     (scenario_.waypoints_m[i] - scenario_.waypoints_m[i - 1]).norm());
}

core::BaseVelocity TeachDriver::command(const Pose2D& pose, double t_s) {
  if (done_) return {};
  if (scenario_.waypoints_m.size() < 2) {
    double t0 = 0.0;
    for (const VelocityStep& s : scenario_.velocity_script) {
      if (t_s < t0 + s.duration_s) return {s.v_x_m_s, 0.0, s.omega_rad_s};
      t0 += s.duration_s;
    }
    done_ = true;
    return {};
  }
  const auto& w = scenario_.waypoints_m;
  const Eigen::Vector2d p(pose.x_m, pose.y_m);
  auto point_at = [&](double s) {
    s = std::clamp(s, 0.0, cum_m_.back());
    size_t i = 1;
    while (i + 1 < cum_m_.size() && cum_m_[i] < s) ++i;
    const double seg = cum_m_[i] - cum_m_[i - 1];
    const double f = seg > 0 ? (s - cum_m_[i - 1]) / seg : 0.0;
    return Eigen::Vector2d(w[i - 1] + f * (w[i] - w[i - 1]));
  };
  // Progress: closest point of the path within a window ahead of the current progress (never
  // jumps back, never skips a corner).
  double best_s = progress_m_, best_d = (point_at(progress_m_) - p).norm();
  for (double s = progress_m_; s <= std::min(cum_m_.back(), progress_m_ + 1.0); s += 0.01) {
    const double d = (point_at(s) - p).norm();
    if (d < best_d) {
      best_d = d;
      best_s = s;
    }
  }
  progress_m_ = best_s;
  const Eigen::Vector2d goal = w.back();
  if ((goal - p).norm() < options_.goal_tolerance_m ||
      (progress_m_ >= cum_m_.back() - 1e-6 && (goal - p).norm() < 2 * options_.goal_tolerance_m)) {
    done_ = true;
    return {};
  }
  const Eigen::Vector2d target = point_at(progress_m_ + options_.lookahead_m);
  const Eigen::Vector2d d = target - p;
  const double c = std::cos(pose.yaw_rad), s = std::sin(pose.yaw_rad);
  const double x_r = c * d.x() + s * d.y();
  const double y_r = -s * d.x() + c * d.y();
  const double heading_err = std::atan2(y_r, x_r);
  if (std::abs(heading_err) > options_.turn_in_place_rad)
    return {0.0, 0.0, std::copysign(options_.max_omega_rad_s, heading_err)};
  const double L2 = std::max(1e-6, x_r * x_r + y_r * y_r);
  const double curvature = 2.0 * y_r / L2;
  double v = scenario_.teach_speed_m_s;
  // Slow down near the goal.
  v = std::min(v, std::max(0.05, 0.8 * (goal - p).norm()));
  double omega = v * curvature;
  if (std::abs(omega) > options_.max_omega_rad_s) {
    omega = std::copysign(options_.max_omega_rad_s, omega);
    v = options_.max_omega_rad_s / std::abs(curvature);
  }
  return {v, 0.0, omega};
}

}  // namespace pepper::sim
