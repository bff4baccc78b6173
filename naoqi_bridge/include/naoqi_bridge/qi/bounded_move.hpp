#pragma once
// A velocity command with its own horizon, for ALMotion.moveTo(x, y, theta, time).
//
// Why: a real NAOqi keeps executing the last ALMotion.move velocity until told otherwise, also
// after the client froze or its connection dropped (PEPPER.md: no built-in timeout). The
// time-constrained moveTo (`(ffff)`, uid 144 in NAOqi 2.5's ALMotion) makes the robot reach a
// relative pose in a given time and then stop by itself. Sending the pose that the velocity
// would reach after a short horizon turns every velocity command into one that ends by itself
// on the robot: if no fresh command follows within the horizon, the base stops without any help
// from the laptop (docs/naoqi_bridge.md, "robot-side deadman").
//
// Both directions of the conversion live here so that the client (QiBridge) and the mock NAOqi
// server agree exactly: a constant body-frame twist (v_x, v_y, omega) held for `horizon_s` ends at
//   theta = omega T,  [x, y] = (1/omega) [[sin th, -(1 - cos th)], [1 - cos th, sin th]] [v_x, v_y]
// (the straight line v T when |theta| is tiny). Units: m, rad, s; robot frame at the start of the
// command (x forward, y left, theta > 0 turns left; docs/conventions.md).
// Failure: non-finite inputs or a horizon <= 0 throw std::invalid_argument.

#include "core/base_velocity.hpp"

namespace pepper::naoqi_bridge::qi {

/// A pose relative to the robot frame at the start of a command.
struct RelativePose {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;
};

/// Where the base is after holding `velocity` for `horizon_s` seconds.
RelativePose pose_after(const core::BaseVelocity& velocity, double horizon_s);

/// The constant twist that reaches `pose` in `horizon_s` seconds (inverse of pose_after).
core::BaseVelocity velocity_reaching(const RelativePose& pose, double horizon_s);

}  // namespace pepper::naoqi_bridge::qi
