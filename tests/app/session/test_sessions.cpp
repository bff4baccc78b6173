// Safety of the teach and replay session loops (issue 6), in-process on the mock robot
// (MockRobot + MockBridge): every way out of a loop ends with a stop sent to the base.
// The core is replaced by a scripted step function where a fault must be injected.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

#include "naoqi_bridge/mock_bridge.hpp"
#include "session/recording.hpp"
#include "session/replay_session.hpp"
#include "session/signals.hpp"
#include "session/teach_session.hpp"

namespace pepper::app {
namespace {

namespace nb = naoqi_bridge;
namespace nav = core::navigator;

const std::string kWorld = std::string("mock:") + PEPPER_SOURCE_DIR + "/worlds/robotics_room.yaml";

std::filesystem::path fresh_dir(const std::string& name) {
  auto p = std::filesystem::temp_directory_path() / ("pepper_session_test_" + name);
  std::filesystem::remove_all(p);
  return p;
}

nb::CameraRequest qvga() {
  nb::CameraRequest r;
  r.width_px = 320;
  r.height_px = 240;
  return r;
}

/// A map whose camera matches the mock's QVGA camera; its key images are never used because the
/// tests replace the navigator's step.
core::memory::VisualMemory dummy_map(const RobotConnection& robot) {
  core::memory::VisualMemory m;
  m.camera = robot.mock->intrinsics(320, 240);
  m.key_images.resize(2);
  return m;
}

/// Moves forward every frame (a navigator that is happily driving).
nav::StepResult driving_step(const core::Frame& f) {
  nav::StepResult r;
  r.command = {0.2, 0.05, false, nav::StopReason::kNone};
  r.telemetry.t_ns = f.t_ns;
  r.telemetry.state = nav::NavState::kNavigating;
  r.telemetry.in = 1;
  return r;
}

/// Drives for `frames` frames, then stops for lost features on every frame (counts in `n`).
StepFunction drives_then_loses(int frames, int& n) {
  return [frames, &n](const core::Frame& f) {
    nav::StepResult s = driving_step(f);
    if (++n > frames) s.command = {0.0, 0.0, true, nav::StopReason::kFeaturesLost};
    return s;
  };
}

bool last_is_stop(const sim::MockRobot& robot) {
  const auto log = robot.command_log();
  if (log.empty()) return false;
  const auto& c = log.back();
  return c.stop_move || (c.velocity.v_x_m_s == 0.0 && c.velocity.omega_rad_s == 0.0);
}

bool ever_moved(const sim::MockRobot& robot) {
  for (const auto& c : robot.command_log())
    if (!c.stop_move && c.velocity.v_x_m_s > 0.0) return true;
  return false;
}

ReplaySessionOptions replay_options() {
  ReplaySessionOptions o;
  o.camera = qvga();
  o.frame_timeout_ms = 200;
  o.max_frames = 200;  // a broken test ends anyway
  return o;
}

TEST(ReplaySessionSafety, ExceptionFromCoreEndsWithStop) {
  RobotConnection robot = open_robot(kWorld, {});
  SessionLink link(nullptr, nullptr);
  int n = 0;
  const ReplayResult r = run_replay_session(
      robot, dummy_map(robot), replay_options(), link, [&](const core::Frame& f) {
        if (++n == 6) throw std::runtime_error("injected core failure");
        return driving_step(f);
      });
  EXPECT_EQ(r.outcome, "error");
  EXPECT_NE(r.error.find("injected"), std::string::npos);
  EXPECT_TRUE(ever_moved(*robot.mock));
  EXPECT_TRUE(last_is_stop(*robot.mock));
}

/// Passes every call to the bridge it wraps, but the stall clock: the steady clock, as a real
/// robot's bridge has (RobotBridge's own).
class ForwardingBridge : public nb::RobotBridge {
 public:
  explicit ForwardingBridge(std::unique_ptr<nb::RobotBridge> inner) : inner_(std::move(inner)) {}
  void connect() override { inner_->connect(); }
  core::CameraIntrinsics start_camera(const nb::CameraRequest& r) override {
    return inner_->start_camera(r);
  }
  std::optional<core::Frame> next_frame(std::chrono::milliseconds timeout) override {
    return inner_->next_frame(timeout);
  }
  nb::HeadLockStatus lock_head(const nb::HeadLockRequest& r) override {
    return inner_->lock_head(r);
  }
  void move(const nb::BaseVelocity& v) override { inner_->move(v); }
  void stop() noexcept override { inner_->stop(); }
  void release() noexcept override { inner_->release(); }
  nb::ConnectionState state() const override { return inner_->state(); }
  std::string describe() const override { return "forwarding " + inner_->describe(); }

 protected:
  std::unique_ptr<nb::RobotBridge> inner_;
};

/// Delivers `good_frames` frames, then none (a camera that stalls).
class StallingBridge final : public ForwardingBridge {
 public:
  StallingBridge(std::unique_ptr<nb::RobotBridge> inner, int good_frames)
      : ForwardingBridge(std::move(inner)), left_(good_frames) {}
  std::optional<core::Frame> next_frame(std::chrono::milliseconds timeout) override {
    if (left_-- > 0) return inner_->next_frame(timeout);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    return std::nullopt;
  }

 private:
  int left_;
};

TEST(ReplaySessionSafety, StalledFramesStop) {
  RobotConnection robot = open_robot(kWorld, {});
  robot.bridge = std::make_unique<StallingBridge>(std::move(robot.bridge), 8);
  SessionLink link(nullptr, nullptr);
  const ReplayResult r =
      run_replay_session(robot, dummy_map(robot), replay_options(), link, driving_step);
  EXPECT_EQ(r.outcome, "frame_timeout");
  EXPECT_EQ(r.frames, 8);
  EXPECT_TRUE(ever_moved(*robot.mock));
  EXPECT_TRUE(last_is_stop(*robot.mock));
}

/// A simulated robot's link whose laptop freezes once: after `good_frames` frames, the next call
/// takes `pause` of wall time and its frame is lost on the way (a WiFi drop); the simulated camera
/// went on at its own rate meanwhile, and later frames arrive again. Its stall clock is the
/// simulated robot's.
class PausedProcessBridge final : public ForwardingBridge {
 public:
  PausedProcessBridge(std::unique_ptr<nb::RobotBridge> inner, int good_frames,
                      std::chrono::milliseconds pause)
      : ForwardingBridge(std::move(inner)), left_(good_frames), pause_(pause) {}
  std::optional<core::Frame> next_frame(std::chrono::milliseconds timeout) override {
    auto frame = inner_->next_frame(timeout);
    if (left_-- == 0) {
      std::this_thread::sleep_for(pause_);
      return std::nullopt;
    }
    return frame;
  }
  std::chrono::nanoseconds stall_clock() const override { return inner_->stall_clock(); }

 private:
  int left_;
  std::chrono::milliseconds pause_;
};

// On a simulated robot the camera stall is measured on the simulated clock: a laptop process
// paused for longer than frame_timeout (SIGSTOP, a loaded machine) right before a dropped frame
// is not a stall of the simulated camera (an evaluation once ended a run with frame_timeout so).
// On a real robot the steady clock decides (StalledFramesStop above: the default stall_clock).
TEST(ReplaySessionSafety, APausedProcessIsNoStallOfASimulatedCamera) {
  reset_interrupt();
  RobotConnection robot = open_robot(kWorld, {});
  ReplaySessionOptions o = replay_options();
  robot.bridge = std::make_unique<PausedProcessBridge>(
      std::move(robot.bridge), 8, std::chrono::milliseconds(o.frame_timeout_ms + 150));
  SessionLink link(nullptr, nullptr);
  int n = 0;
  const ReplayResult r = run_replay_session(robot, dummy_map(robot), o, link,
                                            [&](const core::Frame& f) {
                                              if (++n == 20) request_interrupt();
                                              return driving_step(f);
                                            });
  reset_interrupt();
  EXPECT_EQ(r.outcome, "interrupted");
  EXPECT_EQ(n, 20);
  EXPECT_TRUE(last_is_stop(*robot.mock));
}

TEST(ReplaySessionSafety, UiStopStops) {
  RobotConnection robot = open_robot(kWorld, {});
  SessionLink link(nullptr, nullptr);
  int frames = 0;
  bool pressed = false;
  link.set_intent_source([&]() -> std::optional<teach_ui::Intent> {
    if (frames < 10 || pressed) return std::nullopt;
    pressed = true;
    teach_ui::Intent i;
    i.kind = teach_ui::IntentKind::kEmergencyStop;
    i.reason = "button";
    return i;
  });
  const ReplayResult r = run_replay_session(robot, dummy_map(robot), replay_options(), link,
                                            [&](const core::Frame& f) {
                                              ++frames;
                                              return driving_step(f);
                                            });
  EXPECT_EQ(r.outcome, "ui_stop");
  EXPECT_EQ(r.frames, 10);
  EXPECT_TRUE(ever_moved(*robot.mock));
  EXPECT_TRUE(last_is_stop(*robot.mock));
}

TEST(ReplaySessionSafety, InterruptFlagStops) {
  reset_interrupt();
  RobotConnection robot = open_robot(kWorld, {});
  SessionLink link(nullptr, nullptr);
  int n = 0;
  const ReplayResult r = run_replay_session(robot, dummy_map(robot), replay_options(), link,
                                            [&](const core::Frame& f) {
                                              if (++n == 7) request_interrupt();
                                              return driving_step(f);
                                            });
  reset_interrupt();
  EXPECT_EQ(r.outcome, "interrupted");
  EXPECT_TRUE(ever_moved(*robot.mock));
  EXPECT_TRUE(last_is_stop(*robot.mock));
}

TEST(ReplaySessionSafety, NavigatorStopReasonSendsStop) {
  RobotConnection robot = open_robot(kWorld, {});
  SessionLink link(nullptr, nullptr);
  int n = 0;
  ReplaySessionOptions o = replay_options();
  o.max_frames = 12;
  const ReplayResult r =
      run_replay_session(robot, dummy_map(robot), o, link, drives_then_loses(5, n));
  EXPECT_EQ(r.outcome, "max_frames");
  const auto log = robot.mock->command_log();
  ASSERT_GE(log.size(), 6u);
  EXPECT_TRUE(log.back().stop_move);
}

// A replay that can never localise ends by itself with the best candidate and advice, instead of
// waiting with the robot standing still (issue 30); the base never moved.
TEST(ReplaySessionSafety, NotLocalisedGivesUpWithAdvice) {
  RobotConnection robot = open_robot(kWorld, {});
  std::ostringstream events;
  SessionLink link(nullptr, &events);
  ReplaySessionOptions o = replay_options();
  o.max_frames = 0;
  o.give_up_not_localised_s = 2.0;
  int n = 0;
  const ReplayResult r =
      run_replay_session(robot, dummy_map(robot), o, link, [&](const core::Frame& f) {
        ++n;
        nav::StepResult s;
        s.command = {0.0, 0.0, true, nav::StopReason::kNotLocalized};
        s.telemetry.t_ns = f.t_ns;
        s.telemetry.localization_ran = true;
        s.telemetry.localization_best = 1;
        s.telemetry.localization_best_count = 7;
        return s;
      });
  EXPECT_EQ(r.outcome, "not_localised");
  EXPECT_NE(r.detail.find("key image 1 with 7"), std::string::npos) << r.detail;
  EXPECT_NE(r.detail.find("place the robot"), std::string::npos) << r.detail;
  // 15 fps: just over 2 s of frames (the first frame is t = 0).
  EXPECT_GE(n, 31);
  EXPECT_LE(n, 33);
  EXPECT_FALSE(ever_moved(*robot.mock));
  EXPECT_TRUE(last_is_stop(*robot.mock));
  // Meanwhile the operator saw the search, once a second: the best candidate and the threshold.
  int localising = 0;
  std::istringstream lines(events.str());
  for (std::string line; std::getline(lines, line);) {
    const auto e = nlohmann::json::parse(line, nullptr, false);
    if (!e.is_object() || e.value("event", "") != "localising") continue;
    ++localising;
    EXPECT_EQ(e["best_key_image"], 1);
    EXPECT_EQ(e["verified_matches"], 7);
    EXPECT_GT(e["needed"].get<int>(), 7);
  }
  EXPECT_GE(localising, 2);
  EXPECT_LE(localising, 3);
}

// The not-localised verdict names the best candidate of the whole wait, not the last attempt's
// (the robot stood still: 9 matches with key image 3 early on are better evidence than 2 with key
// image 1 at the end).
TEST(ReplaySessionSafety, NotLocalisedNamesTheBestCandidateOfTheWait) {
  RobotConnection robot = open_robot(kWorld, {});
  SessionLink link(nullptr, nullptr);
  ReplaySessionOptions o = replay_options();
  o.max_frames = 0;
  o.give_up_not_localised_s = 2.0;
  int n = 0;
  const ReplayResult r =
      run_replay_session(robot, dummy_map(robot), o, link, [&](const core::Frame& f) {
        const bool early = n++ < 10;
        nav::StepResult s;
        s.command = {0.0, 0.0, true, nav::StopReason::kNotLocalized};
        s.telemetry.t_ns = f.t_ns;
        s.telemetry.localization_ran = true;
        s.telemetry.localization_best = early ? 3 : 1;
        s.telemetry.localization_best_count = early ? 9 : 2;
        return s;
      });
  EXPECT_EQ(r.outcome, "not_localised");
  EXPECT_NE(r.detail.find("best candidate: key image 3 with 9 verified matches"),
            std::string::npos)
      << r.detail;
}

// Stopped for any reason after driving (lost features, overdue segment ...) for longer than the
// give-up time: the replay ends as "lost" with the base stopped.
TEST(ReplaySessionSafety, StoppedAfterDrivingGivesUp) {
  RobotConnection robot = open_robot(kWorld, {});
  SessionLink link(nullptr, nullptr);
  ReplaySessionOptions o = replay_options();
  o.max_frames = 0;
  o.give_up_lost_s = 1.0;
  int n = 0;
  const ReplayResult r =
      run_replay_session(robot, dummy_map(robot), o, link, drives_then_loses(10, n));
  EXPECT_EQ(r.outcome, "lost");
  EXPECT_NE(r.detail.find("features_lost"), std::string::npos) << r.detail;
  EXPECT_GE(n, 10 + 15);
  EXPECT_LE(n, 10 + 17);
  EXPECT_TRUE(ever_moved(*robot.mock));
  EXPECT_TRUE(last_is_stop(*robot.mock));
}

/// Ends the replay at a given frame, records what it saw.
class EndingMonitor final : public ReplayMonitor {
 public:
  explicit EndingMonitor(int end_at) : end_at_(end_at) {}
  std::optional<ReplayEnd> after_iteration(const nav::StepResult* step,
                                           const ReplaySample* sample) override {
    ++calls;
    if (step && sample) {
      ++steps;
      EXPECT_EQ(sample->v_m_s, step->command.v_m_s);
      EXPECT_GE(sample->step_ms, 0.0);
    }
    if (steps == end_at_) return ReplayEnd{"diverged", "left the path"};
    return std::nullopt;
  }
  int calls = 0, steps = 0;

 private:
  int end_at_;
};

// The evaluation's monitor sees every frame after its command was sent, and the end it asks for
// stops the base like every other way out.
TEST(ReplaySessionSafety, MonitorEndStopsTheBase) {
  RobotConnection robot = open_robot(kWorld, {});
  SessionLink link(nullptr, nullptr);
  EndingMonitor monitor(9);
  ReplaySessionOptions o = replay_options();
  o.monitor = &monitor;
  const ReplayResult r = run_replay_session(robot, dummy_map(robot), o, link, driving_step);
  EXPECT_EQ(r.outcome, "diverged");
  EXPECT_EQ(r.detail, "left the path");
  EXPECT_EQ(monitor.steps, 9);
  EXPECT_EQ(r.frames, 9);
  EXPECT_TRUE(ever_moved(*robot.mock));
  EXPECT_TRUE(last_is_stop(*robot.mock));
}

TEST(ReplaySessionSafety, WrongCameraSizeRefusedBeforeMoving) {
  RobotConnection robot = open_robot(kWorld, {});
  SessionLink link(nullptr, nullptr);
  core::memory::VisualMemory map = dummy_map(robot);
  map.camera = robot.mock->intrinsics(640, 480);
  const ReplayResult r = run_replay_session(robot, map, replay_options(), link, driving_step);
  EXPECT_EQ(r.outcome, "error");
  EXPECT_NE(r.error.find("640x480"), std::string::npos) << r.error;
  EXPECT_FALSE(ever_moved(*robot.mock));
}

TeachSessionOptions teach_options(const std::string& name) {
  TeachSessionOptions o;
  o.map_dir = fresh_dir(name + "_map");
  o.recording_dir = fresh_dir(name + "_rec");
  o.camera = qvga();
  return o;
}

TEST(TeachSessionSafety, InterruptStopsKeepsRecordingAndSavesMap) {
  reset_interrupt();
  RobotConnection robot = open_robot(kWorld, {});
  TeachSessionOptions o = teach_options("interrupt");
  o.scripted = true;
  SessionLink link(nullptr, nullptr);
  int polls = 0;
  link.set_intent_source([&]() -> std::optional<teach_ui::Intent> {
    if (++polls == 25) request_interrupt();  // about 24 frames into the drive
    return std::nullopt;
  });
  const TeachResult r = run_teach_session(robot, o, link);
  reset_interrupt();
  EXPECT_EQ(r.outcome, "interrupted");
  EXPECT_TRUE(ever_moved(*robot.mock));
  EXPECT_TRUE(last_is_stop(*robot.mock));
  EXPECT_TRUE(r.map_saved);
  const Recording rec = read_recording(o.recording_dir, std::nullopt);
  EXPECT_EQ(static_cast<int64_t>(rec.frames.size()), r.frames_recorded);
  EXPECT_GE(rec.frames.size(), 20u);
  const auto map = core::memory::load_map(o.map_dir);
  EXPECT_GE(map.key_images.size(), 2u);
}

TEST(TeachSessionSafety, OperatorDriveNeedsRefreshing) {
  RobotConnection robot = open_robot(kWorld, {});
  TeachSessionOptions o = teach_options("deadman");
  o.max_frames = 100;
  o.pace_hz = 50;           // 100 frames = 2 s of wall time
  // One drive intent, never refreshed. 0.3 s, not less: on a loaded 2-core machine (three
  // evaluations beside the suite) 0.1 s expired before the first move was sent.
  o.drive_timeout_s = 0.3;
  SessionLink link(nullptr, nullptr);
  bool sent = false;
  link.set_intent_source([&]() -> std::optional<teach_ui::Intent> {
    if (sent) return std::nullopt;
    sent = true;
    teach_ui::Intent i;
    i.kind = teach_ui::IntentKind::kDrive;
    i.v_m_s = 0.1;
    return i;
  });
  const TeachResult r = run_teach_session(robot, o, link);
  EXPECT_EQ(r.outcome, "finished");
  EXPECT_TRUE(ever_moved(*robot.mock));
  // The dead-man stopped it long before the end of the session: a stop follows the move.
  const auto log = robot.mock->command_log();
  int moves = 0;
  for (const auto& c : log) moves += (!c.stop_move && c.velocity.v_x_m_s > 0) ? 1 : 0;
  EXPECT_LT(moves, 50);  // 0.3 s is 15 frames at 50 Hz; half the session at most
  EXPECT_TRUE(last_is_stop(*robot.mock));
}

TEST(TeachSessionSafety, ScriptedNeedsMockRobot) {
  RobotConnection robot = open_robot(kWorld, {});
  const auto keep_alive = robot.mock;  // the bridge refers to it
  robot.mock.reset();                   // pretend it is a real robot
  TeachSessionOptions o = teach_options("scripted_real");
  o.scripted = true;
  SessionLink link(nullptr, nullptr);
  EXPECT_THROW(run_teach_session(robot, o, link), std::invalid_argument);
}

TEST(RobotUrl, ParsesAndNormalises) {
  EXPECT_EQ(parse_robot_url("tcp://10.0.0.5").url, "tcp://10.0.0.5:9559");
  EXPECT_EQ(parse_robot_url("tcps://pepper.local").kind, RobotUrl::Kind::kTcps);
  EXPECT_EQ(parse_robot_url("mock:w.yaml").world_file, "w.yaml");
  EXPECT_THROW(parse_robot_url("http://x"), RobotUrlError);  // a usage error: exit 2
  EXPECT_THROW(parse_robot_url("mock:"), RobotUrlError);
}

// tcps:// logs in as Pepper's user "nao" unless told otherwise, with the password from
// PEPPER_PASSWORD when no file is given (issue 23: doctor read it only with --user, and then
// logged in with an empty user); tcp:// without a user does not log in.
TEST(RobotLogin, TlsDefaultsToNaoAndReadsTheEnvironment) {
  ::setenv("PEPPER_PASSWORD", "from-env", 1);
  const RobotLogin tls = robot_login(true, "", "", false, "tcps://10.0.0.5:9503");
  EXPECT_EQ(tls.user, "nao");
  EXPECT_EQ(tls.password, "from-env");
  const RobotLogin other = robot_login(true, "admin", "", false, "tcps://10.0.0.5:9503");
  EXPECT_EQ(other.user, "admin");
  const RobotLogin plain = robot_login(false, "", "", false, "tcp://10.0.0.5:9559");
  EXPECT_TRUE(plain.user.empty());
  EXPECT_TRUE(plain.password.empty());
  ::unsetenv("PEPPER_PASSWORD");
  // No password anywhere and no terminal: a clear error, never an empty password.
  EXPECT_THROW(robot_login(true, "", "", false, "tcps://10.0.0.5:9503"), naoqi_bridge::BridgeError);
}

}  // namespace
}  // namespace pepper::app
