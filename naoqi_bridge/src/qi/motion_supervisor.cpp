// MotionSupervisor: move-failure and head-lock decisions (see the header).
#include "naoqi_bridge/qi/motion_supervisor.hpp"

#include <cmath>
#include <cstdio>

namespace pepper::naoqi_bridge::qi {

namespace {

bool is_zero(const BaseVelocity& v) {
  return v.v_x_m_s == 0.0 && v.v_y_m_s == 0.0 && v.omega_rad_s == 0.0;
}

std::string f2(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

// Below these a commanded component is too small to judge from a read-back.
constexpr double kMinSpeedMS = 0.02;
constexpr double kMinTurnRadS = 0.05;

}  // namespace

void MotionSupervisor::on_command(const BaseVelocity& velocity, std::int64_t t_ns) {
  if (is_zero(velocity)) {
    command_since_ns_ = -1;
  } else if (command_since_ns_ < 0 || t_ns - last_command_ns_ > options_.command_fresh_ns) {
    // A start, or a resume after a gap (a frozen app): the robot-side horizon may have stopped
    // the base meanwhile, so it ramps up again and gets `move_settle` before being judged.
    command_since_ns_ = t_ns;
  }
  command_ = velocity;
  last_command_ns_ = t_ns;
}

MotionSupervisor::CommandSnapshot MotionSupervisor::snapshot(std::int64_t t_ns) const {
  CommandSnapshot s;
  s.velocity = command_;
  s.counts = command_since_ns_ >= 0 && t_ns - command_since_ns_ >= options_.move_settle_ns &&
             t_ns - last_command_ns_ <= options_.command_fresh_ns;
  return s;
}

std::optional<std::string> MotionSupervisor::on_motion_readback(const CommandSnapshot& command,
                                                                const BaseVelocity& measured,
                                                                std::optional<bool> move_active) {
  const double cmd_speed = std::hypot(command.velocity.v_x_m_s, command.velocity.v_y_m_s);
  const double cmd_turn = std::abs(command.velocity.omega_rad_s);
  const double speed = std::hypot(measured.v_x_m_s, measured.v_y_m_s);
  const double turn = std::abs(measured.omega_rad_s);
  const bool judged = command.counts && (cmd_speed >= kMinSpeedMS || cmd_turn >= kMinTurnRadS);
  if (!judged) {
    // No verdict on this read-back; a stop (or no command) ends a failure episode quietly.
    if (!command.counts && is_zero(command.velocity)) {
      disagreeing_ = 0;
      failing_ = false;
    }
    return std::nullopt;
  }
  bool executed = !(move_active.has_value() && !*move_active);
  if (executed) {
    const bool speed_ok =
        cmd_speed < kMinSpeedMS || speed >= options_.executed_fraction * cmd_speed;
    const bool turn_ok = cmd_turn < kMinTurnRadS || turn >= options_.executed_fraction * cmd_turn;
    executed = speed_ok && turn_ok;
  }
  if (executed) {
    disagreeing_ = 0;
    if (failing_) {
      failing_ = false;
      return std::string("the robot executes the commanded moves again");
    }
    return std::nullopt;
  }
  ++disagreeing_;
  if (failing_ || disagreeing_ < options_.failing_probes) return std::nullopt;
  failing_ = true;
  std::string active = move_active ? (*move_active ? "true" : "false") : "unknown";
  return "move failed: the robot does not execute the commanded velocity (commanded " +
         f2(cmd_speed) + " m/s, " + f2(command.velocity.omega_rad_s) + " rad/s; robot reports " +
         f2(speed) + " m/s, " + f2(measured.omega_rad_s) + " rad/s, moveIsActive " + active +
         "): an obstacle within the external collision protection distance, the charging hatch "
         "open, or the robot resting";
}

MotionSupervisor::HeadVerdict MotionSupervisor::on_head_readback(const HeadReadback& r,
                                                                 bool expect_life_disabled,
                                                                 bool expect_awareness_off,
                                                                 double tolerance_rad,
                                                                 std::string& detail) {
  detail.clear();
  auto add = [&](const std::string& what) { detail += (detail.empty() ? "" : ", ") + what; };
  if (expect_life_disabled && r.life_state && *r.life_state != "disabled") {
    add("Autonomous Life is '" + *r.life_state + "' again");
  }
  if (expect_awareness_off && r.awareness_enabled && *r.awareness_enabled) {
    add("ALBasicAwareness is enabled again");
  }
  if (r.max_error_rad && *r.max_error_rad > tolerance_rad) {
    add("the head is " + f2(*r.max_error_rad) + " rad off its locked angles (tolerance " +
        f2(tolerance_rad) + ")");
  }
  if (detail.empty()) {
    head_bad_ = 0;
    return HeadVerdict::kHolding;
  }
  ++head_bad_;
  return head_bad_ >= options_.lost_probes ? HeadVerdict::kLost : HeadVerdict::kRetake;
}

}  // namespace pepper::naoqi_bridge::qi
