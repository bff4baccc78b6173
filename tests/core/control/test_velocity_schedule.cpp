#include <gtest/gtest.h>

#include <cmath>

#include "core/control/velocity_schedule.hpp"

namespace pepper::core::control {
namespace {

constexpr int64_t kNsPerS = 1'000'000'000;
constexpr int64_t kFrame = kNsPerS / 5;  // 5 Hz

VelocityScheduleOptions no_rate_limit() {
  VelocityScheduleOptions o;
  o.max_omega_accel_rad_s2 = 1e6;
  return o;
}

TEST(VelocitySchedule, SaturatesOmega) {
  VelocitySchedule s(no_rate_limit());
  EXPECT_DOUBLE_EQ(s.step(2.0, 0).omega_rad_s, 0.6);
  EXPECT_DOUBLE_EQ(s.step(-2.0, kFrame).omega_rad_s, -0.6);
  EXPECT_DOUBLE_EQ(s.step(0.3, 2 * kFrame).omega_rad_s, 0.3);
}

TEST(VelocitySchedule, RateLimitUsesFrameStamps) {
  VelocitySchedule s;  // 0.75 rad/s^2
  // First step: from rest over first_step_dt_s = 0.2 s -> at most 0.15 rad/s.
  EXPECT_NEAR(s.step(0.5, 1000).omega_rad_s, 0.15, 1e-12);
  // 0.4 s later: +0.3 -> 0.45.
  EXPECT_NEAR(s.step(0.5, 1000 + 2 * kFrame).omega_rad_s, 0.45, 1e-12);
  // Same stamp again: no change allowed.
  EXPECT_NEAR(s.step(-0.5, 1000 + 2 * kFrame).omega_rad_s, 0.45, 1e-12);
  EXPECT_THROW(s.step(0.0, 999), std::invalid_argument);
  EXPECT_THROW(s.step(std::nan(""), 10 * kNsPerS), std::invalid_argument);
}

TEST(VelocitySchedule, TurnHysteresisAndSpeeds) {
  VelocityScheduleOptions o = no_rate_limit();
  o.turn_exit_hold_s = 0.0;  // the thresholds alone
  VelocitySchedule s(o);
  int64_t t = 0;
  auto step = [&](double w) { return s.step(w, t += kFrame); };
  EXPECT_DOUBLE_EQ(step(0.10).v_m_s, 0.15);  // below enter (0.15): straight
  const BaseCommand turning = step(0.16);    // above enter: turning
  EXPECT_TRUE(turning.turning);
  EXPECT_DOUBLE_EQ(turning.v_m_s, 0.08);
  EXPECT_TRUE(step(-0.10).turning);  // between exit and enter: stays turning
  EXPECT_TRUE(step(0.09).turning);
  const BaseCommand straight = step(0.07);  // below exit (0.08): straight again
  EXPECT_FALSE(straight.turning);
  EXPECT_DOUBLE_EQ(straight.v_m_s, 0.15);
  EXPECT_FALSE(step(0.12).turning);  // between thresholds: stays straight
  EXPECT_TRUE(step(-0.15).turning);  // exactly at enter (magnitude): turning
}

// A turn ends only after |omega| has stayed at or below turn_exit_rad_s for turn_exit_hold_s
// (frame stamps); a demand above exit in between starts the wait again.
TEST(VelocitySchedule, TurnEndsOnlyAfterTheDemandStayedCalm) {
  VelocityScheduleOptions o = no_rate_limit();
  o.turn_exit_hold_s = 1.0;  // 5 frames at 5 Hz
  VelocitySchedule s(o);
  int64_t t = 0;
  auto step = [&](double w) { return s.step(w, t += kFrame); };
  EXPECT_TRUE(step(0.2).turning);
  for (int i = 0; i < 4; ++i) {  // calm for 0.0 .. 0.6 s: still turning, still slow
    const BaseCommand c = step(0.05);
    EXPECT_TRUE(c.turning) << i;
    EXPECT_DOUBLE_EQ(c.v_m_s, 0.08) << i;
  }
  EXPECT_TRUE(step(0.1).turning);  // above exit: the wait starts again
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(step(0.0).turning) << i;  // 0.0 .. 0.8 s
  const BaseCommand straight = step(0.0);                           // 1.0 s calm
  EXPECT_FALSE(straight.turning);
  EXPECT_DOUBLE_EQ(straight.v_m_s, 0.15);
  EXPECT_FALSE(step(0.12).turning);  // between thresholds: stays straight
}

TEST(VelocitySchedule, PureHysteresisFunction) {
  const VelocityScheduleOptions o;
  EXPECT_FALSE(next_turning_state(false, 0.149, o));
  EXPECT_TRUE(next_turning_state(false, -0.15, o));
  EXPECT_TRUE(next_turning_state(true, 0.081, o));
  EXPECT_FALSE(next_turning_state(true, 0.08, o));
}

TEST(VelocitySchedule, ResetStartsFromRest) {
  VelocitySchedule s;
  s.step(0.5, 0);
  s.step(0.5, kNsPerS);
  s.reset();
  EXPECT_FALSE(s.turning());
  EXPECT_NEAR(s.step(0.5, 0).omega_rad_s, 0.15, 1e-12);  // stamps may restart after reset
}

TEST(VelocitySchedule, ValidateNamesBadFields) {
  VelocityScheduleOptions o;
  EXPECT_TRUE(o.validate().empty());
  o.turn_enter_rad_s = 0.05;  // below exit
  o.v_turn_m_s = 0.2;         // above straight
  o.turn_exit_hold_s = -1.0;
  const auto errors = o.validate();
  ASSERT_EQ(errors.size(), 3u);
  EXPECT_NE(errors[0].find("v_turn_m_s"), std::string::npos);
  EXPECT_NE(errors[1].find("turn_enter_rad_s"), std::string::npos);
  EXPECT_NE(errors[2].find("turn_exit_hold_s"), std::string::npos);
  EXPECT_THROW(VelocitySchedule{o}, std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::control
