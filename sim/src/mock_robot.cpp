// Simulated Pepper (see mock_robot.hpp).
#include "sim/mock_robot.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace pepper::sim {

namespace {

// URDF joint ranges (PEPPER.md "Head, body and base"); other joints: generous +-pi/2 (not
// modelled).
struct JointRange {
  const char* name;
  double lo, hi;
};
constexpr JointRange kJoints[] = {
    {"HeadYaw", -2.086, 2.086},  {"HeadPitch", -0.707, 0.637}, {"HipRoll", -0.514, 0.514},
    {"HipPitch", -1.038, 1.038}, {"KneePitch", -0.514, 0.514},
};

}  // namespace

Eigen::Isometry3d CameraMount::T_base_cam(double head_yaw_rad, double head_pitch_rad) const {
  // Neck pivot in the base frame, from the camera position at zero joints.
  const Eigen::Vector3d neck(camera_forward_m - cam_in_head_m.x(), -cam_in_head_m.y(),
                             camera_height_m - cam_in_head_m.z());
  Eigen::Isometry3d T_base_head = Eigen::Isometry3d::Identity();
  T_base_head.translation() = neck;
  T_base_head.linear() = (Eigen::AngleAxisd(head_yaw_rad, Eigen::Vector3d::UnitZ()) *
                          Eigen::AngleAxisd(head_pitch_rad, Eigen::Vector3d::UnitY()))
                             .toRotationMatrix();
  // Camera axes (x right, y down, z forward) expressed in the head frame (x fwd, y left, z up).
  Eigen::Matrix3d R_head_cam;
  // clang-format off
  R_head_cam << 0, 0, 1,
               -1, 0, 0,
                0,-1, 0;
  // clang-format on
  Eigen::Isometry3d T_head_cam = Eigen::Isometry3d::Identity();
  T_head_cam.linear() = R_head_cam;
  T_head_cam.translation() = cam_in_head_m;
  return T_base_head * T_head_cam;
}

std::vector<std::string> MockRobotOptions::validate() const {
  std::vector<std::string> errors;
  if (!(frame_rate_hz > 0.5 && frame_rate_hz <= 120.0))
    errors.push_back("frame_rate_hz = " + std::to_string(frame_rate_hz) + " must be in (0.5, 120]");
  if (!(robot_radius_m > 0.0 && robot_radius_m < 1.0))
    errors.push_back("robot_radius_m = " + std::to_string(robot_radius_m) + " must be in (0, 1) m");
  if (!(mount.camera_height_m > 0.1 && mount.camera_height_m < 3.0))
    errors.push_back("mount.camera_height_m must be in (0.1, 3) m");
  for (const auto& e : intrinsics_vga.validate()) errors.push_back("intrinsics_vga." + e);
  for (const auto& e : kinematics.validate()) errors.push_back("kinematics." + e);
  for (const auto& e : odometry.validate()) errors.push_back("odometry." + e);
  for (const auto& e : render.validate()) errors.push_back("render." + e);
  return errors;
}

namespace {
const MockRobotOptions& checked(const MockRobotOptions& o) {
  const auto errors = o.validate();
  if (!errors.empty()) throw std::invalid_argument("MockRobotOptions: " + errors.front());
  return o;
}
}  // namespace

MockRobot::MockRobot(std::shared_ptr<const World> world, MockRobotOptions options)
    : world_(std::move(world)),
      options_(checked(options)),
      base_(options_.kinematics),
      wheel_odometry_(options_.odometry),
      renderer_(options_.render) {
  if (!world_) throw std::invalid_argument("MockRobot: null world");
  light_ = world_->light(options_.lighting);
  base_.reset(world_->scenario.start_pose(), 0);
}

Eigen::Isometry3d MockRobot::T_world_cam_locked() const {
  const Pose2D& p = base_.pose();
  Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();
  T_world_base.translation() = Eigen::Vector3d(p.x_m, p.y_m, 0.0);
  T_world_base.linear() = Eigen::AngleAxisd(p.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T_world_base * options_.mount.T_base_cam(head_yaw_rad_, head_pitch_rad_);
}

void MockRobot::advance_locked(int64_t t_end_ns) {
  if (collision_) {
    base_.advance_to(t_end_ns);  // stopped: only the clock moves
    return;
  }
  std::string hit;
  const double r = options_.robot_radius_m;
  const auto blocked = [&](const Pose2D& p, int64_t t_ns) {
    if (auto what = world_->collision({p.x_m, p.y_m}, r, static_cast<double>(t_ns) * 1e-9)) {
      hit = *what;
      return true;
    }
    return false;
  };
  const auto odometry_step = [&](const BaseStep& step) {
    wheel_odometry_.on_step(step.before, step.after, step.dt_s);
    command_odometry_ = integrate_constant(command_odometry_, step.controlled, step.dt_s);
  };
  const bool free = base_.advance_to(t_end_ns, blocked, odometry_step);
  if (!free) collision_ = CollisionEvent{base_.now_ns(), base_.pose(), hit};
}

core::Frame MockRobot::capture(int width_px, int height_px) {
  if (width_px <= 0 || height_px <= 0 || width_px > 4096 || height_px > 4096)
    throw SimError("MockRobot::capture: bad size " + std::to_string(width_px) + "x" +
                   std::to_string(height_px));
  std::lock_guard lock(mutex_);
  const int64_t period_ns = std::llround(1e9 / options_.frame_rate_hz);
  advance_locked(base_.now_ns() + period_ns);
  ViewState view;
  view.T_world_cam = T_world_cam_locked();
  view.intrinsics = options_.intrinsics_vga.scaled_to(width_px, height_px);
  view.light = light_;
  view.t_s = static_cast<double>(base_.now_ns()) * 1e-9;
  view.robot_base_m = Eigen::Vector2d(base_.pose().x_m, base_.pose().y_m);
  view.yaw_rate_cam_rad_s = base_.velocity().omega_rad_s * std::cos(head_pitch_rad_);
  view.frame_index = static_cast<uint64_t>(frames_);
  core::Frame frame;
  renderer_.render(*world_, view, frame.gray);
  frame.t_ns = base_.now_ns();
  frame.index = frames_++;
  return frame;
}

core::CameraIntrinsics MockRobot::intrinsics(int width_px, int height_px) const {
  return options_.intrinsics_vga.scaled_to(width_px, height_px);
}

void MockRobot::command_velocity(const core::BaseVelocity& velocity) {
  std::lock_guard lock(mutex_);
  log_.push_back({base_.now_ns(), velocity, false});
  if (!collision_) base_.command(velocity, base_.now_ns());
}

void MockRobot::stop_move() {
  std::lock_guard lock(mutex_);
  log_.push_back({base_.now_ns(), core::BaseVelocity{}, true});
  if (!collision_) base_.command(core::BaseVelocity{}, base_.now_ns());
}

void MockRobot::set_joint_angles(const std::vector<std::string>& names,
                                 const std::vector<double>& angles_rad) {
  if (names.size() != angles_rad.size())
    throw SimError("MockRobot::set_joint_angles: " + std::to_string(names.size()) + " names but " +
                   std::to_string(angles_rad.size()) + " angles");
  std::lock_guard lock(mutex_);
  for (size_t i = 0; i < names.size(); ++i) {
    const JointRange* range = nullptr;
    for (const JointRange& j : kJoints)
      if (names[i] == j.name) range = &j;
    if (!range) throw SimError("MockRobot::set_joint_angles: unknown joint '" + names[i] + "'");
    if (!std::isfinite(angles_rad[i]))
      throw SimError("MockRobot::set_joint_angles: non-finite angle for " + names[i]);
    const double a = std::clamp(angles_rad[i], range->lo, range->hi);
    if (names[i] == "HeadYaw") head_yaw_rad_ = a;
    if (names[i] == "HeadPitch") head_pitch_rad_ = a;
    if (names[i] == "HipRoll") hip_roll_rad_ = a;
    if (names[i] == "HipPitch") hip_pitch_rad_ = a;
    if (names[i] == "KneePitch") knee_pitch_rad_ = a;
  }
}

std::vector<double> MockRobot::joint_angles(const std::vector<std::string>& names) const {
  std::lock_guard lock(mutex_);
  std::vector<double> out;
  for (const std::string& n : names) {
    if (n == "HeadYaw")
      out.push_back(head_yaw_rad_);
    else if (n == "HeadPitch")
      out.push_back(head_pitch_rad_);
    else if (n == "HipRoll")
      out.push_back(hip_roll_rad_);
    else if (n == "HipPitch")
      out.push_back(hip_pitch_rad_);
    else if (n == "KneePitch")
      out.push_back(knee_pitch_rad_);
    else
      throw SimError("MockRobot::joint_angles: unknown joint '" + n + "'");
  }
  return out;
}

core::OdometryPose MockRobot::odometry(OdometrySource source) const {
  std::lock_guard lock(mutex_);
  if (source == OdometrySource::kWheels) return wheel_odometry_.pose();
  return {command_odometry_.x_m, command_odometry_.y_m, command_odometry_.yaw_rad};
}

int64_t MockRobot::now_ns() const {
  std::lock_guard lock(mutex_);
  return base_.now_ns();
}

std::vector<CommandRecord> MockRobot::command_log() const {
  std::lock_guard lock(mutex_);
  return log_;
}

void MockRobot::place(const Pose2D& pose) {
  std::lock_guard lock(mutex_);
  base_.reset(pose, base_.now_ns());
  collision_.reset();
}

void MockRobot::set_lighting(const std::string& condition) {
  std::lock_guard lock(mutex_);
  light_ = world_->light(condition);
}

void MockRobot::advance_s(double dt_s) {
  if (!(dt_s >= 0.0 && std::isfinite(dt_s)))
    throw std::invalid_argument("MockRobot::advance_s: dt_s must be finite and >= 0");
  std::lock_guard lock(mutex_);
  advance_locked(base_.now_ns() + std::llround(dt_s * 1e9));
}

GroundTruth MockRobot::ground_truth() const {
  std::lock_guard lock(mutex_);
  GroundTruth g;
  g.t_ns = base_.now_ns();
  g.base = base_.pose();
  g.velocity = base_.velocity();
  g.T_world_cam = T_world_cam_locked();
  g.frames = frames_;
  g.collision = collision_;
  return g;
}

bool MockRobot::collided() const {
  std::lock_guard lock(mutex_);
  return collision_.has_value();
}

cv::Mat MockRobot::last_depth_m() const {
  std::lock_guard lock(mutex_);
  return renderer_.depth_m();
}

}  // namespace pepper::sim
