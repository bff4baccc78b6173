#pragma once
// MockRobot: a simulated Pepper in a textured World. Implements SimRobot (served in-process by
// MockBridge or over the network by the mock NAOqi server) and adds the evaluation-only API:
// place the robot, choose the lighting condition, read ground truth and the collision state.
//
// Time: lockstep. The clock advances only in capture() (one frame period of frame_rate_hz,
// integrating the base over it, then rendering the view at the new time) or in advance_s().
// Camera pose (PEPPER.md "Top head camera"): the camera sits at cam_in_head_m in the head frame
// (URDF: 0.08601, 0, 0.16284 m); with all joints at zero it is camera_height_m = 1.153 m above the
// floor and camera_forward_m = 0.048 m ahead of the base rotation axis (this is `delta`, METHOD.md;
// PEPPER.md estimates ~0.05 m), optical axis horizontal. HeadYaw turns the head about the vertical
// through the neck, HeadPitch (> 0 looks down) about the neck's left axis; both pivot at the same
// point (the URDF's 2 cm between them is neglected). Hip and knee joints are stored but do not
// move the camera.
// Odometry (odometry()): both estimates start at (0, 0, 0) where the robot is created and follow
// every integration step: the wheel odometry from the actual motion with drift
// (sim/wheel_odometry.hpp), the command estimate from the controller's velocity without actuator
// noise. place() moves the base without them (a robot carried elsewhere), so after a place()
// they no longer describe the world pose at all: only their differences along one drive do.
// Collision: after each integration step the base footprint (a disc of robot_radius_m) is tested
// against walls, furniture and people; on contact the base stops where it was, collided() turns
// true and further velocity commands are logged but ignored until place() (the run is over).
// Thread-safety: every public method locks an internal mutex.

#include <Eigen/Geometry>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "sim/kinematics.hpp"
#include "sim/renderer.hpp"
#include "sim/sim_robot.hpp"
#include "sim/wheel_odometry.hpp"
#include "sim/world.hpp"

namespace pepper::sim {

struct CameraMount {
  double camera_height_m = 1.153;   ///< optical centre above the floor at zero joints
  double camera_forward_m = 0.048;  ///< ahead of the base rotation axis at zero joints (delta)
  Eigen::Vector3d cam_in_head_m{0.08601, 0.0, 0.16284};  ///< URDF CameraTop in the head frame

  /// T_base_cam for the given head angles (base: x forward, y left, z up, origin on the floor).
  Eigen::Isometry3d T_base_cam(double head_yaw_rad, double head_pitch_rad) const;
};

struct MockRobotOptions {
  double frame_rate_hz = 15.0;     ///< lockstep frame period = 1 / frame_rate_hz
  double robot_radius_m = 0.3;     ///< base footprint for collisions
  std::string lighting = "teach";  ///< World::lighting condition rendered
  core::CameraIntrinsics intrinsics_vga = core::CameraIntrinsics::pepper_top_vga();
  CameraMount mount;
  KinematicsOptions kinematics;
  WheelOdometryOptions odometry;  ///< the drift of getRobotPosition(true)
  RenderOptions render;

  std::vector<std::string> validate() const;
};

/// Where the collision happened and with what.
struct CollisionEvent {
  int64_t t_ns = 0;
  Pose2D pose;       ///< last free pose (where the base stopped)
  std::string what;  ///< obstacle name from the world file, e.g. "walls[0] piece 2"
};

/// Evaluation-only truth about the simulated robot.
struct GroundTruth {
  int64_t t_ns = 0;
  Pose2D base;                  ///< base rotation axis in the world frame
  core::BaseVelocity velocity;  ///< actual robot-frame velocity
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  int64_t frames = 0;  ///< frames captured so far
  std::optional<CollisionEvent> collision;
};

class MockRobot final : public SimRobot {
 public:
  /// Throws std::invalid_argument for invalid options, WorldError for an unknown lighting.
  /// The robot starts at the scenario's teach start pose.
  explicit MockRobot(std::shared_ptr<const World> world, MockRobotOptions options = {});

  // SimRobot
  core::Frame capture(int width_px, int height_px) override;
  core::CameraIntrinsics intrinsics(int width_px, int height_px) const override;
  void command_velocity(const core::BaseVelocity& velocity) override;
  void stop_move() override;
  void set_joint_angles(const std::vector<std::string>& names,
                        const std::vector<double>& angles_rad) override;
  std::vector<double> joint_angles(const std::vector<std::string>& names) const override;
  core::OdometryPose odometry(OdometrySource source) const override;
  int64_t now_ns() const override;
  std::vector<CommandRecord> command_log() const override;

  // Evaluation only (not part of SimRobot / RobotBridge).
  /// Teleports the base: velocity zero, pending commands dropped, collision cleared. The clock
  /// keeps running (frame timestamps stay increasing).
  void place(const Pose2D& pose);
  /// Selects a World::lighting condition ("teach", "replay", ...); throws WorldError if unknown.
  void set_lighting(const std::string& condition);
  /// Advances the clock without rendering (e.g. between dropped frames).
  void advance_s(double dt_s);
  GroundTruth ground_truth() const;
  bool collided() const;
  const World& world() const { return *world_; }
  std::shared_ptr<const World> world_ptr() const { return world_; }
  const MockRobotOptions& options() const { return options_; }
  /// Depth of each pixel of the last capture (metres along the optical axis, +inf where empty).
  cv::Mat last_depth_m() const;

 private:
  void advance_locked(int64_t t_end_ns);
  Eigen::Isometry3d T_world_cam_locked() const;

  std::shared_ptr<const World> world_;
  MockRobotOptions options_;
  mutable std::mutex mutex_;
  BaseKinematics base_;
  WheelOdometry wheel_odometry_;  ///< getRobotPosition(true)
  Pose2D command_odometry_;       ///< getRobotPosition(false), in the odometry frame
  Renderer renderer_;
  LightingCondition light_;
  double head_yaw_rad_ = 0.0;
  double head_pitch_rad_ = 0.0;
  double hip_roll_rad_ = 0.0;
  double hip_pitch_rad_ = 0.0;
  double knee_pitch_rad_ = 0.0;
  int64_t frames_ = 0;
  std::optional<CollisionEvent> collision_;
  std::vector<CommandRecord> log_;
};

}  // namespace pepper::sim
