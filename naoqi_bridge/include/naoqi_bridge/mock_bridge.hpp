#pragma once
// MockBridge: RobotBridge over any sim::SimRobot, in-process (no sockets). The app and the
// evaluation drive a simulated Pepper exactly as they drive the real one.
//
// Semantics: connect() only changes the state; start_camera() records the requested size (the
// frame rate is the SimRobot's own lockstep rate); next_frame() captures one frame (advancing the
// simulated clock one frame period) and passes it through the WiFi model, so it returns nullopt
// when that frame is dropped or still in flight; each frame carries the robot's wheel odometry
// read right after its capture (Frame::odom, SimRobot::odometry(kWheels)); lock_head() sets
// HeadYaw/HeadPitch and reads them back; move() forwards to command_velocity(); stop() calls
// stop_move() and never throws. Every call that reaches the base is appended to log() with the
// simulated time. Failure: calls before connect() (or next_frame() before start_camera()) throw
// BridgeError; so does a request the simulated robot refuses (its sim::SimError, with the same
// text). Thread-safety: methods lock an internal mutex; stop() may be called from any thread.

#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "naoqi_bridge/robot_bridge.hpp"
#include "sim/sim_robot.hpp"
#include "sim/wifi_model.hpp"

namespace pepper::naoqi_bridge {

struct MockBridgeOptions {
  sim::WifiOptions wifi;  ///< no drops, no delay by default
  std::string description = "mock:in-process";
};

class MockBridge final : public RobotBridge {
 public:
  /// Does not take ownership: `robot` must outlive the bridge.
  explicit MockBridge(sim::SimRobot& robot, MockBridgeOptions options = {});

  void connect() override;
  core::CameraIntrinsics start_camera(const CameraRequest& request) override;
  std::optional<core::Frame> next_frame(std::chrono::milliseconds timeout) override;
  /// The simulated time (SimRobot::now_ns): a stall is one of the simulated camera.
  std::chrono::nanoseconds stall_clock() const override;
  HeadLockStatus lock_head(const HeadLockRequest& request) override;
  void move(const BaseVelocity& velocity) override;
  void stop() noexcept override;
  void release() noexcept override;
  ConnectionState state() const override;
  std::string describe() const override;

  /// Every base command sent through this bridge (move and stop), in order.
  std::vector<sim::CommandRecord> log() const;
  /// Frames lost by the WiFi model so far.
  int64_t frames_dropped() const;

 private:
  sim::SimRobot& robot_;
  MockBridgeOptions options_;
  mutable std::mutex mutex_;
  sim::WifiModel wifi_;
  ConnectionState state_ = ConnectionState::kDisconnected;
  std::optional<CameraRequest> camera_;
  std::vector<sim::CommandRecord> log_;
};

}  // namespace pepper::naoqi_bridge
