#pragma once
// RobotBridge: the one interface through which the app talks to a robot, real or simulated.
//
// Implementations: QiBridge (real Pepper over qi messaging, tcp:// or tcps://), MockBridge
// (in-process simulated robot, no sockets) and QiBridge pointed at our mock NAOqi server.
//
// Units and frames (docs/conventions.md): base velocities in the robot frame, x forward, y left,
// omega > 0 turns left (counter-clockwise seen from above), as ALMotion.move(x, y, theta).
//
// Threading: every method may be called from the app's session thread; implementations guard
// their own state. stop() may additionally be called from any thread (signal handler relay,
// watchdog, UI) and must be safe to call at any time, any number of times.
//
// Failure: environment problems (lost connection, refused call) throw BridgeError (or a subclass)
// from the calling method. stop() never throws: it makes a best effort and reports through state().

#include <chrono>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/base_velocity.hpp"
#include "core/camera/intrinsics.hpp"
#include "core/frame.hpp"

namespace pepper::naoqi_bridge {

/// Any failure to reach or use the robot. `what()` names the service/method where it applies.
class BridgeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Velocity of the base in the robot frame (core/base_velocity.hpp: shared with the simulator).
using BaseVelocity = core::BaseVelocity;

/// What the app asks of the camera stream.
struct CameraRequest {
  int camera_index = 0;  ///< 0 = top head camera (CameraTop)
  int width_px = 640;    ///< 640x480 (kVGA) by default; 320x240 (kQVGA) also supported
  int height_px = 480;
  int fps = 15;
};

/// Head and leg joints held fixed so that the camera is rigid on the base.
struct HeadLockRequest {
  double head_yaw_rad = 0.0;
  double head_pitch_rad = 0.0;  ///< > 0 looks down (URDF range -0.707 .. 0.637)
  double tolerance_rad = 0.05;  ///< read-back error above which the lock counts as not holding
};

struct HeadLockStatus {
  bool holding = false;          ///< every locked joint within tolerance of its target
  double head_yaw_rad = 0.0;     ///< read back from the robot
  double head_pitch_rad = 0.0;   ///< read back from the robot
  double max_error_rad = 0.0;    ///< largest |target - measured| over the locked joints
};

/// What the robot itself shows during a session (RobotBridge::supervise()): whether it executes
/// the commanded velocity and whether the head lock still holds.
struct RobotSupervision {
  /// The head lock cannot be held (Autonomous Life or awareness keeps taking the head back, or
  /// the head stays off its target). The bridge has already stopped the base and refuses moves;
  /// the session must end and tell the operator `head_lock_detail`.
  bool head_lock_lost = false;
  std::string head_lock_detail;
  /// New since the last call, one sentence each for the operator: a move the robot does not
  /// execute (and again when it does), a head lock taken back by the robot and re-established.
  std::vector<std::string> warnings;
  /// Latest read-back of the robot's own motion state (ALMotion.getRobotVelocity, moveIsActive);
  /// empty until the first read-back.
  std::optional<BaseVelocity> measured_velocity;
  std::optional<bool> move_active;
  /// The robot is not executing the commanded velocity now (a move failure in progress).
  bool move_failing = false;
};

enum class ConnectionState { kDisconnected, kConnecting, kConnected, kLost };

const char* to_string(ConnectionState state);

class RobotBridge {
 public:
  virtual ~RobotBridge() = default;
  RobotBridge() = default;
  RobotBridge(const RobotBridge&) = delete;
  RobotBridge& operator=(const RobotBridge&) = delete;

  /// Opens the connection (and logs in where needed). Throws BridgeError on failure.
  virtual void connect() = 0;

  /// Starts streaming frames with the given request; returns the intrinsics of the delivered size.
  virtual core::CameraIntrinsics start_camera(const CameraRequest& request) = 0;

  /// The next frame newer than the previous one returned, or nullopt if none arrived within
  /// `timeout`. Frames carry the robot's capture timestamp and, where the robot gives it, its
  /// odometry read with the frame (Frame::odom; a failure to read it leaves it empty and is not
  /// an error: odometry_problem()). Throws BridgeError on a lost link.
  virtual std::optional<core::Frame> next_frame(std::chrono::milliseconds timeout) = 0;

  /// The clock a session measures a camera stall on ("no frame for frame_timeout_s"): the
  /// laptop's steady clock for a real robot (a frozen or overloaded laptop sees the stall it
  /// caused, and stops the base); a simulated robot's own time for a simulated one, where a
  /// paused or loaded evaluation process would otherwise see a stall the simulated camera never
  /// had. Any epoch; only differences count.
  virtual std::chrono::nanoseconds stall_clock() const {
    return std::chrono::steady_clock::now().time_since_epoch();
  }

  /// Stiffens and holds head (and hip/knee) joints, turns autonomous head motion off, and reads
  /// the angles back. The previous autonomy state is restored by release().
  virtual HeadLockStatus lock_head(const HeadLockRequest& request) = 0;

  /// Commands a base velocity (lasts until the next command; implementations add a watchdog).
  virtual void move(const BaseVelocity& velocity) = 0;

  /// Stops the base now (move(0,0,0) then stopMove on a real robot). Never throws.
  virtual void stop() noexcept = 0;

  /// Stops the base, unsubscribes the camera and restores autonomy settings. Never throws.
  virtual void release() noexcept = 0;

  virtual ConnectionState state() const = 0;

  /// Human-readable description of where the bridge is connected, e.g. "tcp://10.0.0.5:9559".
  virtual std::string describe() const = 0;

  /// Non-blocking check of the robot's own state, called by sessions once per loop iteration:
  /// reads back what the base executes and whether the head lock holds (a few asynchronous calls
  /// at a fixed period), re-takes the head when the robot took it back, and stops the base when
  /// the head cannot be held. Bridges without such read-backs keep this default (nothing to say).
  virtual RobotSupervision supervise() { return {}; }

  /// Why the last frame came without the robot's odometry (Frame::odom empty), for the session
  /// to report; "" when it had it. Bridges that always fill it keep this default.
  virtual std::string odometry_problem() const { return {}; }
};

}  // namespace pepper::naoqi_bridge
