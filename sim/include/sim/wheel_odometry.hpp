#pragma once
// WheelOdometry: the pose the simulated Pepper's wheels report, as ALMotion.getRobotPosition(true)
// does on the robot. It is integrated from the base's actual motion, step by step, with seeded
// errors, so that it drifts as a real robot's odometry does and is never the ground truth:
//   - distance scale: every translation reads (1 + distance_scale_error) times its true length
//     (wheel radius and omni-wheel roller slip, docs/mock_robot.md "Odometry");
//   - yaw scale: every rotation reads (1 + yaw_scale_error) times its true angle (the wheel base
//     and slip while turning: a few degrees per 90-degree turn);
//   - heading drift: yaw_bias_rad_s, added while the wheels turn (a stopped base does not drift);
//   - noise: each step's translation is scaled by (1 + N(0, noise_distance_rel)) and its rotation
//     gets N(0, noise_yaw_rad_sqrt_s * sqrt(dt_s)) (a random walk whose size does not depend on
//     the step length).
//
// Frame: T_odom_base (core/odometry.hpp). The odometry frame is where the base was when the
// odometry was created (pose (0, 0, 0) there), not the world frame; a base teleported by the
// simulator (MockRobot::place) moved without turning its wheels, so the odometry does not see it.
// Deterministic for a given seed and sequence of steps. Not thread-safe (the robots serialise).

#include <cstdint>
#include <string>
#include <vector>

#include "core/odometry.hpp"
#include "sim/world.hpp"

namespace pepper::sim {

struct WheelOdometryOptions {
  double distance_scale_error = 0.015;  ///< +1.5 %: reads 5.075 m over a 5 m line
  double yaw_scale_error = 0.03;        ///< +3 %: reads 92.7 degrees over a 90-degree turn
  double yaw_bias_rad_s = 0.001;        ///< while moving: 1.4 degrees over 25 s of driving
  double noise_distance_rel = 0.01;     ///< per step, relative (std)
  double noise_yaw_rad_sqrt_s = 0.002;  ///< heading random walk while moving, rad / sqrt(s)
  uint64_t seed = 23;

  /// Messages naming each invalid field and its allowed range; empty when valid.
  std::vector<std::string> validate() const;
};

class WheelOdometry {
 public:
  /// Throws std::invalid_argument naming the first invalid option.
  explicit WheelOdometry(WheelOdometryOptions options = {});

  /// One step of the base's actual motion, from pose `before` to pose `after` (any fixed frame,
  /// e.g. the world's) in dt_s seconds. Only the motion relative to `before` is used.
  void on_step(const Pose2D& before, const Pose2D& after, double dt_s);

  /// The odometry now: the base's pose in the odometry frame (yaw wrapped to (-pi, pi]).
  core::OdometryPose pose() const;
  const WheelOdometryOptions& options() const { return options_; }

 private:
  double gaussian();

  WheelOdometryOptions options_;
  double x_m_ = 0.0;
  double y_m_ = 0.0;
  double yaw_rad_ = 0.0;  ///< unwrapped
  uint64_t rng_state_ = 0;
};

}  // namespace pepper::sim
