#pragma once
// SyntheticPatternRobot: a SimRobot whose camera sees a moving test pattern instead of a world.
//
// For protocol and bridge tests that need frames, a base and joints but no rendering of a scene
// (the textured world lives in MockRobot). Each frame is self-checking: its first 8 bytes hold
// the frame index (little-endian int64) and bytes 8..15 an FNV-1a 64-bit hash of every byte from
// offset 16 on, so a receiver can tell that a frame arrived intact and in order
// (verify_frame()). The pattern (checkerboard plus ramp) shifts horizontally with the simulated
// yaw and forward position, so commanded motion is visible in the images.
//
// Time: in lockstep mode (default) the clock advances one frame period per capture() (SimRobot
// contract); in wall-clock mode now_ns() is steady_clock time since construction, so command
// log stamps measure real delays (used by the watchdog test).
// Kinematics: unicycle in the world plane, velocity held until the next command; stop_move()
// zeroes it. Thread-safe (one mutex).

#include <cstdint>
#include <map>
#include <mutex>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>
#include <vector>

#include "sim/sim_robot.hpp"
#include "sim/wheel_odometry.hpp"

namespace pepper::sim {

struct SyntheticPatternOptions {
  enum class Clock { kLockstep, kWallClock };
  Clock clock = Clock::kLockstep;
  double frame_rate_hz = 30.0;  ///< lockstep: simulated time per capture is 1 / frame_rate_hz
  int checker_size_px = 16;     ///< checkerboard square size at VGA (scaled with width)

  /// Messages naming each invalid field and its allowed range; empty when valid.
  std::vector<std::string> validate() const;
};

class SyntheticPatternRobot : public SimRobot {
 public:
  /// Throws SimError naming the first invalid option.
  explicit SyntheticPatternRobot(SyntheticPatternOptions options = {});

  core::Frame capture(int width_px, int height_px) override;
  core::CameraIntrinsics intrinsics(int width_px, int height_px) const override;
  void command_velocity(const core::BaseVelocity& velocity) override;
  void stop_move() override;
  void set_joint_angles(const std::vector<std::string>& names,
                        const std::vector<double>& angles_rad) override;
  std::vector<double> joint_angles(const std::vector<std::string>& names) const override;
  /// kCommands: the pose integrated so far (this base does exactly what it is told); kWheels: the
  /// same motion through WheelOdometry (drifts). As of the last capture() or command.
  core::OdometryPose odometry(OdometrySource source) const override;
  int64_t now_ns() const override;
  std::vector<CommandRecord> command_log() const override;

  /// Base pose in the world plane (ground truth): x, y in m, yaw in rad.
  struct Pose2 {
    double x_m = 0.0;
    double y_m = 0.0;
    double yaw_rad = 0.0;
  };
  Pose2 pose() const;

  /// Checks the embedded index and hash of a frame produced by capture(). Returns the index, or
  /// nullopt when the frame is too small, not 8-bit grey, or its bytes do not match the hash.
  static std::optional<int64_t> verify_frame(const cv::Mat& gray);

 private:
  int64_t now_ns_locked() const;
  void integrate_to_locked(int64_t t_ns);

  SyntheticPatternOptions options_;
  mutable std::mutex mutex_;
  int64_t start_wall_ns_ = 0;
  int64_t sim_t_ns_ = 0;         ///< lockstep clock
  int64_t integrated_t_ns_ = 0;  ///< time up to which the pose is integrated
  int64_t next_index_ = 0;
  Pose2 pose_;
  WheelOdometry wheel_odometry_;
  core::BaseVelocity velocity_;
  std::map<std::string, double> joints_rad_;
  std::vector<CommandRecord> log_;
};

}  // namespace pepper::sim
