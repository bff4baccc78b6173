#pragma once
// Turns a raw yaw-rate demand into the base command (v, omega): forward speed schedule with a
// "turning" state read from |omega| with hysteresis, and limits on |omega| and on its rate of
// change (METHOD.md, "Forward speed"; thresholds and their reasons in docs/method/control.md).
//
// Turning: entered when |omega| >= turn_enter_rad_s, left when |omega| <= turn_exit_rad_s
// (exit < enter, so a demand hovering near one threshold does not make the speed chatter).
// Speed: v_turn_m_s while turning, v_straight_m_s otherwise.
// Rate limit: |omega_k - omega_{k-1}| <= max_omega_accel_rad_s2 * (t_k - t_{k-1}), with the
// interval taken from frame stamps t_ns (never the wall clock), so the output is a deterministic
// function of (demands, stamps). The first step after reset() starts from omega = 0 and uses
// first_step_dt_s as the interval.
//
// Not thread-safe (one instance per control loop). step() throws std::invalid_argument when the
// stamps go backwards or the demand is not finite; the constructor throws on invalid options.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace pepper::core::control {

struct VelocityScheduleOptions {
  double v_straight_m_s = 0.15;          ///< METHOD.md (paper value), >= 0
  double v_turn_m_s = 0.08;              ///< METHOD.md (paper value), in [0, v_straight_m_s]
  double turn_enter_rad_s = 0.15;        ///< |omega| at which turning starts, > turn_exit_rad_s
  double turn_exit_rad_s = 0.08;         ///< |omega| at which turning ends, >= 0
  /// Turning ends only once |omega| has stayed <= turn_exit_rad_s this long (frame stamps), s;
  /// 0 (the default): at once. >= 0. 1 s was measured and not kept (docs/method/control.md
  /// "Turns", session 11): more accurate corners, but it moved room_corridor_room's failures.
  double turn_exit_hold_s = 0.0;
  double max_omega_rad_s = 0.6;          ///< saturation, > 0 (Pepper allows 1.0 by default)
  double max_omega_accel_rad_s2 = 0.75;  ///< rate limit, > 0 (Pepper's MaxAccTheta default)
  double first_step_dt_s = 0.2;          ///< interval assumed for the first step (5 Hz), > 0

  std::vector<std::string> validate() const;
};

struct BaseCommand {
  double v_m_s = 0.0;
  double omega_rad_s = 0.0;
  bool turning = false;
};

class VelocitySchedule {
 public:
  explicit VelocitySchedule(const VelocityScheduleOptions& options = {});

  /// One control step at frame stamp t_ns with raw demand omega_demand_rad_s.
  BaseCommand step(double omega_demand_rad_s, int64_t t_ns);
  /// Forget the previous command (next step starts from rest, not turning).
  void reset();

  bool turning() const { return turning_; }
  const VelocityScheduleOptions& options() const { return options_; }

 private:
  VelocityScheduleOptions options_;
  bool turning_ = false;
  std::optional<int64_t> calm_since_ns_;  ///< while turning: first stamp of |omega| <= exit
  double last_omega_rad_s_ = 0.0;
  std::optional<int64_t> last_t_ns_;
};

/// Turn hysteresis as a pure function: the next "turning" state from the current one and |omega|.
bool next_turning_state(bool turning, double omega_rad_s, const VelocityScheduleOptions& options);

}  // namespace pepper::core::control
