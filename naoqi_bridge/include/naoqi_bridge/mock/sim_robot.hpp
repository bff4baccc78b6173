#pragma once
// SimRobot: what a simulated Pepper offers to the two ways of serving it, the in-process
// MockBridge (no sockets) and the mock NAOqi server (qi messaging over loopback).
//
// Implementations: MockRobot (textured world, renderer, unicycle kinematics; naoqi_bridge/mock)
// and SyntheticPatternRobot (a moving test pattern, for protocol tests that need no world).
//
// Time: the simulator owns its clock. In lockstep mode (default) simulated time advances only in
// capture(): each call moves the clock forward by one frame period of the configured rate and
// integrates the base over that interval with the velocity in force, so runs are deterministic
// and faster than real time. Ground truth (pose) is for evaluation only: the navigator never sees it.
//
// Threading: implementations are internally synchronised; the mock server calls them from its
// I/O thread while tests read the command log from another.

#include <cstdint>
#include <string>
#include <vector>

#include "core/frame.hpp"
#include "naoqi_bridge/robot_bridge.hpp"

namespace pepper::naoqi_bridge::mock {

/// One velocity command as received by the simulated base, for tests and evaluation.
struct CommandRecord {
  int64_t t_ns = 0;      ///< simulated time at which it was received
  BaseVelocity velocity;
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
  virtual void command_velocity(const BaseVelocity& velocity) = 0;

  /// ALMotion.stopMove semantics: the base decelerates to rest.
  virtual void stop_move() = 0;

  /// ALMotion.setAngles / getAngles for the named joints (HeadYaw, HeadPitch, HipRoll, HipPitch,
  /// KneePitch). Unknown names throw BridgeError naming the joint.
  virtual void set_joint_angles(const std::vector<std::string>& names,
                                const std::vector<double>& angles_rad) = 0;
  virtual std::vector<double> joint_angles(const std::vector<std::string>& names) const = 0;

  /// Simulated time now, ns.
  virtual int64_t now_ns() const = 0;

  /// Every command received so far, in order (tests assert on the last one being a stop).
  virtual std::vector<CommandRecord> command_log() const = 0;
};

}  // namespace pepper::naoqi_bridge::mock
