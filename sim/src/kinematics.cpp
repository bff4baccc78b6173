// Simulated Pepper base (see kinematics.hpp).
#include "sim/kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace pepper::sim {

namespace {

double wrap_angle(double a) {
  a = std::remainder(a, 2.0 * M_PI);
  return a <= -M_PI ? a + 2.0 * M_PI : a;
}

// Moves `current` towards `target` by at most max_step (as a vector for xy).
double approach(double current, double target, double max_step) {
  const double d = target - current;
  return std::abs(d) <= max_step ? target : current + std::copysign(max_step, d);
}

}  // namespace

std::vector<std::string> KinematicsOptions::validate() const {
  std::vector<std::string> errors;
  auto check = [&](const char* name, double v, bool ok, const char* range) {
    if (!ok || !std::isfinite(v)) {
      std::ostringstream os;
      os << name << " = " << v << " must be " << range;
      errors.push_back(os.str());
    }
  };
  check("max_v_xy_m_s", max_v_xy_m_s, max_v_xy_m_s > 0, "> 0");
  check("max_omega_rad_s", max_omega_rad_s, max_omega_rad_s > 0, "> 0");
  check("max_acc_xy_m_s2", max_acc_xy_m_s2, max_acc_xy_m_s2 > 0, "> 0");
  check("max_acc_theta_rad_s2", max_acc_theta_rad_s2, max_acc_theta_rad_s2 > 0, "> 0");
  check("latency_s", latency_s, latency_s >= 0 && latency_s <= 5.0, "in [0, 5] s");
  check("step_s", step_s, step_s >= 1e-4 && step_s <= 0.1, "in [1e-4, 0.1] s");
  check("noise_rel", noise_rel, noise_rel >= 0 && noise_rel <= 0.5, "in [0, 0.5]");
  check("noise_v_m_s", noise_v_m_s, noise_v_m_s >= 0 && noise_v_m_s <= 0.5, "in [0, 0.5] m/s");
  check("noise_omega_rad_s", noise_omega_rad_s, noise_omega_rad_s >= 0 && noise_omega_rad_s <= 1,
        "in [0, 1] rad/s");
  return errors;
}

Pose2D integrate_constant(const Pose2D& start, const core::BaseVelocity& v, double dt_s) {
  const double w = v.omega_rad_s;
  const double a = w * dt_s;
  double dx, dy;  // displacement in the start's robot frame
  if (std::abs(a) < 1e-9) {
    dx = v.v_x_m_s * dt_s - 0.5 * v.v_y_m_s * w * dt_s * dt_s;
    dy = v.v_y_m_s * dt_s + 0.5 * v.v_x_m_s * w * dt_s * dt_s;
  } else {
    const double s = std::sin(a), c = std::cos(a);
    dx = (v.v_x_m_s * s + v.v_y_m_s * (c - 1.0)) / w;
    dy = (v.v_x_m_s * (1.0 - c) + v.v_y_m_s * s) / w;
  }
  const double cy = std::cos(start.yaw_rad), sy = std::sin(start.yaw_rad);
  return {start.x_m + cy * dx - sy * dy, start.y_m + sy * dx + cy * dy,
          wrap_angle(start.yaw_rad + a)};
}

BaseKinematics::BaseKinematics(KinematicsOptions options) : options_(options) {
  const auto errors = options_.validate();
  if (!errors.empty()) throw std::invalid_argument("KinematicsOptions: " + errors.front());
  rng_state_ = options_.seed * 0x9E3779B97F4A7C15ULL + 0x1234567ULL;
}

void BaseKinematics::reset(const Pose2D& pose, int64_t t_ns) {
  pose_ = pose;
  pose_.yaw_rad = wrap_angle(pose.yaw_rad);
  velocity_ = {};
  target_ = {};
  pending_.clear();
  t_ns_ = t_ns;
  next_control_ns_ = t_ns;
}

core::BaseVelocity BaseKinematics::clamp(const core::BaseVelocity& v) const {
  core::BaseVelocity c = v;
  auto finite = [](double x) { return std::isfinite(x) ? x : 0.0; };
  c.v_x_m_s = finite(c.v_x_m_s);
  c.v_y_m_s = finite(c.v_y_m_s);
  c.omega_rad_s = finite(c.omega_rad_s);
  const double n = std::hypot(c.v_x_m_s, c.v_y_m_s);
  if (n > options_.max_v_xy_m_s) {
    c.v_x_m_s *= options_.max_v_xy_m_s / n;
    c.v_y_m_s *= options_.max_v_xy_m_s / n;
  }
  c.omega_rad_s = std::clamp(c.omega_rad_s, -options_.max_omega_rad_s, options_.max_omega_rad_s);
  return c;
}

void BaseKinematics::command(const core::BaseVelocity& velocity, int64_t t_ns) {
  const int64_t at =
      std::max(t_ns, t_ns_) + static_cast<int64_t>(std::llround(options_.latency_s * 1e9));
  // Commands keep their order; a later command never takes effect before an earlier one.
  const int64_t effective = pending_.empty() ? at : std::max(at, pending_.back().effective_ns);
  pending_.push_back({effective, clamp(velocity)});
}

void BaseKinematics::halt() {
  velocity_ = {};
  target_ = {};
  pending_.clear();
}

double BaseKinematics::gaussian() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  auto next = [this] {
    uint64_t z = (rng_state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return (static_cast<double>(z >> 11) + 0.5) * 0x1.0p-53;
  };
  const double r = std::sqrt(-2.0 * std::log(next()));
  const double t = 2.0 * M_PI * next();
  spare_ = r * std::sin(t);
  has_spare_ = true;
  return r * std::cos(t);
}

bool BaseKinematics::advance_to(int64_t t_end_ns,
                                const std::function<bool(const Pose2D&, int64_t)>& blocked,
                                const std::function<void(const BaseStep&)>& on_step) {
  const int64_t step_ns = std::max<int64_t>(1, std::llround(options_.step_s * 1e9));
  const bool noisy =
      options_.noise_rel > 0 || options_.noise_v_m_s > 0 || options_.noise_omega_rad_s > 0;
  while (t_ns_ < t_end_ns) {
    // Commands that have become effective.
    while (!pending_.empty() && pending_.front().effective_ns <= t_ns_) {
      target_ = pending_.front().velocity;
      pending_.pop_front();
    }
    // Control update at the 50 Hz ticks: approach the target within the acceleration limits.
    if (t_ns_ >= next_control_ns_) {
      const double dt = options_.step_s;
      const double dvx = target_.v_x_m_s - velocity_.v_x_m_s;
      const double dvy = target_.v_y_m_s - velocity_.v_y_m_s;
      const double dv = std::hypot(dvx, dvy);
      const double max_dv = options_.max_acc_xy_m_s2 * dt;
      if (dv <= max_dv) {
        velocity_.v_x_m_s = target_.v_x_m_s;
        velocity_.v_y_m_s = target_.v_y_m_s;
      } else {
        velocity_.v_x_m_s += dvx * max_dv / dv;
        velocity_.v_y_m_s += dvy * max_dv / dv;
      }
      velocity_.omega_rad_s =
          approach(velocity_.omega_rad_s, target_.omega_rad_s, options_.max_acc_theta_rad_s2 * dt);
      next_control_ns_ = t_ns_ + step_ns;
    }
    int64_t t_next = std::min(t_end_ns, next_control_ns_);
    if (!pending_.empty())
      t_next = std::min(t_next, std::max(t_ns_ + 1, pending_.front().effective_ns));
    if (!pending_.empty() && pending_.front().effective_ns < next_control_ns_ &&
        pending_.front().effective_ns > t_ns_) {
      // A command lands mid-period: it is picked up at the next control tick by design, but we
      // split here so that the tick is re-evaluated when it lands (50 Hz ALMotion reacts
      // within one period; we react at once for exact latency).
      next_control_ns_ = pending_.front().effective_ns;
      t_next = std::min(t_next, next_control_ns_);
    }
    core::BaseVelocity v = velocity_;
    if (noisy) {
      const double k = 1.0 + options_.noise_rel * gaussian();
      v.v_x_m_s = v.v_x_m_s * k + options_.noise_v_m_s * gaussian();
      v.v_y_m_s = v.v_y_m_s * k + options_.noise_v_m_s * gaussian();
      v.omega_rad_s = v.omega_rad_s * k + options_.noise_omega_rad_s * gaussian();
      // No noise at rest: a stopped base does not creep.
      if (velocity_.v_x_m_s == 0 && velocity_.v_y_m_s == 0 && velocity_.omega_rad_s == 0) v = {};
    }
    const Pose2D before = pose_;
    const double dt_s = static_cast<double>(t_next - t_ns_) * 1e-9;
    pose_ = integrate_constant(pose_, v, dt_s);
    t_ns_ = t_next;
    if (blocked && blocked(pose_, t_ns_)) {
      pose_ = before;
      halt();
      t_ns_ = t_end_ns;
      return false;
    }
    if (on_step) on_step({before, pose_, velocity_, dt_s});
  }
  return true;
}

}  // namespace pepper::sim
