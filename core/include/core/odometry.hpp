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

}  // namespace pepper::core
