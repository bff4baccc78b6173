#include "core/control/velocity_schedule.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace pepper::core::control {

std::vector<std::string> VelocityScheduleOptions::validate() const {
  std::vector<std::string> errors;
  auto check = [&](bool ok, const char* name, double value, const char* range) {
    if (!ok) {
      std::ostringstream os;
      os << "control.schedule." << name << " = " << value << " must be " << range;
      errors.push_back(os.str());
    }
  };
  auto fin = [](double v) { return std::isfinite(v); };
  check(fin(v_straight_m_s) && v_straight_m_s >= 0.0, "v_straight_m_s", v_straight_m_s, ">= 0");
  check(fin(v_turn_m_s) && v_turn_m_s >= 0.0 && v_turn_m_s <= v_straight_m_s, "v_turn_m_s",
        v_turn_m_s, "in [0, v_straight_m_s]");
  check(fin(turn_exit_rad_s) && turn_exit_rad_s >= 0.0, "turn_exit_rad_s", turn_exit_rad_s, ">= 0");
  check(fin(turn_enter_rad_s) && turn_enter_rad_s > turn_exit_rad_s, "turn_enter_rad_s",
        turn_enter_rad_s, "> turn_exit_rad_s");
  check(fin(turn_exit_hold_s) && turn_exit_hold_s >= 0.0, "turn_exit_hold_s", turn_exit_hold_s,
        ">= 0");
  check(fin(max_omega_rad_s) && max_omega_rad_s > 0.0, "max_omega_rad_s", max_omega_rad_s, "> 0");
  check(fin(max_omega_accel_rad_s2) && max_omega_accel_rad_s2 > 0.0, "max_omega_accel_rad_s2",
        max_omega_accel_rad_s2, "> 0");
  check(fin(first_step_dt_s) && first_step_dt_s > 0.0, "first_step_dt_s", first_step_dt_s, "> 0");
  return errors;
}

bool next_turning_state(bool turning, double omega_rad_s, const VelocityScheduleOptions& options) {
  const double magnitude = std::abs(omega_rad_s);
  if (turning) return magnitude > options.turn_exit_rad_s;
  return magnitude >= options.turn_enter_rad_s;
}

VelocitySchedule::VelocitySchedule(const VelocityScheduleOptions& options) : options_(options) {
  if (const auto errors = options_.validate(); !errors.empty()) {
    throw std::invalid_argument("VelocitySchedule: " + errors.front());
  }
}

void VelocitySchedule::reset() {
  turning_ = false;
  calm_since_ns_.reset();
  last_omega_rad_s_ = 0.0;
  last_t_ns_.reset();
}

BaseCommand VelocitySchedule::step(double omega_demand_rad_s, int64_t t_ns) {
  if (!std::isfinite(omega_demand_rad_s)) {
    throw std::invalid_argument("VelocitySchedule::step: omega demand is not finite");
  }
  double dt_s = options_.first_step_dt_s;
  if (last_t_ns_) {
    if (t_ns < *last_t_ns_) {
      std::ostringstream os;
      os << "VelocitySchedule::step: t_ns " << t_ns << " is before the previous " << *last_t_ns_;
      throw std::invalid_argument(os.str());
    }
    dt_s = static_cast<double>(t_ns - *last_t_ns_) * 1e-9;
  }
  double omega =
      std::clamp(omega_demand_rad_s, -options_.max_omega_rad_s, options_.max_omega_rad_s);
  const double max_change = options_.max_omega_accel_rad_s2 * dt_s;
  omega = std::clamp(omega, last_omega_rad_s_ - max_change, last_omega_rad_s_ + max_change);
  const bool turning = next_turning_state(turning_, omega, options_);
  if (turning_ && !turning && options_.turn_exit_hold_s > 0.0) {
    // A turn's demand dips between key images: stay slow until it has been calm for a while.
    if (!calm_since_ns_) calm_since_ns_ = t_ns;
    turning_ = static_cast<double>(t_ns - *calm_since_ns_) * 1e-9 < options_.turn_exit_hold_s;
  } else {
    turning_ = turning;
  }
  if (!turning_ || turning) calm_since_ns_.reset();
  last_omega_rad_s_ = omega;
  last_t_ns_ = t_ns;
  BaseCommand cmd;
  cmd.omega_rad_s = omega;
  cmd.turning = turning_;
  cmd.v_m_s = turning_ ? options_.v_turn_m_s : options_.v_straight_m_s;
  return cmd;
}

}  // namespace pepper::core::control
