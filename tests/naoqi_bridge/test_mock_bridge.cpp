// MockBridge: a RobotBridge over a sim::SimRobot, in-process. Bridge semantics (connection state,
// camera requests, move/stop and the log, stop from another thread, head lock), the WiFi model
// between capture and delivery, and requests the simulated robot refuses.
#include <gtest/gtest.h>

#include <chrono>
#include <opencv2/core.hpp>
#include <string>
#include <thread>

#include "naoqi_bridge/mock_bridge.hpp"
#include "sim/mock_robot.hpp"
#include "sim/synthetic_pattern_robot.hpp"
#include "support/sim_fixtures.hpp"

namespace pepper::naoqi_bridge {
namespace {

using sim::MockRobot;
using std::chrono::milliseconds;
using test::room;
using test::small_fast;

TEST(MockBridge, MoveReachesTheBaseAndStopZeroesIt) {
  MockRobot robot(room(), small_fast());
  MockBridge bridge(robot);
  EXPECT_THROW(bridge.move({0.1, 0, 0}), BridgeError);  // not connected
  bridge.connect();
  EXPECT_EQ(bridge.state(), ConnectionState::kConnected);
  bridge.start_camera({0, 320, 240, 15});
  bridge.move({0.2, 0.0, 0.1});
  ASSERT_FALSE(robot.command_log().empty());
  EXPECT_EQ(robot.command_log().back().velocity.v_x_m_s, 0.2);
  EXPECT_EQ(robot.command_log().back().velocity.omega_rad_s, 0.1);
  for (int i = 0; i < 15; ++i) bridge.next_frame(milliseconds(100));
  EXPECT_NEAR(robot.ground_truth().velocity.v_x_m_s, 0.2, 1e-12);
  bridge.stop();
  EXPECT_TRUE(robot.command_log().back().stop_move);
  EXPECT_TRUE(bridge.log().back().stop_move);
  for (int i = 0; i < 30; ++i) bridge.next_frame(milliseconds(100));
  EXPECT_EQ(robot.ground_truth().velocity.v_x_m_s, 0.0);
  EXPECT_EQ(robot.ground_truth().velocity.omega_rad_s, 0.0);
  bridge.release();
  EXPECT_THROW(bridge.next_frame(milliseconds(1)), BridgeError);  // camera released
}

TEST(MockBridge, FramesComeWithIncreasingTimestamps) {
  MockRobot robot(room(), small_fast());
  MockBridge bridge(robot);
  bridge.connect();
  EXPECT_THROW(bridge.start_camera({1, 320, 240, 15}), BridgeError);  // bottom camera
  const core::CameraIntrinsics k = bridge.start_camera({0, 320, 240, 15});
  EXPECT_EQ(k, robot.intrinsics(320, 240));
  EXPECT_EQ(k.width_px, 320);
  int64_t prev = -1;
  for (int i = 0; i < 10; ++i) {
    const auto f = bridge.next_frame(milliseconds(100));
    ASSERT_TRUE(f.has_value());
    EXPECT_GT(f->t_ns, prev);
    EXPECT_EQ(f->gray.size(), cv::Size(320, 240));
    prev = f->t_ns;
  }
}

TEST(MockBridge, StopIsSafeFromAnotherThreadAndBeforeConnect) {
  MockRobot robot(room(), small_fast());
  MockBridge bridge(robot);
  bridge.stop();  // never throws, even unconnected
  bridge.connect();
  bridge.start_camera({0, 160, 120, 15});
  bridge.move({0.2, 0, 0});
  std::thread t([&] { bridge.stop(); });
  for (int i = 0; i < 3; ++i) bridge.next_frame(milliseconds(10));
  t.join();
  EXPECT_TRUE(bridge.log().back().stop_move);
}

TEST(MockBridge, LockHeadSetsAndReadsBackTheAngles) {
  MockRobot robot(room(), small_fast());
  MockBridge bridge(robot);
  bridge.connect();
  HeadLockRequest req;
  req.head_pitch_rad = 0.1;
  const HeadLockStatus s = bridge.lock_head(req);
  EXPECT_TRUE(s.holding);
  EXPECT_NEAR(s.head_pitch_rad, 0.1, 1e-12);
  req.head_pitch_rad = 1.5;  // beyond the joint limit: cannot hold
  EXPECT_FALSE(bridge.lock_head(req).holding);
}

TEST(MockBridge, WifiDropsAndDelaysFrames) {
  MockRobot robot(room(), small_fast());
  MockBridgeOptions o;
  o.wifi.drop_probability = 0.3;
  o.wifi.delay_s = 0.2;
  MockBridge bridge(robot, o);
  bridge.connect();
  bridge.start_camera({0, 160, 120, 15});
  int delivered = 0, missing = 0;
  int64_t prev = -1;
  for (int i = 0; i < 60; ++i) {
    const auto f = bridge.next_frame(milliseconds(100));
    if (!f) {
      ++missing;
      continue;
    }
    ++delivered;
    EXPECT_GT(f->t_ns, prev);
    EXPECT_LE(f->t_ns, robot.now_ns() - 200'000'000);  // at least the transport delay old
    prev = f->t_ns;
  }
  EXPECT_GT(bridge.frames_dropped(), 5);
  EXPECT_GT(delivered, 25);
  EXPECT_GT(missing, 5);
}

// A request the simulated robot refuses (sim::SimError) reaches RobotBridge callers as the
// BridgeError they handle, with the robot's text: here a size the bridge accepts but the test
// pattern cannot draw.
TEST(MockBridge, ARequestTheRobotRefusesIsABridgeError) {
  sim::SyntheticPatternRobot robot;
  MockBridge bridge(robot);
  bridge.connect();
  bridge.start_camera({0, 4, 4, 15});
  try {
    (void)bridge.next_frame(milliseconds(10));
    FAIL() << "expected a BridgeError";
  } catch (const BridgeError& e) {
    EXPECT_NE(std::string(e.what()).find("unsupported size 4x4"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pepper::naoqi_bridge
