// Simulated odometry: WheelOdometry drifts as documented (docs/mock_robot.md "Odometry"), and
// MockRobot serves it (getRobotPosition(true)) and the command integration (false), neither of
// them the ground truth.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/mock_robot.hpp"
#include "sim/wheel_odometry.hpp"
#include "support/sim_fixtures.hpp"

namespace pepper::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

/// `p` in the frame of `origin` (both in one fixed frame): the motion since `origin`.
Pose2D relative(const Pose2D& origin, const Pose2D& p) {
  const double c = std::cos(origin.yaw_rad), s = std::sin(origin.yaw_rad);
  const double dx = p.x_m - origin.x_m, dy = p.y_m - origin.y_m;
  return {c * dx + s * dy, -s * dx + c * dy, std::remainder(p.yaw_rad - origin.yaw_rad, 2 * M_PI)};
}

/// Feeds WheelOdometry a motion at constant velocity for duration_s in 20 ms steps (ALMotion's
/// period), the way MockRobot does, and returns the true end pose.
Pose2D drive(WheelOdometry& odometry, Pose2D pose, const core::BaseVelocity& v, double duration_s) {
  constexpr double kStep_s = 0.02;
  const int whole = static_cast<int>(std::floor(duration_s / kStep_s + 1e-9));
  for (int i = 0; i <= whole; ++i) {
    const double dt_s = i < whole ? kStep_s : duration_s - whole * kStep_s;  // the rest last
    const Pose2D next = integrate_constant(pose, v, dt_s);
    odometry.on_step(pose, next, dt_s);
    pose = next;
  }
  return pose;
}

TEST(WheelOdometry, AQuarterTurnReadsAFewDegreesTooMuch) {
  WheelOdometry odometry;
  // 90 degrees on the spot at 0.5 rad/s (pi s).
  const Pose2D end = drive(odometry, {}, {0.0, 0.0, 0.5}, M_PI);
  ASSERT_NEAR(end.yaw_rad, M_PI / 2, 1e-9);
  const double error_deg = (odometry.pose().yaw_rad - end.yaw_rad) / kDeg;
  // Defaults: +3 % yaw scale = +2.7 degrees, bias 0.001 rad/s x 3.1 s = +0.18, plus a random
  // walk of 0.002 rad/sqrt(s) x sqrt(3.1 s) = 0.2 degrees (1 sigma): "a few degrees per turn",
  // never zero.
  EXPECT_GT(error_deg, 1.5);
  EXPECT_LT(error_deg, 4.5);
  // Turning on the spot does not move the odometry's position.
  EXPECT_NEAR(odometry.pose().x_m, 0.0, 1e-9);
  EXPECT_NEAR(odometry.pose().y_m, 0.0, 1e-9);
}

TEST(WheelOdometry, AFiveMetreLineReadsLongAndDriftsSideways) {
  WheelOdometry odometry;
  const Pose2D end = drive(odometry, {}, {0.2, 0.0, 0.0}, 25.0);
  ASSERT_NEAR(end.x_m, 5.0, 1e-9);
  const core::OdometryPose o = odometry.pose();
  // +1.5 % distance scale (7.5 cm over 5 m), per-step noise 1 % / sqrt(1250 steps): 0.03 %.
  const double along_error = std::hypot(o.x_m, o.y_m) / 5.0 - 1.0;
  EXPECT_GT(along_error, 0.010);
  EXPECT_LT(along_error, 0.020);
  // Heading drift while driving: bias 0.001 rad/s x 25 s = 1.4 degrees, random walk 0.002 x 5 =
  // 0.6 degrees (1 sigma); the lateral offset is about half of it times the length (6 cm).
  EXPECT_GT(std::abs(o.yaw_rad), 0.2 * kDeg);
  EXPECT_LT(std::abs(o.yaw_rad), 4.0 * kDeg);
  EXPECT_LT(std::abs(o.y_m), 0.2);
}

TEST(WheelOdometry, AtRestNothingDrifts) {
  WheelOdometry odometry;
  drive(odometry, {1.0, 2.0, 0.3}, {0.0, 0.0, 0.0}, 60.0);
  EXPECT_EQ(odometry.pose().x_m, 0.0);
  EXPECT_EQ(odometry.pose().y_m, 0.0);
  EXPECT_EQ(odometry.pose().yaw_rad, 0.0);
}

TEST(WheelOdometry, SeedDecidesTheNoiseOnly) {
  WheelOdometryOptions a, b;
  b.seed = a.seed + 1;
  WheelOdometry oa(a), oa2(a), ob(b);
  const core::BaseVelocity arc{0.2, 0.0, 0.3};
  drive(oa, {}, arc, 10.0);
  drive(oa2, {}, arc, 10.0);
  drive(ob, {}, arc, 10.0);
  EXPECT_EQ(oa.pose().x_m, oa2.pose().x_m);
  EXPECT_EQ(oa.pose().yaw_rad, oa2.pose().yaw_rad);
  EXPECT_NE(oa.pose().x_m, ob.pose().x_m);
  // Same systematic errors: the two differ by noise, millimetres and tenths of a degree.
  EXPECT_NEAR(oa.pose().x_m, ob.pose().x_m, 0.02);
  EXPECT_NEAR(oa.pose().yaw_rad, ob.pose().yaw_rad, 1.0 * kDeg);
}

TEST(WheelOdometry, InvalidOptionsAreRefusedByName) {
  WheelOdometryOptions o;
  o.distance_scale_error = 0.5;
  EXPECT_THROW({ WheelOdometry w(o); }, std::invalid_argument);
  o = {};
  o.noise_yaw_rad_sqrt_s = -1;
  ASSERT_FALSE(o.validate().empty());
  EXPECT_NE(o.validate().front().find("noise_yaw_rad_sqrt_s"), std::string::npos);
}

/// Drives `robot` with `v` for duration_s, one captured frame at a time (the lockstep clock).
void drive(MockRobot& robot, const core::BaseVelocity& v, double duration_s) {
  robot.command_velocity(v);
  const int frames = static_cast<int>(std::lround(duration_s * robot.options().frame_rate_hz));
  for (int i = 0; i < frames; ++i) robot.capture(32, 24);
}

TEST(MockRobot, WheelOdometryDriftsOverALineAndATurnButStaysPlausible) {
  MockRobot robot(test::room(), test::small_fast());  // at the teach start, (2, 1.8) facing +x
  const Pose2D start = robot.ground_truth().base;
  const core::OdometryPose odom0 = robot.odometry(OdometrySource::kWheels);
  EXPECT_EQ(odom0.x_m, 0.0);
  EXPECT_EQ(odom0.yaw_rad, 0.0);

  // 5 m straight at 0.25 m/s (accelerations included), stop.
  drive(robot, {0.25, 0.0, 0.0}, 20.0);
  drive(robot, {}, 2.0);
  ASSERT_FALSE(robot.collided());
  const Pose2D line = relative(start, robot.ground_truth().base);
  const core::OdometryPose after_line = robot.odometry(OdometrySource::kWheels);
  const double true_m = std::hypot(line.x_m, line.y_m);
  ASSERT_GT(true_m, 4.8);
  const double odom_m = std::hypot(after_line.x_m, after_line.y_m);
  EXPECT_GT(odom_m / true_m - 1.0, 0.010);  // reads 1.5 % long: not the ground truth
  EXPECT_LT(odom_m / true_m - 1.0, 0.020);

  // A left quarter turn on the spot.
  const double yaw_before_turn = robot.ground_truth().base.yaw_rad;
  // pi s at 0.5 rad/s: the ramp up (0.75 rad/s^2) loses 0.17 rad, the ramp down after the stop
  // adds them back.
  drive(robot, {0.0, 0.0, 0.5}, M_PI);
  drive(robot, {}, 2.0);
  const double true_turn =
      std::remainder(robot.ground_truth().base.yaw_rad - yaw_before_turn, 2 * M_PI);
  ASSERT_NEAR(true_turn, M_PI / 2, 0.2);
  const double odom_turn = std::remainder(
      robot.odometry(OdometrySource::kWheels).yaw_rad - after_line.yaw_rad, 2 * M_PI);
  const double turn_error_deg = (odom_turn - true_turn) / kDeg;
  EXPECT_GT(turn_error_deg, 1.0);  // a few degrees per quarter turn
  EXPECT_LT(turn_error_deg, 5.0);

  // The command integration follows the controller without actuator noise: with the default
  // (noise-free) kinematics it is the true motion, in the odometry frame.
  const Pose2D truth = relative(start, robot.ground_truth().base);
  const core::OdometryPose commanded = robot.odometry(OdometrySource::kCommands);
  EXPECT_NEAR(commanded.x_m, truth.x_m, 1e-6);
  EXPECT_NEAR(commanded.y_m, truth.y_m, 1e-6);
  EXPECT_NEAR(commanded.yaw_rad, truth.yaw_rad, 1e-9);
}

TEST(MockRobot, CommandOdometryIgnoresActuatorNoiseAndPlaceMovesNeither) {
  MockRobotOptions o = test::small_fast();
  o.kinematics.noise_rel = 0.05;
  o.kinematics.noise_omega_rad_s = 0.05;
  MockRobot robot(test::room(), o);
  robot.place({1.5, 1.8, 0.0});
  const Pose2D start = robot.ground_truth().base;
  drive(robot, {0.2, 0.0, 0.2}, 8.0);
  ASSERT_FALSE(robot.collided());
  const Pose2D truth = relative(start, robot.ground_truth().base);
  const core::OdometryPose commanded = robot.odometry(OdometrySource::kCommands);
  const core::OdometryPose wheels = robot.odometry(OdometrySource::kWheels);
  // Neither estimate is the truth, and they differ from each other.
  EXPECT_GT(std::hypot(commanded.x_m - truth.x_m, commanded.y_m - truth.y_m) +
                std::abs(commanded.yaw_rad - truth.yaw_rad),
            1e-4);
  EXPECT_GT(std::abs(wheels.yaw_rad - commanded.yaw_rad), 1e-4);
  // Both stay within metres of plausibility of an 8 s drive at 0.2 m/s.
  EXPECT_NEAR(std::hypot(commanded.x_m, commanded.y_m), std::hypot(truth.x_m, truth.y_m), 0.1);
  // Carrying the robot elsewhere turns no wheel.
  robot.place({3.0, 3.0, 1.0});
  EXPECT_EQ(robot.odometry(OdometrySource::kWheels).x_m, wheels.x_m);
  EXPECT_EQ(robot.odometry(OdometrySource::kCommands).yaw_rad, commanded.yaw_rad);
}

}  // namespace
}  // namespace pepper::sim
