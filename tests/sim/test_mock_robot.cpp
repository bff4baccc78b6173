// MockRobot, TeachDriver and WifiModel: lockstep clock, camera mount, collisions, WiFi.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>

#include "sim/mock_robot.hpp"
#include "sim/teach_driver.hpp"
#include "sim/wifi_model.hpp"
#include "support/sim_fixtures.hpp"

namespace pepper::sim {
namespace {

using test::room;
using test::small_fast;

const std::filesystem::path kWorlds = std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds";

TEST(MockRobot, CameraMountMatchesPepperAtZeroJoints) {
  MockRobot robot(room(), small_fast());
  robot.place({2.0, 1.8, M_PI / 2});
  const auto gt = robot.ground_truth();
  // PEPPER.md: 1.153 m high, 4.8 cm ahead of the base origin, optical axis horizontal.
  EXPECT_NEAR(gt.T_world_cam.translation().z(), 1.153, 1e-9);
  EXPECT_NEAR(gt.T_world_cam.translation().x(), 2.0, 1e-9);
  EXPECT_NEAR(gt.T_world_cam.translation().y(), 1.8 + 0.048, 1e-9);
  const Eigen::Vector3d optical_axis = gt.T_world_cam.linear().col(2);
  EXPECT_NEAR(optical_axis.y(), 1.0, 1e-12);  // facing world +y
  const Eigen::Vector3d cam_x = gt.T_world_cam.linear().col(0);
  EXPECT_NEAR(cam_x.x(), 1.0, 1e-12);  // image right = robot right = world +x when facing +y
}

TEST(MockRobot, HeadPitchLooksDownAndYawLooksLeft) {
  MockRobot robot(room(), small_fast());
  robot.place({2.0, 1.8, 0.0});
  robot.set_joint_angles({"HeadPitch", "HeadYaw"}, {0.3, 0.0});
  Eigen::Vector3d axis = robot.ground_truth().T_world_cam.linear().col(2);
  EXPECT_NEAR(axis.z(), -std::sin(0.3), 1e-12);
  robot.set_joint_angles({"HeadPitch", "HeadYaw"}, {0.0, 0.4});
  axis = robot.ground_truth().T_world_cam.linear().col(2);
  EXPECT_NEAR(axis.y(), std::sin(0.4), 1e-12);  // left of +x is +y
  // Limits clamp (URDF HeadPitch up to -0.707), unknown joints throw.
  robot.set_joint_angles({"HeadPitch"}, {-2.0});
  EXPECT_NEAR(robot.joint_angles({"HeadPitch"})[0], -0.707, 1e-12);
  EXPECT_THROW(robot.set_joint_angles({"LWristYaw"}, {0.0}), SimError);
  EXPECT_THROW(robot.joint_angles({"Nose"}), SimError);
}

TEST(MockRobot, CaptureAdvancesTheClockOneFramePeriod) {
  MockRobotOptions o = small_fast();
  o.frame_rate_hz = 20.0;
  MockRobot robot(room(), o);
  int64_t prev = robot.now_ns();
  for (int i = 0; i < 5; ++i) {
    const core::Frame f = robot.capture(160, 120);
    EXPECT_EQ(f.t_ns - prev, 50'000'000);
    EXPECT_EQ(f.index, i);
    EXPECT_EQ(f.gray.type(), CV_8UC1);
    EXPECT_EQ(f.gray.size(), cv::Size(160, 120));
    prev = f.t_ns;
  }
}

TEST(MockRobot, DrivingIntoAWallIsACollision) {
  MockRobot robot(room(), small_fast());
  robot.place({1.2, 3.3, M_PI});  // facing the west wall (x = 0), between the two bookshelves
  robot.command_velocity({0.3, 0.0, 0.0});
  for (int i = 0; i < 150 && !robot.collided(); ++i) robot.advance_s(1.0 / 15);
  ASSERT_TRUE(robot.collided());
  const GroundTruth gt = robot.ground_truth();
  ASSERT_TRUE(gt.collision.has_value());
  EXPECT_NE(gt.collision->what.find("walls[0]"), std::string::npos) << gt.collision->what;
  // Stopped with the 0.3 m disc touching the 0.1 m thick wall (x = 0.05 + 0.3), within a step.
  EXPECT_NEAR(gt.base.x_m, 0.35, 0.01);
  EXPECT_EQ(gt.velocity.v_x_m_s, 0.0);
  // The run is over: further commands are logged but do not move the base.
  robot.command_velocity({0.3, 0.0, 0.5});
  robot.advance_s(1.0);
  EXPECT_EQ(robot.ground_truth().base.x_m, gt.base.x_m);
  EXPECT_EQ(robot.command_log().size(), 2u);
  // place() starts a new run.
  robot.place({2.0, 1.8, 0.0});
  EXPECT_FALSE(robot.collided());
}

TEST(MockRobot, CollisionWithFurniture) {
  MockRobot robot(room(), small_fast());
  robot.place({4.5, 1.8, M_PI / 2});  // facing the central tables (y 2.9 .. 4.1)
  robot.command_velocity({0.3, 0.0, 0.0});
  for (int i = 0; i < 150 && !robot.collided(); ++i) robot.advance_s(1.0 / 15);
  ASSERT_TRUE(robot.collided());
  EXPECT_NE(robot.ground_truth().collision->what.find("table_centre"), std::string::npos);
}

TEST(MockRobot, SameSeedsGiveSameFrames) {
  MockRobotOptions o = small_fast();
  o.kinematics.noise_rel = 0.05;
  MockRobot a(room(), o), b(room(), o);
  for (MockRobot* r : {&a, &b}) r->command_velocity({0.2, 0.0, 0.3});
  for (int i = 0; i < 5; ++i) {
    const core::Frame fa = a.capture(320, 240), fb = b.capture(320, 240);
    EXPECT_EQ(cv::norm(fa.gray, fb.gray, cv::NORM_INF), 0.0);
  }
  EXPECT_EQ(a.ground_truth().base.x_m, b.ground_truth().base.x_m);
}

TEST(MockRobot, ReplayLightingChangesExposure) {
  const auto world = std::make_shared<const World>(load_world(kWorlds / "window_corridor.yaml"));
  MockRobot teach(world, small_fast());
  MockRobotOptions o = small_fast();
  o.lighting = "replay";
  MockRobot replay(world, o);
  const double m_teach = cv::mean(teach.capture(320, 240).gray)[0];
  const double m_replay = cv::mean(replay.capture(320, 240).gray)[0];
  EXPECT_LT(m_replay, m_teach - 10.0);  // ambient 0.7 vs 1.0
  EXPECT_THROW(teach.set_lighting("night"), WorldError);
}

// Drives each world's taught path with the ground-truth teach driver (no rendering): the path
// can be driven within Pepper's limits without touching anything and ends at the last waypoint.
TEST(MockRobot, EveryTaughtPathCanBeDrivenWithoutCollision) {
  for (const char* name : {"robotics_room.yaml", "room_corridor_room.yaml", "white_corridor.yaml",
                           "window_corridor.yaml"}) {
    SCOPED_TRACE(name);
    const auto world = std::make_shared<const World>(load_world(kWorlds / name));
    MockRobot robot(world, small_fast());
    TeachDriver driver(world->scenario);
    const double dt = 1.0 / 15;
    double t = 0.0;
    int step = 0;
    while (!driver.done() && t < 400.0 && !robot.collided()) {
      robot.command_velocity(driver.command(robot.ground_truth().base, t));
      if (++step % 30 == 0) {
        // Every 2 s a QVGA frame: neither black nor washed out, and textured.
        const core::Frame f = robot.capture(320, 240);
        cv::Scalar mean, stddev;
        cv::meanStdDev(f.gray, mean, stddev);
        EXPECT_GT(mean[0], 40.0) << "t = " << t;
        EXPECT_LT(mean[0], 230.0) << "t = " << t;
        EXPECT_GT(stddev[0], 10.0) << "t = " << t;
      } else {
        robot.advance_s(dt);
      }
      t += dt;
    }
    EXPECT_FALSE(robot.collided()) << robot.ground_truth().collision->what;
    EXPECT_TRUE(driver.done());
    const Eigen::Vector2d end = world->scenario.waypoints_m.back();
    const Pose2D p = robot.ground_truth().base;
    EXPECT_LT((Eigen::Vector2d(p.x_m, p.y_m) - end).norm(), 0.2);
  }
}

TEST(TeachDriver, VelocityScriptIsPlayedStepByStep) {
  Scenario s;
  s.velocity_script = {{0.2, 0.0, 2.0}, {0.0, 0.5, 1.0}};
  TeachDriver d(s);
  EXPECT_EQ(d.command({}, 0.5).v_x_m_s, 0.2);
  EXPECT_EQ(d.command({}, 2.5).omega_rad_s, 0.5);
  EXPECT_FALSE(d.done());
  EXPECT_EQ(d.command({}, 3.5).v_x_m_s, 0.0);
  EXPECT_TRUE(d.done());
  EXPECT_THROW(TeachDriver{Scenario{}}, std::invalid_argument);
}

TEST(WifiModel, NoDropNoDelayDeliversEveryFrame) {
  WifiModel w;
  for (int i = 0; i < 5; ++i) {
    core::Frame f;
    f.t_ns = i * 10;
    const auto out = w.transmit(f, f.t_ns);
    ASSERT_TRUE(out.has_value());
    EXPECT_EQ(out->t_ns, f.t_ns);
  }
  WifiOptions bad;
  bad.drop_probability = 1.0;
  EXPECT_THROW(WifiModel{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace pepper::sim
