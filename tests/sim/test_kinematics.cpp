// BaseKinematics: closed-form arcs, limits, latency, seeded noise.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/kinematics.hpp"

namespace pepper::sim {
namespace {

constexpr int64_t kSecond = 1'000'000'000;

KinematicsOptions instant() {
  KinematicsOptions o;
  o.max_acc_xy_m_s2 = 1e6;  // reaches the target at the first control tick
  o.max_acc_theta_rad_s2 = 1e6;
  return o;
}

TEST(Kinematics, ClosedFormMatchesFineEulerIntegration) {
  // Exact arc vs 1e5 tiny Euler steps of the same robot-frame velocity, lateral speed included.
  const core::BaseVelocity v{0.25, -0.1, 0.7};
  const Pose2D start{1.0, -2.0, 0.4};
  const double T = 3.0;
  Pose2D e = start;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double dt = T / n;
    const double c = std::cos(e.yaw_rad + 0.5 * v.omega_rad_s * dt);
    const double s = std::sin(e.yaw_rad + 0.5 * v.omega_rad_s * dt);
    e.x_m += (c * v.v_x_m_s - s * v.v_y_m_s) * dt;
    e.y_m += (s * v.v_x_m_s + c * v.v_y_m_s) * dt;
    e.yaw_rad += v.omega_rad_s * dt;
  }
  const Pose2D a = integrate_constant(start, v, T);
  EXPECT_NEAR(a.x_m, e.x_m, 1e-8);
  EXPECT_NEAR(a.y_m, e.y_m, 1e-8);
  EXPECT_NEAR(a.yaw_rad, std::remainder(e.yaw_rad, 2 * M_PI), 1e-9);
}

TEST(Kinematics, ConstantVelocityFollowsTheArc) {
  BaseKinematics k(instant());
  k.reset({0, 0, 0}, 0);
  const double v = 0.3, w = 0.5, T = 4.0;
  k.command({v, 0.0, w}, 0);
  ASSERT_TRUE(k.advance_to(static_cast<int64_t>(T * kSecond)));
  // Circle of radius v / w = 0.6 m starting at the origin heading +x, turning left.
  EXPECT_NEAR(k.pose().x_m, v / w * std::sin(w * T), 1e-9);
  EXPECT_NEAR(k.pose().y_m, v / w * (1 - std::cos(w * T)), 1e-9);
  EXPECT_NEAR(k.pose().yaw_rad, w * T, 1e-9);
  EXPECT_EQ(k.now_ns(), 4 * kSecond);
}

TEST(Kinematics, LateralVelocityIsHonoured) {
  BaseKinematics k(instant());
  k.reset({0, 0, M_PI / 2}, 0);  // facing +y: moving left is moving -x
  k.command({0.0, 0.2, 0.0}, 0);
  k.advance_to(2 * kSecond);
  EXPECT_NEAR(k.pose().x_m, -0.4, 1e-9);
  EXPECT_NEAR(k.pose().y_m, 0.0, 1e-9);
}

TEST(Kinematics, VelocityLimitsAreRespected) {
  BaseKinematics k(instant());
  k.reset({0, 0, 0}, 0);
  k.command({1.0, 1.0, 3.0}, 0);
  k.advance_to(kSecond);
  EXPECT_NEAR(std::hypot(k.velocity().v_x_m_s, k.velocity().v_y_m_s), 0.35, 1e-12);  // MaxVelXY
  EXPECT_NEAR(k.velocity().v_x_m_s, k.velocity().v_y_m_s, 1e-12);  // direction kept
  EXPECT_NEAR(k.velocity().omega_rad_s, 1.0, 1e-12);               // MaxVelTheta
  k.command({0.0, 0.0, -5.0}, k.now_ns());
  k.advance_to(2 * kSecond);
  EXPECT_NEAR(k.velocity().omega_rad_s, -1.0, 1e-12);
}

TEST(Kinematics, AccelerationLimitsAreRespected) {
  BaseKinematics k;  // Pepper defaults: 0.3 m/s^2, 0.75 rad/s^2
  k.reset({0, 0, 0}, 0);
  k.command({0.35, 0.0, 1.0}, 0);
  double prev_v = 0.0, prev_w = 0.0;
  for (int i = 1; i <= 100; ++i) {
    k.advance_to(i * kSecond / 50);
    EXPECT_LE(k.velocity().v_x_m_s - prev_v, 0.3 * 0.02 + 1e-12);
    EXPECT_LE(k.velocity().omega_rad_s - prev_w, 0.75 * 0.02 + 1e-12);
    prev_v = k.velocity().v_x_m_s;
    prev_w = k.velocity().omega_rad_s;
  }
  // After 2 s: v at its 0.35 cap (reached at ~1.17 s), omega at its 1.0 cap (reached at 1.33 s).
  EXPECT_NEAR(k.velocity().v_x_m_s, 0.35, 1e-12);
  EXPECT_NEAR(k.velocity().omega_rad_s, 1.0, 1e-12);
  // Deceleration to rest after a stop is limited as well: 0.35 m/s takes >= 1.1 s.
  k.command({}, k.now_ns());
  k.advance_to(k.now_ns() + kSecond);
  EXPECT_GT(k.velocity().v_x_m_s, 0.0);
  k.advance_to(k.now_ns() + kSecond);
  EXPECT_EQ(k.velocity().v_x_m_s, 0.0);
  EXPECT_EQ(k.velocity().omega_rad_s, 0.0);
}

TEST(Kinematics, LatencyDelaysTheCommand) {
  KinematicsOptions o = instant();
  o.latency_s = 0.2;
  BaseKinematics k(o);
  k.reset({0, 0, 0}, 0);
  k.command({0.3, 0.0, 0.0}, 0);
  k.advance_to(kSecond / 10);  // 0.1 s: not yet
  EXPECT_EQ(k.pose().x_m, 0.0);
  EXPECT_EQ(k.velocity().v_x_m_s, 0.0);
  k.advance_to(kSecond / 2);  // moving from 0.2 s to 0.5 s: 0.3 m/s * 0.3 s
  EXPECT_NEAR(k.pose().x_m, 0.09, 1e-9);
}

TEST(Kinematics, NoiseIsSeeded) {
  auto run = [](uint64_t seed) {
    KinematicsOptions o;
    o.noise_rel = 0.05;
    o.noise_omega_rad_s = 0.02;
    o.seed = seed;
    BaseKinematics k(o);
    k.reset({0, 0, 0}, 0);
    k.command({0.2, 0.0, 0.1}, 0);
    k.advance_to(5 * kSecond);
    return k.pose();
  };
  const Pose2D a = run(3), b = run(3), c = run(4);
  EXPECT_EQ(a.x_m, b.x_m);
  EXPECT_EQ(a.y_m, b.y_m);
  EXPECT_EQ(a.yaw_rad, b.yaw_rad);
  EXPECT_NE(a.x_m, c.x_m);
  EXPECT_NEAR(a.x_m, c.x_m, 0.1);  // noise is small
}

TEST(Kinematics, BlockedStepStopsTheBaseWhereItWas) {
  BaseKinematics k(instant());
  k.reset({0, 0, 0}, 0);
  k.command({0.3, 0.0, 0.0}, 0);
  const bool free =
      k.advance_to(2 * kSecond, [](const Pose2D& p, int64_t) { return p.x_m > 0.25; });
  EXPECT_FALSE(free);
  EXPECT_LE(k.pose().x_m, 0.25);
  EXPECT_GT(k.pose().x_m, 0.25 - 0.3 * 0.02 - 1e-9);  // within one 20 ms step of the obstacle
  EXPECT_EQ(k.velocity().v_x_m_s, 0.0);
  EXPECT_EQ(k.now_ns(), 2 * kSecond);
}

TEST(Kinematics, InvalidOptionsNameTheField) {
  KinematicsOptions o;
  o.max_acc_xy_m_s2 = 0.0;
  const auto errors = o.validate();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("max_acc_xy_m_s2"), std::string::npos);
  EXPECT_THROW(BaseKinematics{o}, std::invalid_argument);
}

}  // namespace
}  // namespace pepper::sim
