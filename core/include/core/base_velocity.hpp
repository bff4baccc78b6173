#pragma once
// The velocity of Pepper's base: what a controller commands and what a robot (real or
// simulated) executes. Plain data, shared by the bridge (RobotBridge::move) and the simulator
// (sim::SimRobot::command_velocity), so that neither has to include the other.
//
// Units and frames (docs/conventions.md): robot frame, x forward, y left, omega > 0 turns left
// (counter-clockwise seen from above), as ALMotion.move(x, y, theta).

namespace pepper::core {

/// Velocity of the base in the robot frame.
struct BaseVelocity {
  double v_x_m_s = 0.0;      ///< forward, m/s
  double v_y_m_s = 0.0;      ///< left, m/s (our controllers keep it 0: unicycle)
  double omega_rad_s = 0.0;  ///< yaw rate, rad/s, > 0 turns left
};

}  // namespace pepper::core
