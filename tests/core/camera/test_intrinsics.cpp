#include "core/camera/intrinsics.hpp"

#include <gtest/gtest.h>

namespace pepper::core {
namespace {

constexpr double kTol = 1e-12;  // exact arithmetic on a few operations

TEST(CameraIntrinsics, PepperVgaIsQvgaCalibrationScaledWithPixelCentres) {
  const CameraIntrinsics k = CameraIntrinsics::pepper_top_vga();
  EXPECT_EQ(k.width_px, 640);
  EXPECT_EQ(k.height_px, 480);
  EXPECT_NEAR(k.fx_px, 596.26, kTol);             // 298.13 * 2
  EXPECT_NEAR(k.fy_px, 597.44, kTol);             // 298.72 * 2
  EXPECT_NEAR(k.cx_px, 318.80, 1e-9);             // (159.15 + 0.5) * 2 - 0.5
  EXPECT_NEAR(k.cy_px, 238.32, 1e-9);             // (118.91 + 0.5) * 2 - 0.5
  EXPECT_TRUE(k.validate().empty());
}

TEST(CameraIntrinsics, NormalizeDenormalizeRoundTrip) {
  const CameraIntrinsics k = CameraIntrinsics::pepper_top_vga();
  const cv::Point2d p_px{123.25, 401.5};
  const cv::Point2d p_norm = k.normalize(p_px);
  EXPECT_NEAR(p_norm.x, (123.25 - 318.8) / 596.26, 1e-12);
  EXPECT_NEAR(p_norm.y, (401.5 - 238.32) / 597.44, 1e-12);
  const cv::Point2d back = k.denormalize(p_norm);
  EXPECT_NEAR(back.x, p_px.x, 1e-9);
  EXPECT_NEAR(back.y, p_px.y, 1e-9);
}

TEST(CameraIntrinsics, ScalingTwiceBackIsIdentity) {
  const CameraIntrinsics k = CameraIntrinsics::pepper_top_vga();
  const CameraIntrinsics back = k.scaled_to(320, 240).scaled_to(640, 480);
  EXPECT_NEAR(back.fx_px, k.fx_px, 1e-9);
  EXPECT_NEAR(back.cx_px, k.cx_px, 1e-9);
  EXPECT_NEAR(back.cy_px, k.cy_px, 1e-9);
}

TEST(CameraIntrinsics, ValidateNamesEveryBadField) {
  CameraIntrinsics k;
  k.width_px = 0;
  k.height_px = 480;
  k.fx_px = -1.0;
  k.fy_px = 500.0;
  k.cx_px = std::numeric_limits<double>::quiet_NaN();
  k.cy_px = 240.0;
  const auto errors = k.validate();
  ASSERT_EQ(errors.size(), 3u);
  EXPECT_NE(errors[0].find("width_px"), std::string::npos);
  EXPECT_NE(errors[1].find("fx_px"), std::string::npos);
  EXPECT_NE(errors[2].find("cx_px"), std::string::npos);
}

}  // namespace
}  // namespace pepper::core
