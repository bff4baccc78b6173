// What the robot itself shows during a session (issue 23 leftovers, issue 30 item 7): the mock
// NAOqi's robot state and its hooks, and QiBridge::supervise() over 127.0.0.1 against them.
// A move the robot does not execute becomes a warning (with ALMotion/MoveFailed's cause); a head
// that Autonomous Life takes back is re-taken with a warning; a head that cannot be held stops
// the base and is reported as lost. MotionSupervisor's rules are tested on their own first.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "naoqi_bridge/qi/errors.hpp"
#include "naoqi_bridge/qi/mock_server.hpp"
#include "naoqi_bridge/qi/motion_supervisor.hpp"
#include "naoqi_bridge/qi/qi_bridge.hpp"
#include "naoqi_bridge/qi/session.hpp"
#include "sim/synthetic_pattern_robot.hpp"

namespace qi = pepper::naoqi_bridge::qi;
namespace nb = pepper::naoqi_bridge;
namespace sim = pepper::sim;
using namespace std::chrono_literals;

namespace {

constexpr std::int64_t kMs = 1'000'000;

bool contains(const std::vector<std::string>& v, const std::string& text) {
  for (const auto& s : v) {
    if (s.find(text) != std::string::npos) return true;
  }
  return false;
}

std::string joined(const std::vector<std::string>& v) {
  std::string all;
  for (const auto& s : v) all += s + " | ";
  return all;
}

}  // namespace

// ---- MotionSupervisor on its own ---------------------------------------------------------------

TEST(MotionSupervisor, AMoveFailsOnlyAfterSettlingAndTwoDisagreeingReadbacks) {
  qi::MotionSupervisor s;  // settle 700 ms, fresh 200 ms, 2 probes
  s.on_command({0.2, 0.0, 0.1}, 0);
  // Too early: the robot is still accelerating, a zero read-back says nothing.
  auto early = s.snapshot(300 * kMs);
  EXPECT_FALSE(early.counts);
  EXPECT_FALSE(s.on_motion_readback(early, {}, false).has_value());
  // Settled, refreshed (a command every 50 ms, as a session sends them): the first
  // disagreement is not yet a failure, the second is.
  for (int t_ms = 50; t_ms <= 750; t_ms += 50) s.on_command({0.2, 0.0, 0.1}, t_ms * kMs);
  auto snap = s.snapshot(800 * kMs);
  ASSERT_TRUE(snap.counts);
  EXPECT_FALSE(s.on_motion_readback(snap, {0.0, 0.0, 0.0}, false).has_value());
  auto w = s.on_motion_readback(snap, {0.0, 0.0, 0.0}, false);
  ASSERT_TRUE(w.has_value());
  EXPECT_NE(w->find("move failed"), std::string::npos);
  EXPECT_NE(w->find("0.20 m/s"), std::string::npos) << *w;  // the command is named
  EXPECT_TRUE(s.move_failing());
  // Executed again (magnitude compared: getRobotVelocity is in the world frame).
  auto again = s.on_motion_readback(snap, {0.0, -0.19, 0.1}, true);
  ASSERT_TRUE(again.has_value());
  EXPECT_FALSE(s.move_failing());
}

TEST(MotionSupervisor, StaleOrStoppedCommandsAreNotJudged) {
  qi::MotionSupervisor s;
  s.on_command({0.2, 0.0, 0.0}, 0);
  // The last command is older than the robot-side horizon: it may have ended by itself.
  EXPECT_FALSE(s.snapshot(1000 * kMs).counts);
  // Commands again after the gap (a frozen app resumed): a new ramp, not judged at once.
  s.on_command({0.2, 0.0, 0.0}, 900 * kMs);
  EXPECT_FALSE(s.snapshot(950 * kMs).counts);
  s.on_command({0.0, 0.0, 0.0}, 1000 * kMs);
  const auto stopped = s.snapshot(1050 * kMs);
  EXPECT_FALSE(stopped.counts);
  EXPECT_FALSE(s.on_motion_readback(stopped, {}, false).has_value());
  EXPECT_FALSE(s.move_failing());
}

TEST(MotionSupervisor, HeadTakenIsRetakenThenLostAfterThreeReadbacks) {
  qi::MotionSupervisor s;
  std::string detail;
  qi::MotionSupervisor::HeadReadback ok{std::string("disabled"), false, 0.01};
  EXPECT_EQ(s.on_head_readback(ok, true, true, 0.05, detail),
            qi::MotionSupervisor::HeadVerdict::kHolding);
  qi::MotionSupervisor::HeadReadback taken{std::string("solitary"), true, 0.6};
  EXPECT_EQ(s.on_head_readback(taken, true, true, 0.05, detail),
            qi::MotionSupervisor::HeadVerdict::kRetake);
  EXPECT_NE(detail.find("solitary"), std::string::npos) << detail;
  EXPECT_NE(detail.find("0.60 rad off"), std::string::npos) << detail;
  EXPECT_EQ(s.on_head_readback(taken, true, true, 0.05, detail),
            qi::MotionSupervisor::HeadVerdict::kRetake);
  EXPECT_EQ(s.on_head_readback(taken, true, true, 0.05, detail),
            qi::MotionSupervisor::HeadVerdict::kLost);
  // Autonomous Life left on by choice (the bridge did not turn it off) is not a problem.
  qi::MotionSupervisor t;
  qi::MotionSupervisor::HeadReadback chosen{std::string("solitary"), true, 0.0};
  EXPECT_EQ(t.on_head_readback(chosen, false, false, 0.05, detail),
            qi::MotionSupervisor::HeadVerdict::kHolding);
}

// ---- Over the wire ----------------------------------------------------------------------------

namespace {

struct Rig {
  explicit Rig(qi::MockRobotState state = {}) {
    qi::MockServerOptions so;
    so.robot_state = std::move(state);
    server = std::make_unique<qi::MockNaoqiServer>(robot, so);
    server->start();
  }
  qi::QiBridgeOptions bridge_options() const {
    qi::QiBridgeOptions o;
    o.url = server->url();
    o.head_settle_timeout = 500ms;
    o.watchdog_timeout = 2000ms;  // the test drives with a slow loop; the watchdog stays out
    o.frame_stall_timeout = 5000ms;
    o.supervise_period = 50ms;
    o.supervisor.move_settle_ns = 150 * kMs;
    o.supervisor.command_fresh_ns = 150 * kMs;
    return o;
  }
  sim::SyntheticPatternRobot robot;
  std::unique_ptr<qi::MockNaoqiServer> server;
};

/// Calls supervise() (and keeps the command fresh with `drive`) until `done` says so or the
/// limit passes; returns every warning seen and the last supervision.
nb::RobotSupervision supervise_until(qi::QiBridge& bridge, std::vector<std::string>& warnings,
                                     const std::function<bool(const nb::RobotSupervision&)>& done,
                                     const std::function<void()>& drive = {},
                                     std::chrono::milliseconds limit = 5000ms) {
  const auto end = std::chrono::steady_clock::now() + limit;
  nb::RobotSupervision s;
  while (std::chrono::steady_clock::now() < end) {
    if (drive) drive();
    s = bridge.supervise();
    for (const auto& w : s.warnings) warnings.push_back(w);
    if (done(s)) return s;
    std::this_thread::sleep_for(20ms);
  }
  return s;
}

std::vector<double> robot_velocity(const std::string& url) {
  qi::QiSession watcher;
  watcher.connect(url);
  const auto motion = watcher.service("ALMotion");
  std::vector<double> out;
  const qi::Value reply = watcher.call(motion, "getRobotVelocity", "()", {});
  for (const auto& e : reply.elements()) out.push_back(e.as_double());
  return out;
}

}  // namespace

TEST(MockRobotState, ServesVersionBatteryChargerAndLeavesServicesOut) {
  qi::MockRobotState st;
  st.naoqi_version = "2.9.5.172";
  st.battery_percent = 12;
  st.charging = true;
  st.awake = false;
  st.autonomous_life = "solitary";
  st.collision_protection = false;
  st.missing_services = {"ALBasicAwareness"};
  Rig rig(st);
  qi::QiSession s;
  s.connect(rig.server->url());
  EXPECT_EQ(s.call(s.service("ALSystem"), "systemVersion", "()", {}).as_string(), "2.9.5.172");
  EXPECT_EQ(s.call(s.service("ALMotion"), "version", "()", {}).as_string(), "2.9.5.172");
  EXPECT_EQ(s.call(s.service("ALBattery"), "getBatteryCharge", "()", {}).as_int(), 12);
  const auto memory = s.service("ALMemory");
  EXPECT_GT(s.call(memory, "getData", "(s)",
                   {qi::Value::string("Device/SubDeviceList/Battery/Current/Sensor/Value")})
                .unwrapped()
                .as_double(),
            0.0);  // charging: current into the battery
  EXPECT_THROW(s.call(memory, "getData", "(s)", {qi::Value::string("No/Such/Key")}),
               qi::RemoteCallError);
  const auto motion = s.service("ALMotion");
  EXPECT_FALSE(s.call(motion, "robotIsWakeUp", "()", {}).as_bool());
  EXPECT_FALSE(
      s.call(motion, "getExternalCollisionProtectionEnabled", "(s)", {qi::Value::string("Move")})
          .as_bool());
  EXPECT_EQ(s.call(s.service("ALAutonomousLife"), "getState", "()", {}).as_string(), "solitary");
  EXPECT_THROW(s.service("ALBasicAwareness"), qi::ServiceNotFound);
  // Resting and charging: a move is answered but the base stays still, and MoveFailed says why.
  s.call(motion, "move", "(fff)",
         {qi::Value::float32(0.2f), qi::Value::float32(0.f), qi::Value::float32(0.f)});
  EXPECT_FALSE(s.call(motion, "moveIsActive", "()", {}).as_bool());
  const auto failed = s.call(memory, "getData", "(s)", {qi::Value::string("ALMotion/MoveFailed")});
  EXPECT_NE(failed.unwrapped().elements().at(0).unwrapped().as_string().find("not awake"),
            std::string::npos);
  // Bad states are refused before serving.
  qi::MockServerOptions bad;
  bad.robot_state.battery_percent = 130;
  bad.robot_state.autonomous_life = "asleep";
  EXPECT_EQ(bad.validate().size(), 2u);
}

TEST(MockRobotState, NextRobotPositionIsWhereTheBaseStopsWhenStoppedNow) {
  Rig rig;
  qi::QiSession s;
  s.connect(rig.server->url());
  const auto motion = s.service("ALMotion");
  auto floats = [&](const char* m, std::vector<qi::Value> args, const char* sig) {
    std::vector<double> out;
    const qi::Value reply =
        s.call(motion, m, sig, std::move(args));  // kept: elements() refer to it
    for (const auto& e : reply.elements()) out.push_back(e.as_double());
    return out;
  };
  // Standing still: the same as getRobotPosition(false) (NAOqi's documented equality).
  const auto still = floats("getNextRobotPosition", {}, "()");
  const auto pos = floats("getRobotPosition", {qi::Value::boolean(false)}, "(b)");
  ASSERT_EQ(still.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_FLOAT_EQ(still[i], pos[i]);
  // Driving straight at 0.3 m/s: braking at 0.3 m/s^2 takes 0.15 m more.
  s.call(motion, "move", "(fff)",
         {qi::Value::float32(0.3f), qi::Value::float32(0.f), qi::Value::float32(0.f)});
  const auto now = floats("getRobotPosition", {qi::Value::boolean(false)}, "(b)");
  const auto next = floats("getNextRobotPosition", {}, "()");
  const double ahead = std::hypot(next[0] - now[0], next[1] - now[1]);
  EXPECT_NEAR(ahead, 0.15, 0.01);
  s.call(motion, "stopMove", "()", {});
}

TEST(QiSupervision, AMoveTheRobotDoesNotExecuteIsReportedWithItsCause) {
  Rig rig;
  qi::QiBridge bridge(rig.bridge_options());
  bridge.connect();
  ASSERT_TRUE(bridge.lock_head({}).holding);
  auto drive = [&] { bridge.move({0.15, 0.0, 0.0}); };
  std::vector<std::string> warnings;
  // Executed: read-backs agree, no warning.
  auto s = supervise_until(
      bridge, warnings,
      [](const auto& x) { return x.measured_velocity && x.move_active.value_or(false); }, drive);
  ASSERT_TRUE(s.measured_velocity.has_value());
  EXPECT_NEAR(s.measured_velocity->v_x_m_s, 0.15, 1e-6);
  EXPECT_FALSE(s.move_failing);
  // An obstacle: the robot keeps answering the moves but does not drive.
  rig.server->set_move_failure("Safety: obstacle in front (test)");
  s = supervise_until(
      bridge, warnings, [&](const auto&) { return contains(warnings, "obstacle in front"); },
      drive);
  EXPECT_TRUE(s.move_failing);
  EXPECT_TRUE(contains(warnings, "move failed")) << joined(warnings);
  EXPECT_TRUE(contains(warnings, "ALMotion/MoveFailed on the robot: Safety: obstacle in front"))
      << joined(warnings);
  EXPECT_EQ(bridge.counters().move_failures, 1u);
  // The obstacle goes away: the operator is told the moves are executed again.
  rig.server->set_move_failure("");
  s = supervise_until(
      bridge, warnings, [&](const auto& x) { return !x.move_failing; }, drive);
  EXPECT_FALSE(s.move_failing);
  EXPECT_TRUE(contains(warnings, "executes the commanded moves again")) << joined(warnings);
  bridge.stop();
}

TEST(QiSupervision, AHeadTakenBackByAutonomousLifeIsRetaken) {
  Rig rig;
  rig.server->take_head_back(0.0, false);  // start from a robot in solitary
  qi::QiBridge bridge(rig.bridge_options());
  bridge.connect();
  ASSERT_TRUE(bridge.lock_head({}).holding);
  ASSERT_EQ(rig.server->autonomous_life_state(), "disabled");
  std::vector<std::string> warnings;
  supervise_until(
      bridge, warnings, [](const auto&) { return false; }, {}, 200ms);
  EXPECT_TRUE(warnings.empty()) << joined(warnings);
  // Mid-session, Autonomous Life comes back and turns the head to a person.
  rig.server->take_head_back(0.6, false);
  auto s = supervise_until(bridge, warnings,
                           [&](const auto&) { return contains(warnings, "re-established"); });
  EXPECT_TRUE(contains(warnings, "took the head back")) << joined(warnings);
  EXPECT_TRUE(contains(warnings, "re-established")) << joined(warnings);
  EXPECT_FALSE(s.head_lock_lost);
  EXPECT_EQ(rig.server->autonomous_life_state(), "disabled");
  EXPECT_FALSE(rig.server->basic_awareness_enabled());
  EXPECT_EQ(bridge.counters().head_retakes, 1u);
  bridge.move({0.1, 0.0, 0.0});  // still allowed
  bridge.stop();
}

TEST(QiSupervision, AHeadThatCannotBeHeldStopsTheBaseAndIsReportedLost) {
  Rig rig;
  qi::QiBridge bridge(rig.bridge_options());
  bridge.connect();
  ASSERT_TRUE(bridge.lock_head({}).holding);
  auto drive = [&] {
    try {
      bridge.move({0.15, 0.0, 0.0});
    } catch (const nb::BridgeError&) {
      // refused once the lock is lost: that is the point
    }
  };
  std::vector<std::string> warnings;
  supervise_until(
      bridge, warnings, [](const auto& x) { return x.measured_velocity.has_value(); }, drive);
  rig.server->take_head_back(0.6, /*sticky=*/true);
  const auto s = supervise_until(
      bridge, warnings, [](const auto& x) { return x.head_lock_lost; }, drive);
  ASSERT_TRUE(s.head_lock_lost) << joined(warnings);
  EXPECT_NE(s.head_lock_detail.find("head lock lost"), std::string::npos);
  EXPECT_NE(s.head_lock_detail.find("Autonomous Life is 'solitary'"), std::string::npos)
      << s.head_lock_detail;
  EXPECT_TRUE(contains(warnings, "took the head back")) << joined(warnings);
  // The base was stopped by the bridge and further moves are refused.
  const auto v = robot_velocity(rig.server->url());
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v[0], 0.0);
  EXPECT_EQ(v[2], 0.0);
  EXPECT_THROW(bridge.move({0.15, 0.0, 0.0}), nb::BridgeError);
  EXPECT_TRUE(bridge.needs_operator());
}

// With the default period (500 ms) and rules: how long from the robot's misbehaviour to the
// operator's warning / the stop. Generous bounds; the figures are printed ("[measured]").
TEST(QiSupervision, DefaultTimingFromMisbehaviourToWarningAndStop) {
  Rig rig;
  qi::QiBridgeOptions o = rig.bridge_options();
  o.supervise_period = qi::QiBridgeOptions{}.supervise_period;
  o.supervisor = qi::MotionSupervisorOptions{};
  qi::QiBridge bridge(o);
  bridge.connect();
  ASSERT_TRUE(bridge.lock_head({}).holding);
  auto drive = [&] {
    try {
      bridge.move({0.15, 0.0, 0.0});
    } catch (const nb::BridgeError&) {
    }
  };
  std::vector<std::string> warnings;
  // Driving for a while first: the command is settled when the failure starts.
  supervise_until(
      bridge, warnings, [](const auto&) { return false; }, drive, 1000ms);
  ASSERT_TRUE(warnings.empty()) << joined(warnings);
  auto t0 = std::chrono::steady_clock::now();
  rig.server->set_move_failure("Safety: obstacle (timing)");
  supervise_until(
      bridge, warnings, [&](const auto&) { return contains(warnings, "move failed"); }, drive,
      10000ms);
  const double warn_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_TRUE(contains(warnings, "move failed")) << joined(warnings);
  EXPECT_LT(warn_ms, 5000.0);
  rig.server->set_move_failure("");
  t0 = std::chrono::steady_clock::now();
  rig.server->take_head_back(0.6, /*sticky=*/true);
  const auto s = supervise_until(
      bridge, warnings, [](const auto& x) { return x.head_lock_lost; }, drive, 10000ms);
  const double lost_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_TRUE(s.head_lock_lost);
  EXPECT_LT(lost_ms, 5000.0);
  std::cout << "[measured] move failure -> warning: " << warn_ms
            << " ms; head taken (sticky) -> base stopped, head_lock_lost: " << lost_ms << " ms\n";
}
