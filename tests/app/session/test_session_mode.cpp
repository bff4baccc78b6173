// --mode forward|ceiling (issue 24): the head lock follows the mode, ceiling mode is refused on
// real robots by teach and replay until the ceiling's height is set, the ceiling pitch and height
// are range-checked, and a real Pepper's ceiling camera agrees with the simulated one.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>
#include <string>

#include "config/app_config.hpp"
#include "config/parameters.hpp"
#include "session/ceiling_teach.hpp"
#include "session/session_cli.hpp"
#include "sim/mock_robot.hpp"
#include "sim/world.hpp"

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

TEST(SessionMode, CeilingModeOnARealRobotNeedsTheCeilingHeight) {
  AppConfig config;  // robot.ceiling_height_m not set
  const auto ceiling = core::NavMode::kCeiling;
  EXPECT_NO_THROW(refuse_ceiling_on_real_robot(ceiling, "mock:w.yaml", config, "replay"));
  EXPECT_NO_THROW(
      refuse_ceiling_on_real_robot(core::NavMode::kForward, "tcp://10.0.0.5", config, "replay"));
  try {
    refuse_ceiling_on_real_robot(ceiling, "tcp://10.0.0.5", config, "replay");
    FAIL() << "ceiling mode on a real robot without the ceiling's height was not refused";
  } catch (const ModeUnavailableError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("replay --mode ceiling"),
                                HasSubstr("robot.ceiling_height_m"), HasSubstr("--set")));
  }
  config.robot.ceiling_height_m = 2.7;
  EXPECT_NO_THROW(refuse_ceiling_on_real_robot(ceiling, "tcp://10.0.0.5", config, "teach"));
}

TEST(SessionMode, APeppersCeilingCameraIsTheSimulatedOnes) {
  // The mock robot's camera mount (sim) and the real Pepper's (geometry::pepper_top_camera) give
  // the same canonical view: the ceiling's height above the camera and the camera on the base,
  // within a millimetre, at the ceiling pitch and at another one.
  auto world = std::make_shared<const sim::World>(
      sim::load_world(std::string(PEPPER_SOURCE_DIR) + "/worlds/robotics_room.yaml"));
  sim::MockRobot robot(world);
  core::CameraIntrinsics camera;
  camera.width_px = 320;
  camera.height_px = 240;
  camera.fx_px = camera.fy_px = 278.0;
  camera.cx_px = 160.0;
  camera.cy_px = 120.0;
  for (const double pitch_rad : {-0.7, -0.4}) {
    const CeilingCameraSetup mock = ceiling_camera_of_mock(robot, camera, pitch_rad);
    const CeilingCameraSetup real =
        ceiling_camera_of_pepper(world->ceiling_height_m, camera, pitch_rad);
    EXPECT_NEAR(real.camera.ceiling_above_cam_m, mock.camera.ceiling_above_cam_m, 1e-3) << pitch_rad;
    EXPECT_NEAR(real.cam_in_base_m.x, mock.cam_in_base_m.x, 1e-3) << pitch_rad;
    EXPECT_NEAR(real.cam_in_base_m.y, mock.cam_in_base_m.y, 1e-3) << pitch_rad;
    EXPECT_EQ(real.camera.head_pitch_rad, pitch_rad);
    // The session's choice: the simulated robot's when there is one.
    EXPECT_EQ(ceiling_camera_for(&robot, 9.0, camera, pitch_rad).camera.ceiling_above_cam_m,
              mock.camera.ceiling_above_cam_m);
  }
  // A ceiling below the camera, or not set: a clear error naming the option.
  try {
    ceiling_camera_of_pepper(0.0, camera, -0.7);
    FAIL() << "a ceiling height of 0 was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("robot.ceiling_height_m"));
  }
  EXPECT_THROW(ceiling_camera_for(nullptr, 1.0, camera, -0.7), std::invalid_argument);
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
  config = AppConfig{};
  config.robot.ceiling_height_m = -2.0;
  ASSERT_EQ(check_ranges(config).size(), 1u);
  EXPECT_THAT(check_ranges(config)[0], HasSubstr("robot.ceiling_height_m"));
}

}  // namespace
}  // namespace pepper::app
