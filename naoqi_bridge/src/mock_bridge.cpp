// In-process RobotBridge over a sim::SimRobot (see mock_bridge.hpp).
#include "naoqi_bridge/mock_bridge.hpp"

#include <algorithm>
#include <cmath>

namespace pepper::naoqi_bridge {

namespace {

/// Runs `call` on the simulated robot; a request it refuses (sim::SimError) becomes the
/// BridgeError that every RobotBridge caller handles, with the same text.
template <typename Call>
auto on_robot(Call&& call) -> decltype(call()) {
  try {
    return call();
  } catch (const sim::SimError& e) {
    throw BridgeError(e.what());
  }
}

}  // namespace

MockBridge::MockBridge(sim::SimRobot& robot, MockBridgeOptions options)
    : robot_(robot), options_(std::move(options)), wifi_(options_.wifi) {}

void MockBridge::connect() {
  std::lock_guard lock(mutex_);
  state_ = ConnectionState::kConnected;
}

core::CameraIntrinsics MockBridge::start_camera(const CameraRequest& request) {
  std::lock_guard lock(mutex_);
  if (state_ != ConnectionState::kConnected)
    throw BridgeError("MockBridge::start_camera: not connected");
  if (request.camera_index != 0)
    throw BridgeError("MockBridge::start_camera: only camera 0 (CameraTop) is simulated, got " +
                      std::to_string(request.camera_index));
  if (request.width_px <= 0 || request.height_px <= 0 || request.width_px > 4096 ||
      request.height_px > 4096)
    throw BridgeError("MockBridge::start_camera: bad size " + std::to_string(request.width_px) +
                      "x" + std::to_string(request.height_px));
  camera_ = request;
  return on_robot([&] { return robot_.intrinsics(request.width_px, request.height_px); });
}

std::optional<core::Frame> MockBridge::next_frame(std::chrono::milliseconds /*timeout*/) {
  std::lock_guard lock(mutex_);
  if (state_ != ConnectionState::kConnected)
    throw BridgeError("MockBridge::next_frame: not connected");
  if (!camera_) throw BridgeError("MockBridge::next_frame: camera not started");
  core::Frame frame =
      on_robot([&] { return robot_.capture(camera_->width_px, camera_->height_px); });
  // The wheel odometry at the capture's time (the simulated clock has not moved since): what
  // QiBridge reads with ALMotion.getRobotPosition(true) for each frame.
  frame.odom = robot_.odometry(sim::OdometrySource::kWheels);
  return wifi_.transmit(frame, robot_.now_ns());
}

std::chrono::nanoseconds MockBridge::stall_clock() const {
  std::lock_guard lock(mutex_);
  return std::chrono::nanoseconds(robot_.now_ns());
}

HeadLockStatus MockBridge::lock_head(const HeadLockRequest& request) {
  std::lock_guard lock(mutex_);
  if (state_ != ConnectionState::kConnected)
    throw BridgeError("MockBridge::lock_head: not connected");
  const auto angles = on_robot([&] {
    robot_.set_joint_angles({"HeadYaw", "HeadPitch"},
                            {request.head_yaw_rad, request.head_pitch_rad});
    return robot_.joint_angles({"HeadYaw", "HeadPitch"});
  });
  HeadLockStatus s;
  s.head_yaw_rad = angles.at(0);
  s.head_pitch_rad = angles.at(1);
  s.max_error_rad = std::max(std::abs(angles[0] - request.head_yaw_rad),
                             std::abs(angles[1] - request.head_pitch_rad));
  s.holding = s.max_error_rad <= request.tolerance_rad;
  return s;
}

void MockBridge::move(const BaseVelocity& velocity) {
  std::lock_guard lock(mutex_);
  if (state_ != ConnectionState::kConnected) throw BridgeError("MockBridge::move: not connected");
  robot_.command_velocity(velocity);
  log_.push_back({robot_.now_ns(), velocity, false});
}

void MockBridge::stop() noexcept {
  try {
    std::lock_guard lock(mutex_);
    robot_.stop_move();
    log_.push_back({robot_.now_ns(), BaseVelocity{}, true});
  } catch (...) {
    // Best effort by contract; the simulated base cannot fail to stop.
  }
}

void MockBridge::release() noexcept {
  stop();
  try {
    std::lock_guard lock(mutex_);
    camera_.reset();
  } catch (...) {
  }
}

ConnectionState MockBridge::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

std::string MockBridge::describe() const { return options_.description; }

std::vector<sim::CommandRecord> MockBridge::log() const {
  std::lock_guard lock(mutex_);
  return log_;
}

int64_t MockBridge::frames_dropped() const {
  std::lock_guard lock(mutex_);
  return wifi_.dropped();
}

}  // namespace pepper::naoqi_bridge
