#pragma once
// SimRobot: what a simulated Pepper offers to the two ways of serving it, the in-process
// MockBridge (no sockets) and the mock NAOqi server (qi messaging over loopback). Both live in
// naoqi_bridge and use this interface; sim itself knows nothing of bridges or protocols.
//
// Implementations: MockRobot (textured world, renderer, unicycle kinematics; sim/mock_robot.hpp)
// and SyntheticPatternRobot (a moving test pattern, for protocol tests that need no world).
//
// Time: the simulator owns its clock. In lockstep mode (default) simulated time advances only in
// capture(): each call moves the clock forward by one frame period of the configured rate and
// integrates the base over that interval with the velocity in force, so runs are deterministic
// and faster than real time. Ground truth (pose) is for evaluation only: the navigator never sees it.
//
// Failure: a request the simulated robot cannot serve (unknown joint, names and angles of
// different lengths, non-finite angle, unsupported image size) throws SimError naming the method
// and the value. Callers that speak for a robot translate it: the mock NAOqi server into an Error
// reply with the same text, MockBridge into a BridgeError.
// Threading: implementations are internally synchronised; the mock server calls them from its
// I/O thread while tests read the command log from another.

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/base_velocity.hpp"
#include "core/camera/intrinsics.hpp"
#include "core/frame.hpp"
#include "core/odometry.hpp"

namespace pepper::sim {

/// A request the simulated robot cannot serve. what() names the method and the offending value.
class SimError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Which pose estimate ALMotion.getRobotPosition(useSensors) returns.
enum class OdometrySource {
  kWheels,    ///< useSensors = true: the wheel odometry, integrated from the actual motion, drifts
  kCommands,  ///< useSensors = false: the commanded velocities integrated (what ALMotion asked)
};

/// One velocity command as received by the simulated base, for tests and evaluation.
struct CommandRecord {
  int64_t t_ns = 0;  ///< simulated time at which it was received
  core::BaseVelocity velocity;
  bool stop_move = false;  ///< true for an explicit stopMove (velocity is then zero)
};

class SimRobot {
 public:
  virtual ~SimRobot() = default;

  /// Renders the head camera's current view as 8-bit grey at the requested size (any size) and
  /// stamps it with simulated time; in lockstep mode, first advances the clock one frame period.
  virtual core::Frame capture(int width_px, int height_px) = 0;

  /// Intrinsics of the simulated camera at the given size.
  virtual core::CameraIntrinsics intrinsics(int width_px, int height_px) const = 0;

  /// ALMotion.move semantics: the velocity lasts until the next command.
  virtual void command_velocity(const core::BaseVelocity& velocity) = 0;

  /// ALMotion.stopMove semantics: the base decelerates to rest.
  virtual void stop_move() = 0;

  /// ALMotion.setAngles / getAngles for the named joints (HeadYaw, HeadPitch, HipRoll, HipPitch,
  /// KneePitch). Unknown names throw SimError naming the joint.
  virtual void set_joint_angles(const std::vector<std::string>& names,
                                const std::vector<double>& angles_rad) = 0;
  virtual std::vector<double> joint_angles(const std::vector<std::string>& names) const = 0;

  /// ALMotion.getRobotPosition: the base's pose in the odometry frame (T_odom_base,
  /// core/odometry.hpp), at the simulated time now (a capture() just before gives the odometry
  /// of that frame). Never the ground truth: the odometry frame is where the robot was created,
  /// and the wheel estimate drifts (sim/wheel_odometry.hpp).
  virtual core::OdometryPose odometry(OdometrySource source) const = 0;

  /// Simulated time now, ns.
  virtual int64_t now_ns() const = 0;

  /// Every command received so far, in order (tests assert on the last one being a stop).
  virtual std::vector<CommandRecord> command_log() const = 0;
};

}  // namespace pepper::sim
