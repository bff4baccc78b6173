// SyntheticPatternRobot: self-checking frames, lockstep clock, unicycle motion, joints.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>

#include "sim/synthetic_pattern_robot.hpp"

namespace sim = pepper::sim;
using sim::SyntheticPatternRobot;

TEST(SyntheticPatternRobot, FramesAreSelfCheckingAndOrdered) {
  SyntheticPatternRobot robot;
  const auto f0 = robot.capture(640, 480);
  const auto f1 = robot.capture(640, 480);
  EXPECT_EQ(SyntheticPatternRobot::verify_frame(f0.gray), 0);
  EXPECT_EQ(SyntheticPatternRobot::verify_frame(f1.gray), 1);
  // Lockstep at 30 Hz: one period per capture.
  EXPECT_EQ(f1.t_ns - f0.t_ns, 33'333'333);
  cv::Mat broken = f1.gray.clone();
  broken.at<uint8_t>(300, 200) ^= 1;
  EXPECT_FALSE(SyntheticPatternRobot::verify_frame(broken).has_value());
}

TEST(SyntheticPatternRobot, TurningShiftsThePatternAndIntegratesYaw) {
  SyntheticPatternRobot robot;
  const auto before = robot.capture(320, 240);
  robot.command_velocity({0.0, 0.0, 0.5});
  for (int i = 0; i < 30; ++i) (void)robot.capture(320, 240);  // 1 s of simulated time
  EXPECT_NEAR(robot.pose().yaw_rad, 0.5, 1e-6);
  const auto after = robot.capture(320, 240);
  // Row 100 compared: the pattern moved, so the rows differ.
  EXPECT_NE(cv::norm(before.gray.row(100), after.gray.row(100), cv::NORM_L1), 0.0);
  robot.stop_move();
  const auto log = robot.command_log();
  ASSERT_EQ(log.size(), 2u);
  EXPECT_TRUE(log.back().stop_move);
  const double yaw = robot.pose().yaw_rad;
  for (int i = 0; i < 10; ++i) (void)robot.capture(320, 240);
  EXPECT_DOUBLE_EQ(robot.pose().yaw_rad, yaw);
}

TEST(SyntheticPatternRobot, JointsAndUnknownNames) {
  SyntheticPatternRobot robot;
  robot.set_joint_angles({"HeadYaw", "HeadPitch"}, {0.1, -0.2});
  EXPECT_EQ(robot.joint_angles({"HeadPitch", "HeadYaw"}), (std::vector<double>{-0.2, 0.1}));
  EXPECT_THROW(robot.set_joint_angles({"LElbowRoll"}, {0.0}), sim::SimError);
  EXPECT_THROW((void)robot.joint_angles({"Nope"}), sim::SimError);
}
