// Canonical ceiling view: a ceiling grid projected by an independent pinhole model lands on a
// regular metric grid; round trips; warping agrees with the point maps; bad inputs are refused.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/camera/distortion.hpp"
#include "core/ceiling/canonical_view.hpp"

namespace pepper::core::ceiling {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

// The camera's pose in a base frame (x forward, y left, z up) built as the simulator's mount does
// (head pitch about base +y, then the fixed head-to-camera axes), so the test does not reuse the
// module's own rotation.
Eigen::Matrix3d R_base_cam(double head_pitch_rad) {
  Eigen::Matrix3d R_head_cam;
  // clang-format off
  R_head_cam << 0, 0, 1,
               -1, 0, 0,
                0,-1, 0;
  // clang-format on
  return Eigen::AngleAxisd(head_pitch_rad, Eigen::Vector3d::UnitY()).toRotationMatrix() *
         R_head_cam;
}

// Pixel of the ceiling point (forward, left) h metres above the optical centre; false if behind.
bool project(const CameraIntrinsics& k, double pitch_rad, double h_m, double forward_m,
             double left_m, cv::Point2d& p_px) {
  const Eigen::Vector3d X_cam =
      R_base_cam(pitch_rad).transpose() * Eigen::Vector3d(forward_m, left_m, h_m);
  if (X_cam.z() <= 0) return false;
  p_px = {k.fx_px * X_cam.x() / X_cam.z() + k.cx_px, k.fy_px * X_cam.y() / X_cam.z() + k.cy_px};
  return true;
}

CeilingCamera qvga_camera(double pitch_rad, double h_m) {
  CeilingCamera c;
  c.intrinsics = CameraIntrinsics::pepper_top_vga().scaled_to(320, 240);
  c.head_pitch_rad = pitch_rad;
  c.ceiling_above_cam_m = h_m;
  return c;
}

TEST(CanonicalView, CeilingGridLandsOnRegularMetricGrid) {
  for (const double pitch : {-0.7068, -0.5, -0.2}) {
    SCOPED_TRACE(pitch);
    const CeilingCamera cam = qvga_camera(pitch, 1.4);
    CanonicalFrame frame;
    frame.px_per_m = 100.0;
    frame.width_px = 600;
    frame.height_px = 500;
    frame.center_forward_m = 3.0;
    frame.center_left_m = 0.2;
    const CanonicalView view(cam, frame);
    const double step_m = 0.25;
    int seen = 0;
    for (int i = 0; i <= 24; ++i) {
      for (int j = -12; j <= 12; ++j) {
        const double fwd = 0.5 + i * step_m, left = j * step_m;
        cv::Point2d p_px;
        if (!project(cam.intrinsics, pitch, 1.4, fwd, left, p_px)) continue;
        if (p_px.x < 0 || p_px.y < 0 || p_px.x > 319 || p_px.y > 239) continue;
        ++seen;
        // Through the homography itself (cv::perspectiveTransform), as warp() uses it.
        std::vector<cv::Point2d> in{p_px}, out;
        cv::perspectiveTransform(in, out, view.homography());
        // Regular grid: forward up, left to the right, 100 px per metre around the centre.
        const double u_expected = 299.5 + 100.0 * (left - 0.2);
        const double v_expected = 249.5 - 100.0 * (fwd - 3.0);
        EXPECT_NEAR(out[0].x, u_expected, 1.0) << fwd << " " << left;
        EXPECT_NEAR(out[0].y, v_expected, 1.0) << fwd << " " << left;
        // The point map agrees with the homography to rounding.
        const auto q = view.to_canonical(p_px);
        ASSERT_TRUE(q.has_value());
        EXPECT_NEAR(q->x, out[0].x, 1e-6);
        EXPECT_NEAR(q->y, out[0].y, 1e-6);
      }
    }
    EXPECT_GT(seen, 20);  // the test saw a real part of the grid
  }
}

TEST(CanonicalView, RoundTripsBothWays) {
  const CanonicalView view(qvga_camera(-0.6, 1.5), CanonicalFrame{});
  for (double v = 0; v < 240; v += 17) {
    for (double u = 0; u < 320; u += 23) {
      const auto c = view.to_canonical({u, v});
      ASSERT_TRUE(c.has_value());
      const auto back = view.to_image(*c);
      ASSERT_TRUE(back.has_value());
      EXPECT_NEAR(back->x, u, 1e-9);
      EXPECT_NEAR(back->y, v, 1e-9);
    }
  }
  for (double v = 0; v < 320; v += 31) {
    for (double u = 0; u < 320; u += 29) {
      const auto p = view.to_image({u, v});
      ASSERT_TRUE(p.has_value());
      const auto back = view.to_canonical(*p);
      ASSERT_TRUE(back.has_value());
      EXPECT_NEAR(back->x, u, 1e-9);
      EXPECT_NEAR(back->y, v, 1e-9);
    }
  }
  // The two homographies are inverses up to scale (each is normalised to H(2, 2) = 1).
  cv::Matx33d I = view.H_canon_img() * view.H_img_canon();
  I *= 1.0 / I(2, 2);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(I(r, c), r == c ? 1.0 : 0.0, 1e-9);
}

TEST(CanonicalView, LeftTurnMovesThePointAheadToTheLeftOfTheCanonicalImage) {
  // A ceiling point ahead, seen after the base turned left by 0.1 rad, is at the robot's right:
  // (forward, left) rotated by -0.1 rad; the canonical image shows it left of where it was.
  const CanonicalView view(qvga_camera(-0.7, 1.4), CanonicalFrame{});
  const cv::Point2d before = view.canonical_of_ceiling({2.0, 0.0});
  const cv::Point2d after = view.canonical_of_ceiling({2.0 * std::cos(0.1), -2.0 * std::sin(0.1)});
  EXPECT_LT(after.x, before.x - 10.0);
}

TEST(CanonicalView, WarpMovesADotWhereThePointMapSays) {
  const CeilingCamera cam = qvga_camera(-0.65, 1.3);
  CanonicalFrame frame;
  frame.px_per_m = 60.0;
  frame.width_px = 400;
  frame.height_px = 400;
  frame.center_forward_m = 3.0;
  const CanonicalView view(cam, frame);
  for (const cv::Point2d p_px :
       {cv::Point2d(160, 120), cv::Point2d(60, 200), cv::Point2d(280, 40)}) {
    cv::Mat image(240, 320, CV_8UC1, cv::Scalar(0));
    cv::circle(image, cv::Point(static_cast<int>(p_px.x), static_cast<int>(p_px.y)), 2,
               cv::Scalar(255), cv::FILLED);
    cv::Mat seen;
    cv::Mat canon = view.warp(image, &seen);
    ASSERT_EQ(canon.size(), cv::Size(400, 400));
    ASSERT_EQ(canon.type(), CV_8UC1);
    cv::GaussianBlur(canon, canon, cv::Size(5, 5), 0);
    cv::Point max_loc;
    cv::minMaxLoc(canon, nullptr, nullptr, nullptr, &max_loc);
    const auto expected = view.to_canonical(p_px);
    ASSERT_TRUE(expected.has_value());
    EXPECT_NEAR(max_loc.x, expected->x, 2.0);
    EXPECT_NEAR(max_loc.y, expected->y, 2.0);
    EXPECT_EQ(seen.at<uint8_t>(max_loc), 255);
  }
}

TEST(CanonicalView, SeenMaskIsTheCameraFootprint) {
  const CanonicalView view(qvga_camera(-0.7, 1.4), CanonicalFrame{});
  cv::Mat seen;
  view.warp(cv::Mat(240, 320, CV_8UC1, cv::Scalar(100)), &seen);
  int checked = 0;
  for (int v = 0; v < seen.rows; v += 7) {
    for (int u = 0; u < seen.cols; u += 7) {
      const auto p = view.to_image({static_cast<double>(u), static_cast<double>(v)});
      ASSERT_TRUE(p.has_value());
      // Away from the border by a pixel, the mask says whether the camera sees the point.
      const bool in = p->x > 1 && p->y > 1 && p->x < 318 && p->y < 238;
      const bool out = p->x < -1 || p->y < -1 || p->x > 320 || p->y > 240;
      if (in) {
        EXPECT_EQ(seen.at<uint8_t>(v, u), 255) << u << " " << v;
      }
      if (out) {
        EXPECT_EQ(seen.at<uint8_t>(v, u), 0) << u << " " << v;
      }
      checked += in || out;
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(CanonicalView, DistortedIntrinsicsAreMappedThroughTheLens) {
  CeilingCamera cam = qvga_camera(-0.6, 1.4);
  cam.intrinsics.model = ProjectionModel::kWithDistortion;
  cam.intrinsics.kud = 0.03;
  cam.intrinsics.kdu = -0.029;
  const CanonicalView view(cam, CanonicalFrame{});
  // A ceiling point's distorted pixel maps back to the same ceiling point (to the accuracy of
  // the kud/kdu pair, distortion.hpp: ~1e-4 normalised units, a few mm here).
  const cv::Point2d fl(1.8, 1.15);  // near the image's left edge, where the lens bends most
  const auto p = view.pixel_of_ceiling(fl);
  ASSERT_TRUE(p.has_value());
  const cv::Point2d pinhole = cam.intrinsics.denormalize(camera::pixel_to_norm(cam.intrinsics, *p));
  EXPECT_GT(cv::norm(*p - pinhole), 0.5);  // the lens matters at this pixel
  const auto back = view.ceiling_of_pixel(*p);
  ASSERT_TRUE(back.has_value());
  EXPECT_NEAR(back->x, fl.x, 0.01);
  EXPECT_NEAR(back->y, fl.y, 0.01);
  // warp() goes through the lens too: a dot at the distorted pixel lands at the point's place.
  cv::Mat image(240, 320, CV_8UC1, cv::Scalar(0));
  cv::circle(image,
             cv::Point(static_cast<int>(std::lround(p->x)), static_cast<int>(std::lround(p->y))), 2,
             cv::Scalar(255), cv::FILLED);
  cv::Mat canon = view.warp(image);
  cv::GaussianBlur(canon, canon, cv::Size(5, 5), 0);
  cv::Point max_loc;
  cv::minMaxLoc(canon, nullptr, nullptr, nullptr, &max_loc);
  const cv::Point2d expected = view.canonical_of_ceiling(fl);
  EXPECT_NEAR(max_loc.x, expected.x, 2.0);
  EXPECT_NEAR(max_loc.y, expected.y, 2.0);
}

TEST(CanonicalView, PixelsAtOrBelowTheHorizonHaveNoCeilingPoint) {
  // At pitch 0 the optical axis is horizontal: the lower half of the image looks down.
  const CeilingCamera cam = qvga_camera(0.0, 1.4);
  CanonicalFrame frame;
  frame.center_forward_m = 30.0;
  const CanonicalView view(cam, frame);
  EXPECT_FALSE(view.to_canonical({160, 200}).has_value());
  EXPECT_FALSE(view.ceiling_of_pixel({160, cam.intrinsics.cy_px}).has_value());
  EXPECT_TRUE(view.to_canonical({160, 10}).has_value());
  // A ceiling point behind the camera has no pixel.
  EXPECT_FALSE(view.pixel_of_ceiling({-1.0, 0.0}).has_value());
}

TEST(CanonicalView, RefusesGeometryThatDoesNotSeeTheCeiling) {
  const CameraIntrinsics k = qvga_camera(0, 1).intrinsics;
  const double max_pitch = max_ceiling_pitch_rad(k);
  EXPECT_NEAR(max_pitch, std::atan(k.cy_px / k.fy_px), 1e-12);
  // Looking down (pitch > 0) beyond the limit: no row sees above the horizon.
  try {
    CanonicalView(qvga_camera(max_pitch + 0.05, 1.4), CanonicalFrame{});
    FAIL() << "expected CeilingViewError";
  } catch (const CeilingViewError& e) {
    EXPECT_THAT(e.what(),
                AllOf(HasSubstr("head_pitch_rad"), HasSubstr("horizon"), HasSubstr("looks down")));
  }
  for (const double h : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                         std::numeric_limits<double>::infinity()}) {
    try {
      CanonicalView(qvga_camera(-0.7, h), CanonicalFrame{});
      FAIL() << "expected CeilingViewError for height " << h;
    } catch (const CeilingViewError& e) {
      EXPECT_THAT(e.what(), HasSubstr("ceiling_above_cam_m"));
    }
  }
  EXPECT_THROW(
      CanonicalView(qvga_camera(std::numeric_limits<double>::quiet_NaN(), 1.4), CanonicalFrame{}),
      CeilingViewError);
  CeilingCamera bad_k = qvga_camera(-0.7, 1.4);
  bad_k.intrinsics.fx_px = -1.0;
  EXPECT_THROW(CanonicalView(bad_k, CanonicalFrame{}), CeilingViewError);
}

TEST(CanonicalView, RefusesAFrameBehindTheCameraOrMalformed) {
  CanonicalFrame behind;
  behind.center_forward_m = -3.0;  // at pitch 0 the image plane is vertical through the centre
  try {
    CanonicalView(qvga_camera(0.0, 1.4), behind);
    FAIL() << "expected CeilingViewError";
  } catch (const CeilingViewError& e) {
    EXPECT_THAT(e.what(), HasSubstr("behind the camera"));
  }
  CanonicalFrame scale;
  scale.px_per_m = 0.0;
  try {
    CanonicalView(qvga_camera(-0.7, 1.4), scale);
    FAIL() << "expected CeilingViewError";
  } catch (const CeilingViewError& e) {
    EXPECT_THAT(e.what(), HasSubstr("px_per_m"));
  }
  CanonicalFrame size;
  size.width_px = 0;
  EXPECT_THROW(CanonicalView(qvga_camera(-0.7, 1.4), size), CeilingViewError);
  const CanonicalView view(qvga_camera(-0.7, 1.4), CanonicalFrame{});
  try {
    view.warp(cv::Mat(480, 640, CV_8UC1, cv::Scalar(0)));
    FAIL() << "expected CeilingViewError";
  } catch (const CeilingViewError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("640x480"), HasSubstr("320x240")));
  }
}

TEST(CanonicalView, FitFrameBoundsTheFootprint) {
  const CeilingCamera cam = qvga_camera(-0.7068, 1.4);
  const CanonicalFrame frame = fit_frame(cam, 50.0, 6.0);
  const CanonicalView view(cam, frame);
  // Every image pixel whose ceiling point is within 6 m ahead lands inside the frame.
  for (double v = 0; v <= 239; v += 239.0 / 8) {
    for (double u = 0; u <= 319; u += 319.0 / 8) {
      const auto fl = view.ceiling_of_pixel({u, v});
      ASSERT_TRUE(fl.has_value());
      if (fl->x > 6.0) continue;
      const cv::Point2d c = view.canonical_of_ceiling(*fl);
      EXPECT_GE(c.x, -0.6);
      EXPECT_GE(c.y, -0.6);
      EXPECT_LE(c.x, frame.width_px - 0.4);
      EXPECT_LE(c.y, frame.height_px - 0.4);
    }
  }
  // ...and the frame is tight: the camera sees a good part of it.
  cv::Mat seen;
  view.warp(cv::Mat(240, 320, CV_8UC1, cv::Scalar(1)), &seen);
  EXPECT_GT(cv::countNonZero(seen), seen.total() / 3);
  EXPECT_THROW(fit_frame(cam, 50.0, 0.1), CeilingViewError);  // nothing that close is seen
}

}  // namespace
}  // namespace pepper::core::ceiling
