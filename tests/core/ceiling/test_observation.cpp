// observe(): canonical-view landmarks to base-frame points and orientations.
#include <gtest/gtest.h>

#include <cmath>

#include "core/ceiling/observation.hpp"

namespace pepper::core::ceiling {
namespace {

TEST(CeilingObservation, CanonicalPixelsBecomeBaseFramePointsAndAngles) {
  CeilingCamera camera;
  camera.intrinsics = CameraIntrinsics::pepper_top_vga().scaled_to(320, 240);
  camera.head_pitch_rad = -0.7;
  camera.ceiling_above_cam_m = 1.5;
  CanonicalFrame frame;
  frame.width_px = 200;
  frame.height_px = 200;
  frame.px_per_m = 100.0;
  frame.center_forward_m = 2.0;
  frame.center_left_m = 0.0;
  const CanonicalView view(camera, frame);
  const cv::Point2d cam_in_base(0.07, 0.0);

  CeilingLandmarks lm;
  // The ceiling point 2 m straight ahead of the optical centre, and one 0.2 m farther and 0.3 m
  // to the left (30 px right and 20 px up of it on the canonical image).
  const cv::Point2d ahead = view.canonical_of_ceiling({2.0, 0.0});
  const cv::Point2d ahead_left = view.canonical_of_ceiling({2.2, 0.3});
  EXPECT_NEAR(ahead_left.x - ahead.x, 30.0, 1e-9);
  EXPECT_NEAR(ahead_left.y - ahead.y, -20.0, 1e-9);
  lm.keypoints.emplace_back(cv::Point2f(ahead), 31.0f, 0.0f);
  lm.keypoints.emplace_back(cv::Point2f(ahead_left), 31.0f, 90.0f);
  lm.keypoints.emplace_back(cv::Point2f(ahead), 31.0f, 180.0f);
  lm.descriptors = cv::Mat::zeros(3, 32, CV_8U);
  const CeilingObservation o = observe(view, cam_in_base, lm);
  ASSERT_EQ(o.size(), 3u);
  EXPECT_EQ(o.descriptors.rows, 3);
  // The optical centre is 7 cm ahead of the base's rotation axis (float pixels: 1e-5 m).
  EXPECT_NEAR(o.p_base_m[0].x, 2.07, 1e-5);
  EXPECT_NEAR(o.p_base_m[0].y, 0.0, 1e-5);
  EXPECT_NEAR(o.p_base_m[1].x, 2.27, 1e-5);
  EXPECT_NEAR(o.p_base_m[1].y, 0.3, 1e-5);
  // Image direction +u (angle 0) is the robot's left (+pi/2 in the base); +v (90 deg, image
  // down) is the robot's back (pi); -u (180 deg) is the robot's right (-pi/2).
  EXPECT_NEAR(o.orientation_base_rad[0], M_PI / 2, 1e-6);
  EXPECT_NEAR(std::abs(o.orientation_base_rad[1]), M_PI, 1e-6);
  EXPECT_NEAR(o.orientation_base_rad[2], -M_PI / 2, 1e-6);
  EXPECT_NEAR(o.orientation_canon_rad[1], M_PI / 2, 1e-6);
  EXPECT_EQ(o.p_canon_px[1], cv::Point2f(ahead_left));
}

}  // namespace
}  // namespace pepper::core::ceiling
