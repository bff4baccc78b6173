// The robot's odometry over the wire (issues 23, 29): QiBridge reads
// ALMotion.getRobotPosition(true) with every frame from MockNaoqiServer on 127.0.0.1; the server
// answers useSensors = true with the simulated wheel odometry and false with the commanded-motion
// integration; a reading that fails leaves the frame without odometry, reported, never fatal.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <mutex>
#include <vector>

#include "naoqi_bridge/qi/mock_server.hpp"
#include "naoqi_bridge/qi/qi_bridge.hpp"
#include "naoqi_bridge/qi/session.hpp"
#include "sim/synthetic_pattern_robot.hpp"

namespace qi = pepper::naoqi_bridge::qi;
namespace nb = pepper::naoqi_bridge;
namespace sim = pepper::sim;
namespace core = pepper::core;
using namespace std::chrono_literals;

namespace {

/// A SimRobot that forwards to a SyntheticPatternRobot and keeps every odometry reading it
/// served (time, source, pose); `fail_odometry` makes it refuse them as a robot could.
class OdometryWitness final : public sim::SimRobot {
 public:
  struct Reading {
    int64_t t_ns;
    sim::OdometrySource source;
    core::OdometryPose pose;
  };

  core::Frame capture(int w, int h) override { return inner_.capture(w, h); }
  core::CameraIntrinsics intrinsics(int w, int h) const override { return inner_.intrinsics(w, h); }
  void command_velocity(const core::BaseVelocity& v) override { inner_.command_velocity(v); }
  void stop_move() override { inner_.stop_move(); }
  void set_joint_angles(const std::vector<std::string>& n, const std::vector<double>& a) override {
    inner_.set_joint_angles(n, a);
  }
  std::vector<double> joint_angles(const std::vector<std::string>& n) const override {
    return inner_.joint_angles(n);
  }
  int64_t now_ns() const override { return inner_.now_ns(); }
  std::vector<sim::CommandRecord> command_log() const override { return inner_.command_log(); }
  core::OdometryPose odometry(sim::OdometrySource source) const override {
    std::lock_guard lock(mutex_);
    if (fail_odometry) throw sim::SimError("ALMotion: odometry not available (test)");
    const core::OdometryPose p = inner_.odometry(source);
    readings_.push_back({inner_.now_ns(), source, p});
    return p;
  }

  std::vector<Reading> readings() const {
    std::lock_guard lock(mutex_);
    return readings_;
  }
  void set_fail(bool fail) {
    std::lock_guard lock(mutex_);
    fail_odometry = fail;
  }

 private:
  sim::SyntheticPatternRobot inner_;
  mutable std::mutex mutex_;
  mutable std::vector<Reading> readings_;
  bool fail_odometry = false;
};

qi::QiBridgeOptions bridge_options(const qi::MockNaoqiServer& server) {
  qi::QiBridgeOptions o;
  o.url = server.url();
  o.connect_timeout = 3000ms;
  o.call_timeout = 3000ms;
  o.head_settle_timeout = 0ms;
  o.watchdog_timeout = 10000ms;  // the tests ask for frames, not moves; no stop in between
  // A loaded test machine may be slow to hand over the odometry reply; the default grace is
  // for the robot, where that reply is back long before the image's.
  o.odometry_grace = 200ms;
  return o;
}

constexpr int64_t kFramePeriodNs = 33'333'333;  // SyntheticPatternRobot's lockstep 30 Hz

}  // namespace

TEST(QiOdometry, EveryFrameCarriesTheWheelOdometryReadWithIt) {
  OdometryWitness robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  qi::QiBridge bridge(bridge_options(server));
  bridge.connect();
  bridge.start_camera({0, 320, 240, 30});
  bridge.move({0.2, 0.0, 0.3});  // an arc: both position and heading change
  std::vector<core::Frame> frames;
  for (int i = 0; i < 20; ++i) {
    auto f = bridge.next_frame(3000ms);
    ASSERT_TRUE(f.has_value()) << i;
    frames.push_back(*f);
  }
  bridge.release();
  EXPECT_EQ(bridge.counters().frames_without_odometry, 0u);
  EXPECT_EQ(bridge.odometry_problem(), "");
  const auto readings = robot.readings();
  for (size_t i = 0; i < frames.size(); ++i) {
    const core::Frame& f = frames[i];
    ASSERT_TRUE(f.odom.has_value()) << "frame " << i;
    // The reading was sent just before the frame's image request: on the lockstep mock it is the
    // odometry one frame period before the image's stamp (on a robot, within one frame period).
    bool found = false;
    for (const auto& r : readings) {
      // Frame stamps cross the wire in whole microseconds.
      if (r.source != sim::OdometrySource::kWheels ||
          std::abs(r.t_ns - (f.t_ns - kFramePeriodNs)) >= 1000) {
        continue;
      }
      found = true;
      EXPECT_NEAR(f.odom->x_m, r.pose.x_m, 1e-5);  // float32 on the wire
      EXPECT_NEAR(f.odom->y_m, r.pose.y_m, 1e-5);
      EXPECT_NEAR(f.odom->yaw_rad, r.pose.yaw_rad, 1e-5);
    }
    EXPECT_TRUE(found) << "no odometry read for frame " << i << " at t " << f.t_ns;
  }
  // The base moved: the odometry says so, and only the wheels were asked (useSensors = true).
  EXPECT_GT(frames.back().odom->x_m, frames.front().odom->x_m + 0.05);
  EXPECT_GT(frames.back().odom->yaw_rad, frames.front().odom->yaw_rad + 0.1);
  for (const auto& r : readings) EXPECT_EQ(r.source, sim::OdometrySource::kWheels);
}

TEST(QiOdometry, UseSensorsSelectsWheelsOrCommands) {
  OdometryWitness robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  qi::QiSession session;
  session.connect(server.url());
  const auto motion = session.service("ALMotion");
  const auto* method = motion.meta.find("getRobotPosition", "(b)");
  ASSERT_NE(method, nullptr);
  EXPECT_EQ(method->uid, 180u);  // PROTOCOL.md 7.1
  EXPECT_EQ(method->return_signature, "[f]");
  (void)session.call(motion, "move", "(fff)",
                     {qi::Value::float32(0.25f), qi::Value::float32(0.f),
                      qi::Value::float32(0.2f)});
  for (int i = 0; i < 60; ++i) (void)robot.capture(16, 8);  // 2 s of lockstep time
  auto read = [&](bool use_sensors) {
    const qi::Value v =
        session.call(motion, "getRobotPosition", "(b)", {qi::Value::boolean(use_sensors)});
    EXPECT_EQ(v.elements().size(), 3u);
    return core::OdometryPose{v.elements().at(0).as_double(), v.elements().at(1).as_double(),
                              v.elements().at(2).as_double()};
  };
  const core::OdometryPose wheels = read(true);
  const core::OdometryPose commands = read(false);
  const auto expect_same = [](const core::OdometryPose& wire, const core::OdometryPose& sim) {
    EXPECT_NEAR(wire.x_m, sim.x_m, 1e-5);
    EXPECT_NEAR(wire.y_m, sim.y_m, 1e-5);
    EXPECT_NEAR(wire.yaw_rad, sim.yaw_rad, 1e-5);
  };
  expect_same(wheels, robot.odometry(sim::OdometrySource::kWheels));
  expect_same(commands, robot.odometry(sim::OdometrySource::kCommands));
  // 2 s at 0.25 m/s: about half a metre; the wheels read 1.5 % long and the turn 3 % wide.
  EXPECT_NEAR(commands.yaw_rad, 0.4, 1e-3);
  EXPECT_GT(wheels.yaw_rad - commands.yaw_rad, 0.005);
  EXPECT_GT(std::hypot(wheels.x_m, wheels.y_m), std::hypot(commands.x_m, commands.y_m) + 0.003);
  session.close();
}

TEST(QiOdometry, AFailedReadingLeavesTheFrameWithoutOdometryAndSaysWhy) {
  OdometryWitness robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  qi::QiBridge bridge(bridge_options(server));
  bridge.connect();
  bridge.start_camera({0, 320, 240, 30});
  robot.set_fail(true);
  // The request already in flight was answered before the failure began; after it, none is.
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(bridge.next_frame(3000ms).has_value());
  const auto f = bridge.next_frame(3000ms);
  ASSERT_TRUE(f.has_value());  // the frame still comes
  EXPECT_FALSE(f->odom.has_value());
  EXPECT_NE(bridge.odometry_problem().find("odometry not available (test)"), std::string::npos)
      << bridge.odometry_problem();
  EXPECT_GE(bridge.counters().frames_without_odometry, 4u);
  EXPECT_EQ(bridge.state(), nb::ConnectionState::kConnected);
  EXPECT_FALSE(bridge.needs_operator());
  robot.set_fail(false);
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(bridge.next_frame(3000ms).has_value());
  const auto again = bridge.next_frame(3000ms);
  ASSERT_TRUE(again.has_value());
  EXPECT_TRUE(again->odom.has_value());
  EXPECT_EQ(bridge.odometry_problem(), "");
  bridge.release();
}

TEST(QiOdometry, TurnedOffNothingIsAsked) {
  OdometryWitness robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  qi::QiBridgeOptions o = bridge_options(server);
  o.read_odometry = false;
  qi::QiBridge bridge(o);
  bridge.connect();
  bridge.start_camera({0, 320, 240, 30});
  for (int i = 0; i < 3; ++i) {
    const auto f = bridge.next_frame(3000ms);
    ASSERT_TRUE(f.has_value());
    EXPECT_FALSE(f->odom.has_value());
  }
  bridge.release();
  EXPECT_TRUE(robot.readings().empty());
  EXPECT_EQ(bridge.odometry_problem(), "");
}
