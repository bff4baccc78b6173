// `evaluate --lens pepper --lens-correction on|off` (issue 31): the options parse, the mock of
// the teach and of every replay run renders through Pepper's lens, and the app's camera model
// (what the map records and the features are normalised with) has the lens's distortion with the
// correction and the pinhole calibration without it.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "core/camera/intrinsics.hpp"
#include "evaluation/closed_loop.hpp"
#include "sim/mock_robot.hpp"
#include "sim/world.hpp"
#include "support/temp_dir.hpp"

namespace pepper::app::evaluation {
namespace {

std::shared_ptr<const sim::World> small_room() {
  static const auto w = std::make_shared<const sim::World>(sim::load_world(
      std::string(PEPPER_SOURCE_DIR) + "/tests/app/evaluation/data/small_room.yaml"));
  return w;
}

TEST(LensOption, ParsesTheTwoLensesAndTheCorrectionAndRefusesOthers) {
  EvaluationOptions o;
  EXPECT_EQ(o.lens, EvaluationOptions::Lens::kNone);  // the default: a pinhole mock
  EXPECT_TRUE(o.correct_lens);
  set_lens_options("pepper", "off", o);
  EXPECT_EQ(o.lens, EvaluationOptions::Lens::kPepper);
  EXPECT_FALSE(o.correct_lens);
  EXPECT_EQ(lens_label(o), "pepper uncorrected");
  set_lens_options("pepper", "on", o);
  EXPECT_TRUE(o.correct_lens);
  EXPECT_EQ(lens_label(o), "pepper");
  set_lens_options("none", "on", o);
  EXPECT_EQ(o.lens, EvaluationOptions::Lens::kNone);
  EXPECT_EQ(lens_label(o), "none");
  try {
    set_lens_options("fisheye", "on", o);
    FAIL() << "unknown lens accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--lens must be none or pepper"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("fisheye"), std::string::npos) << e.what();
  }
  EXPECT_THROW(set_lens_options("pepper", "yes", o), std::invalid_argument);
}

// The replay runs' mock: its camera is the lens, it reports it, and its frames differ from the
// pinhole mock's of the same run (same pose, light and noise seed) by the lens alone: they are
// those of a mock given the lens's camera directly. (Where the lens puts a point in the image is
// sim's test, Renderer.DistortionModelMovesPointsWhereViSPsModelPutsThem.)
TEST(LensOption, ReachesTheRenderer) {
  EvaluationOptions pinhole_options, lens_options;
  set_lens_options("pepper", "on", lens_options);
  const MockReplaySetup pin = mock_replay_setup(*small_room(), 0, "replay", pinhole_options);
  const MockReplaySetup lens = mock_replay_setup(*small_room(), 0, "replay", lens_options);
  EXPECT_EQ(pin.robot.intrinsics_vga, core::CameraIntrinsics::pepper_top_vga());
  EXPECT_EQ(lens.robot.intrinsics_vga, core::CameraIntrinsics::pepper_top_vga_with_distortion());
  sim::MockRobotOptions given = pin.robot;
  given.intrinsics_vga = core::CameraIntrinsics::pepper_top_vga_with_distortion();
  sim::MockRobot pin_robot(small_room(), pin.robot), lens_robot(small_room(), lens.robot),
      given_robot(small_room(), given);
  for (sim::MockRobot* robot : {&pin_robot, &lens_robot, &given_robot}) robot->place(pin.start);
  EXPECT_EQ(lens_robot.intrinsics(320, 240),
            core::CameraIntrinsics::pepper_top_vga_with_distortion().scaled_to(320, 240));
  const cv::Mat a = pin_robot.capture(320, 240).gray, b = lens_robot.capture(320, 240).gray,
                c = given_robot.capture(320, 240).gray;
  ASSERT_EQ(a.size(), b.size());
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  EXPECT_GT(cv::mean(diff)[0], 1.0);  // grey levels per pixel
  EXPECT_EQ(cv::norm(b, c, cv::NORM_INF), 0.0);
}

// What the app teaches with: the lens model with the correction (the map records
// perspectiveProjWithDistortion, the features are undistorted), the pinhole calibration without.
TEST(LensOption, TheMapRecordsTheAppsCameraModel) {
  EvaluationOptions o;
  o.width_px = 320;
  o.height_px = 240;
  o.starts = 1;
  o.seed = 3;
  set_lens_options("pepper", "off", o);
  ASSERT_TRUE(app_camera_model(o).has_value());
  EXPECT_EQ(*app_camera_model(o), core::CameraIntrinsics::pepper_top_vga());
  set_lens_options("none", "on", o);
  EXPECT_FALSE(app_camera_model(o).has_value());
  set_lens_options("pepper", "on", o);
  EXPECT_FALSE(app_camera_model(o).has_value());  // the mock reports the lens

  const test::TempDir tmp("lens_teach");
  o.map_dir = tmp.path() / "corrected";
  const TeachResult corrected = teach_tour(small_room(), o);
  EXPECT_EQ(corrected.map.camera,
            core::CameraIntrinsics::pepper_top_vga_with_distortion().scaled_to(320, 240));
  for (const auto& key : corrected.map.key_images) {
    EXPECT_EQ(key.features.intrinsics.model, core::ProjectionModel::kWithDistortion);
  }
  set_lens_options("pepper", "off", o);
  o.map_dir = tmp.path() / "uncorrected";
  const TeachResult uncorrected = teach_tour(small_room(), o);
  EXPECT_EQ(uncorrected.map.camera, core::CameraIntrinsics::pepper_top_vga().scaled_to(320, 240));
}

}  // namespace
}  // namespace pepper::app::evaluation
