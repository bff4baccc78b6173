#pragma once
// BaseKinematics: the simulated Pepper base. Integrates robot-frame velocities (v_x, v_y, omega)
// exactly over piecewise-constant steps (arcs), with ALMotion's velocity and acceleration limits,
// a command latency and seeded actuator noise.
//
// Units and frames (docs/conventions.md): pose of the base rotation axis in the world frame
// (x, y in metres, yaw in rad counter-clockwise); velocities in the robot frame, x forward,
// y left, omega > 0 turns left, as ALMotion.move(x, y, theta).
// Defaults: PEPPER.md "Head, body and base" (qiBullet pepper_virtual.py): MaxVelXY 0.35 m/s,
// MaxVelTheta 1.0 rad/s, MaxAccXY 0.3 m/s^2, MaxAccTheta 0.75 rad/s^2; ALMotion runs at 50 Hz.
// Model: a command received at t takes effect at t + latency_s; its velocity is clamped to the
// limits (|v_xy| as a vector); the actual velocity then approaches it at the acceleration limits,
// updated every step_s; within a step the velocity is constant and the pose follows the exact arc.
// Noise (when enabled): each step, the integrated velocity is the actual one times (1 + N(0,
// noise_rel)) plus N(0, noise_*) per axis, from a generator seeded with `seed`.
// Thread-safety: none (MockRobot serialises access).

#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <vector>

#include "core/base_velocity.hpp"
#include "sim/world.hpp"

namespace pepper::sim {

struct KinematicsOptions {
  double max_v_xy_m_s = 0.35;          ///< ALMotion MaxVelXY default
  double max_omega_rad_s = 1.0;        ///< MaxVelTheta default
  double max_acc_xy_m_s2 = 0.3;        ///< MaxAccXY default
  double max_acc_theta_rad_s2 = 0.75;  ///< MaxAccTheta default
  double latency_s = 0.0;              ///< command reception to actuation, >= 0
  double step_s = 0.02;                ///< integration / control period (ALMotion 50 Hz)
  double noise_rel = 0.0;              ///< multiplicative velocity noise (std, fraction)
  double noise_v_m_s = 0.0;            ///< additive noise on v_x and v_y (std)
  double noise_omega_rad_s = 0.0;      ///< additive noise on omega (std)
  uint64_t seed = 1;

  std::vector<std::string> validate() const;
};

/// One integration step the base took (not blocked): for the odometry models.
struct BaseStep {
  Pose2D before;                  ///< pose at the start of the step
  Pose2D after;                   ///< pose at its end (actual motion, actuator noise included)
  core::BaseVelocity controlled;  ///< the motion controller's velocity, without actuator noise
  double dt_s = 0.0;
};

/// Exact pose after moving with constant robot-frame velocity for dt_s (an arc, or a line when
/// omega is ~0). Yaw is wrapped to (-pi, pi].
Pose2D integrate_constant(const Pose2D& start, const core::BaseVelocity& velocity, double dt_s);

class BaseKinematics {
 public:
  /// Throws std::invalid_argument naming the bad field.
  explicit BaseKinematics(KinematicsOptions options = {});

  /// Teleports the base (velocity zero, pending commands dropped); the clock is set to t_ns.
  void reset(const Pose2D& pose, int64_t t_ns);

  /// A velocity command received at t_ns (>= the current time); effective after the latency.
  void command(const core::BaseVelocity& velocity, int64_t t_ns);

  /// Advances the clock to t_end_ns. `blocked(pose, t_ns)` is asked after every step; when it
  /// returns true the base goes back to the pose before that step, stops (velocity zero) and
  /// the function returns false. Returns true when the interval was completed freely.
  /// `on_step`, when given, is told of every step taken (after `blocked` let it through).
  bool advance_to(int64_t t_end_ns,
                  const std::function<bool(const Pose2D&, int64_t)>& blocked = nullptr,
                  const std::function<void(const BaseStep&)>& on_step = nullptr);

  /// Stops at once (after a collision): velocity and pending commands cleared.
  void halt();

  const Pose2D& pose() const { return pose_; }
  /// Actual velocity now (robot frame, without the per-step noise).
  const core::BaseVelocity& velocity() const { return velocity_; }
  /// The velocity the base is steering towards (clamped command in force).
  const core::BaseVelocity& target() const { return target_; }
  int64_t now_ns() const { return t_ns_; }
  const KinematicsOptions& options() const { return options_; }

 private:
  struct Pending {
    int64_t effective_ns;
    core::BaseVelocity velocity;
  };
  core::BaseVelocity clamp(const core::BaseVelocity& v) const;
  double gaussian();

  KinematicsOptions options_;
  Pose2D pose_;
  core::BaseVelocity velocity_;
  core::BaseVelocity target_;
  std::deque<Pending> pending_;
  int64_t t_ns_ = 0;
  int64_t next_control_ns_ = 0;
  uint64_t rng_state_ = 0;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace pepper::sim
