// SyntheticPatternRobot: self-checking moving test pattern (see the header).
#include "sim/synthetic_pattern_robot.hpp"

#include <chrono>
#include <cmath>
#include <cstring>

namespace pepper::sim {

namespace {

int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

uint64_t fnv1a(const uint8_t* p, size_t n) {
  uint64_t h = 1469598103934665603ull;
  for (size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

constexpr const char* kJointNames[] = {"HeadYaw", "HeadPitch", "HipRoll", "HipPitch", "KneePitch"};

}  // namespace

std::vector<std::string> SyntheticPatternOptions::validate() const {
  std::vector<std::string> errors;
  if (!(frame_rate_hz > 0.0 && frame_rate_hz <= 1000.0)) {
    errors.push_back("frame_rate_hz must be in (0, 1000], got " + std::to_string(frame_rate_hz));
  }
  if (checker_size_px < 2 || checker_size_px > 256) {
    errors.push_back("checker_size_px must be in 2..256, got " + std::to_string(checker_size_px));
  }
  return errors;
}

SyntheticPatternRobot::SyntheticPatternRobot(SyntheticPatternOptions options)
    : options_(options), start_wall_ns_(steady_ns()) {
  const auto errors = options_.validate();
  if (!errors.empty()) throw SimError("SyntheticPatternOptions: " + errors.front());
  for (const char* j : kJointNames) joints_rad_[j] = 0.0;
}

int64_t SyntheticPatternRobot::now_ns_locked() const {
  if (options_.clock == SyntheticPatternOptions::Clock::kWallClock) {
    return steady_ns() - start_wall_ns_;
  }
  return sim_t_ns_;
}

int64_t SyntheticPatternRobot::now_ns() const {
  std::lock_guard lock(mutex_);
  return now_ns_locked();
}

void SyntheticPatternRobot::integrate_to_locked(int64_t t_ns) {
  const double dt_s = static_cast<double>(t_ns - integrated_t_ns_) * 1e-9;
  if (dt_s <= 0.0) return;
  // Exact unicycle integration for constant (v, omega) over dt (plus lateral velocity).
  const Pose2 before = pose_;
  const double w = velocity_.omega_rad_s;
  const double yaw0 = pose_.yaw_rad;
  const double yaw1 = yaw0 + w * dt_s;
  if (std::fabs(w) < 1e-9) {
    pose_.x_m += (velocity_.v_x_m_s * std::cos(yaw0) - velocity_.v_y_m_s * std::sin(yaw0)) * dt_s;
    pose_.y_m += (velocity_.v_x_m_s * std::sin(yaw0) + velocity_.v_y_m_s * std::cos(yaw0)) * dt_s;
  } else {
    pose_.x_m += velocity_.v_x_m_s / w * (std::sin(yaw1) - std::sin(yaw0)) +
                 velocity_.v_y_m_s / w * (std::cos(yaw1) - std::cos(yaw0));
    pose_.y_m += -velocity_.v_x_m_s / w * (std::cos(yaw1) - std::cos(yaw0)) +
                 velocity_.v_y_m_s / w * (std::sin(yaw1) - std::sin(yaw0));
  }
  pose_.yaw_rad = yaw1;
  integrated_t_ns_ = t_ns;
  wheel_odometry_.on_step({before.x_m, before.y_m, before.yaw_rad},
                          {pose_.x_m, pose_.y_m, pose_.yaw_rad}, dt_s);
}

core::Frame SyntheticPatternRobot::capture(int width_px, int height_px) {
  if (width_px < 8 || height_px < 2 || width_px > 4096 || height_px > 4096) {
    throw SimError("SyntheticPatternRobot::capture: unsupported size " + std::to_string(width_px) +
                   "x" + std::to_string(height_px));
  }
  std::lock_guard lock(mutex_);
  if (options_.clock == SyntheticPatternOptions::Clock::kLockstep) {
    sim_t_ns_ += static_cast<int64_t>(std::llround(1e9 / options_.frame_rate_hz));
  }
  const int64_t t_ns = now_ns_locked();
  integrate_to_locked(t_ns);

  const auto intr = core::CameraIntrinsics::pepper_top_vga().scaled_to(width_px, height_px);
  // Horizontal shift of the pattern: a yaw to the left moves the scene to the right in the image;
  // driving forward scrolls it by 100 px per metre (a visible, monotonic cue, not a projection).
  const long shift_px = std::lround(pose_.yaw_rad * intr.fx_px + pose_.x_m * 100.0);
  const int square = std::max(2, options_.checker_size_px * width_px / 640);

  core::Frame frame;
  frame.gray.create(height_px, width_px, CV_8UC1);
  frame.t_ns = t_ns;
  frame.index = next_index_++;
  for (int v = 0; v < height_px; ++v) {
    uint8_t* row = frame.gray.ptr<uint8_t>(v);
    const long cv_sq = v / square;
    for (int u = 0; u < width_px; ++u) {
      const long su = u + shift_px;
      const long cu = (su >= 0 ? su : su - square + 1) / square;
      const bool dark = ((cu + cv_sq) & 1) != 0;
      row[u] = static_cast<uint8_t>((dark ? 40 : 170) + ((su & 63) >> 1));
    }
  }
  uint8_t* p = frame.gray.data;  // continuous (freshly created)
  const size_t n = frame.gray.total();
  std::memcpy(p, &frame.index, 8);
  const uint64_t h = fnv1a(p + 16, n - 16);
  std::memcpy(p + 8, &h, 8);
  return frame;
}

std::optional<int64_t> SyntheticPatternRobot::verify_frame(const cv::Mat& gray) {
  if (gray.type() != CV_8UC1 || gray.total() < 16) return std::nullopt;
  cv::Mat c = gray.isContinuous() ? gray : gray.clone();
  const uint8_t* p = c.data;
  uint64_t stored = 0;
  std::memcpy(&stored, p + 8, 8);
  if (stored != fnv1a(p + 16, c.total() - 16)) return std::nullopt;
  int64_t index = 0;
  std::memcpy(&index, p, 8);
  return index;
}

core::CameraIntrinsics SyntheticPatternRobot::intrinsics(int width_px, int height_px) const {
  return core::CameraIntrinsics::pepper_top_vga().scaled_to(width_px, height_px);
}

void SyntheticPatternRobot::command_velocity(const core::BaseVelocity& velocity) {
  std::lock_guard lock(mutex_);
  const int64_t t = now_ns_locked();
  integrate_to_locked(t);
  velocity_ = velocity;
  log_.push_back({t, velocity, false});
}

void SyntheticPatternRobot::stop_move() {
  std::lock_guard lock(mutex_);
  const int64_t t = now_ns_locked();
  integrate_to_locked(t);
  velocity_ = core::BaseVelocity{};
  log_.push_back({t, core::BaseVelocity{}, true});
}

void SyntheticPatternRobot::set_joint_angles(const std::vector<std::string>& names,
                                             const std::vector<double>& angles_rad) {
  if (names.size() != angles_rad.size()) {
    throw SimError("set_joint_angles: " + std::to_string(names.size()) + " names for " +
                   std::to_string(angles_rad.size()) + " angles");
  }
  std::lock_guard lock(mutex_);
  for (const auto& n : names) {
    if (!joints_rad_.count(n)) throw SimError("set_joint_angles: unknown joint '" + n + "'");
  }
  for (size_t i = 0; i < names.size(); ++i) joints_rad_[names[i]] = angles_rad[i];
}

std::vector<double> SyntheticPatternRobot::joint_angles(
    const std::vector<std::string>& names) const {
  std::lock_guard lock(mutex_);
  std::vector<double> out;
  for (const auto& n : names) {
    auto it = joints_rad_.find(n);
    if (it == joints_rad_.end()) throw SimError("joint_angles: unknown joint '" + n + "'");
    out.push_back(it->second);
  }
  return out;
}

std::vector<CommandRecord> SyntheticPatternRobot::command_log() const {
  std::lock_guard lock(mutex_);
  return log_;
}

core::OdometryPose SyntheticPatternRobot::odometry(OdometrySource source) const {
  std::lock_guard lock(mutex_);
  if (source == OdometrySource::kWheels) return wheel_odometry_.pose();
  return {pose_.x_m, pose_.y_m, std::remainder(pose_.yaw_rad, 2.0 * M_PI)};
}

SyntheticPatternRobot::Pose2 SyntheticPatternRobot::pose() const {
  std::lock_guard lock(mutex_);
  return pose_;
}

}  // namespace pepper::sim
