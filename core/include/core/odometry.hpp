#pragma once
// The robot's own odometry: where the base believes it is, from its wheels (and IMU), in a frame
// fixed when the robot booted. On Pepper this is ALMotion.getRobotPosition(true) (x, y, theta);
// the simulator serves wheel odometry with drift, never its ground truth.
//
// Frame (docs/conventions.md): T_odom_base, the base frame's pose in the odometry frame, x forward,
// y left, yaw counter-clockwise seen from above, metres and radians. Only differences between two
// readings of one run mean anything: the origin is wherever the robot started, and the estimate
// drifts (a few percent of the distance, a few degrees per turn).

namespace pepper::core {

/// One odometry reading: the base's pose in the odometry frame.
struct OdometryPose {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;  ///< counter-clockwise from the odometry frame's x axis
};

/// Bounds of the wheel odometry's systematic errors, per metre driven and per radian turned:
/// margins above the mock's model of wheel odometry (1.5 % of the distance, 3 % of each turn,
/// 0.001 rad/s of heading drift while moving; docs/mock_robot.md "Odometry"), not measured on a
/// real Pepper. The forward navigator grows its estimate's sigmas with them
/// (navigator/navigator.cpp), the ceiling navigator the error of its coasting
/// (ceiling/ceiling_navigator.hpp).
inline constexpr double kOdometryDistanceErrorPerM = 0.03;
inline constexpr double kOdometryYawErrorPerRad = 0.05;
inline constexpr double kOdometryYawErrorPerM = 0.01;

}  // namespace pepper::core
