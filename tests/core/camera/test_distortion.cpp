// Pixel <-> normalised through the projection model (core/camera/distortion.hpp) against ViSP's
// vpPixelMeterConversion / vpMeterPixelConversion, through visp_adapter.
#include "core/camera/distortion.hpp"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "visp_adapter/pixel_conversion.hpp"

namespace pepper::core::camera {
namespace {

// Same formulas on O(1) values: rounding only (~1e-13 px); a wrong coefficient or radius moves
// the corner pixels of Pepper's VGA image by whole pixels.
constexpr double kTolPx = 1e-9;
constexpr double kTolNorm = 1e-12;

visp_adapter::CameraCalibration to_adapter(const CameraIntrinsics& k) {
  visp_adapter::CameraCalibration c;
  c.width_px = k.width_px;
  c.height_px = k.height_px;
  c.model = k.model == ProjectionModel::kWithDistortion
                ? visp_adapter::CameraModel::kPerspectiveWithDistortion
                : visp_adapter::CameraModel::kPerspectiveWithoutDistortion;
  c.px = k.fx_px;
  c.py = k.fy_px;
  c.u0 = k.cx_px;
  c.v0 = k.cy_px;
  c.kud = k.kud;
  c.kdu = k.kdu;
  return c;
}

CameraIntrinsics pepper_with_distortion() {
  CameraIntrinsics k = CameraIntrinsics::pepper_top_vga();
  k.model = ProjectionModel::kWithDistortion;
  k.kud = 0.03;  // Pepper's top camera, PEPPER.md
  k.kdu = -0.029;
  return k;
}

TEST(Distortion, BothDirectionsAreViSPs) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(0.0, 639.0), v(0.0, 479.0), x(-0.6, 0.6), y(-0.45, 0.45);
  for (const CameraIntrinsics& k : {CameraIntrinsics::pepper_top_vga(), pepper_with_distortion()}) {
    const visp_adapter::CameraCalibration c = to_adapter(k);
    for (int i = 0; i < 1000; ++i) {
      const cv::Point2d p_px{u(rng), v(rng)};
      const cv::Point2d n = pixel_to_norm(k, p_px);
      const auto [vx, vy] = visp_adapter::pixel_to_meter(c, p_px.x, p_px.y);
      ASSERT_NEAR(n.x, vx, kTolNorm) << to_string(k.model) << " u=" << p_px.x << " v=" << p_px.y;
      ASSERT_NEAR(n.y, vy, kTolNorm);
      const cv::Point2d q_norm{x(rng), y(rng)};
      const cv::Point2d q_px = norm_to_pixel(k, q_norm);
      const auto [vu, vv] = visp_adapter::meter_to_pixel(c, q_norm.x, q_norm.y);
      ASSERT_NEAR(q_px.x, vu, kTolPx) << to_string(k.model) << " x=" << q_norm.x << " y=" << q_norm.y;
      ASSERT_NEAR(q_px.y, vv, kTolPx);
    }
  }
}

TEST(Distortion, PepperLensMovesTheCornersByPixelsAndNotTheCentre) {
  const CameraIntrinsics k = pepper_with_distortion();
  const CameraIntrinsics pinhole = CameraIntrinsics::pepper_top_vga();
  const cv::Point2d centre{k.cx_px, k.cy_px};
  EXPECT_NEAR(pixel_to_norm(k, centre).x, 0.0, 1e-15);
  const cv::Point2d corner{0.0, 0.0};
  const cv::Point2d moved = norm_to_pixel(k, pinhole.normalize(corner));
  // r^2 ~ 0.45 at the corner: kud r^2 ~ 1.4 % of ~400 px from the centre, about 5 px.
  EXPECT_GT(std::hypot(moved.x - corner.x, moved.y - corner.y), 3.0);
  // kud and kdu are two fits, not inverses: the round trip comes back within a fraction of a pixel.
  const cv::Point2d back = norm_to_pixel(k, pixel_to_norm(k, corner));
  EXPECT_LT(std::hypot(back.x - corner.x, back.y - corner.y), 0.5);
}

}  // namespace
}  // namespace pepper::core::camera
