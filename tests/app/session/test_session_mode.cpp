// --mode forward|ceiling (issue 24): the head lock follows the mode, ceiling mode is refused on
// real robots by teach and replay, and the ceiling pitch is range-checked.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "config/app_config.hpp"
#include "config/parameters.hpp"
#include "session/session_cli.hpp"

namespace pepper::app {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

TEST(SessionMode, HeadLockTakesTheCeilingPitchInCeilingMode) {
  AppConfig config;
  config.robot.head_pitch_rad = 0.1;
  config.robot.ceiling_head_pitch_rad = -0.6;
  config.robot.head_yaw_rad = 0.2;
  const auto forward = head_request(config, core::NavMode::kForward);
  EXPECT_EQ(forward.head_pitch_rad, 0.1);
  EXPECT_EQ(forward.head_yaw_rad, 0.2);
  const auto ceiling = head_request(config, core::NavMode::kCeiling);
  EXPECT_EQ(ceiling.head_pitch_rad, -0.6);
  EXPECT_EQ(ceiling.head_yaw_rad, 0.2);
  EXPECT_EQ(head_request(config).head_pitch_rad, 0.1);  // forward is the default
  // The default ceiling pitch looks up, near HeadPitch's limit.
  EXPECT_LT(AppConfig{}.robot.ceiling_head_pitch_rad, -0.6);
  EXPECT_GE(AppConfig{}.robot.ceiling_head_pitch_rad, -0.707);
}

TEST(SessionMode, ModesParse) {
  EXPECT_EQ(parse_mode("forward"), core::NavMode::kForward);
  EXPECT_EQ(parse_mode("ceiling"), core::NavMode::kCeiling);
  EXPECT_THROW(parse_mode("sideways"), ConfigError);
}

TEST(SessionMode, CeilingModeIsRefusedOnRealRobotsOnly) {
  EXPECT_NO_THROW(refuse_ceiling_on_real_robot(core::NavMode::kCeiling, "mock:w.yaml", "replay"));
  EXPECT_NO_THROW(refuse_ceiling_on_real_robot(core::NavMode::kForward, "tcp://10.0.0.5", "replay"));
  try {
    refuse_ceiling_on_real_robot(core::NavMode::kCeiling, "tcp://10.0.0.5", "replay");
    FAIL() << "ceiling mode on a real robot was not refused";
  } catch (const ModeUnavailableError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("replay --mode ceiling"), HasSubstr("mock: robots only"),
                                HasSubstr("ceiling's height")));
  }
}

TEST(SessionMode, CeilingPitchMustLookUp) {
  AppConfig config;
  EXPECT_TRUE(check_ranges(config).empty());
  config.robot.ceiling_head_pitch_rad = 0.2;  // looks down: no ceiling
  const auto problems = check_ranges(config);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_THAT(problems[0], HasSubstr("robot.ceiling_head_pitch_rad"));
  config.robot.ceiling_head_pitch_rad = -0.8;  // beyond HeadPitch's range
  EXPECT_EQ(check_ranges(config).size(), 1u);
}

}  // namespace
}  // namespace pepper::app
