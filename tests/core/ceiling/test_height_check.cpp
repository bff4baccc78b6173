// The ceiling-height check against the odometry (height_check.hpp) on synthetic tours: the scale
// of a chain built under a wrong height is found exactly without noise, through the mosaic
// builder with observation noise and drifting odometry; losses, jumps of the chain and a tour of
// turns are handled; a short tour or one without odometry gives no estimate; bad input refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <vector>

#include "core/ceiling/height_check.hpp"
#include "core/ceiling/mosaic_builder.hpp"
#include "synthetic_ceiling.hpp"

namespace pepper::core::ceiling {
namespace {

namespace ts = test_support;

// Pepper's optical centre is 5-9 cm ahead of the rotation axis (observation.hpp).
const cv::Point2d kCamInBase{0.07, 0.0};
// The ceiling 1.45 m above the camera, whose optical centre is 1.15 m above the floor.
constexpr double kAboveCamM = 1.45;
constexpr double kCamHeightM = 1.15;

// The base poses a chain built under a height k times the true one gives: the optical centre's
// path scaled by k about the first frame's, the headings unchanged (height_check.hpp).
std::vector<PlanarPose> scaled_chain(const std::vector<PlanarPose>& truth, double k) {
  const PlanarPose T_0_world = truth.front().inverse();
  std::vector<PlanarPose> out;
  for (const PlanarPose& T : truth) {
    const PlanarPose T_0_base = T_0_world * T;
    const cv::Point2d centre = k * (T_0_base.apply(kCamInBase) - kCamInBase) + kCamInBase;
    const cv::Point2d rotated_c =
        T_0_base.apply(kCamInBase) - cv::Point2d(T_0_base.x_m, T_0_base.y_m);  // R c
    out.push_back({centre.x - rotated_c.x, centre.y - rotated_c.y, T_0_base.theta_rad});
  }
  return out;
}

// Wheel odometry as the simulator's (sim/wheel_odometry.hpp): every step's translation read
// (1 + scale_error)(1 + N(0, noise_rel)) times its length, its rotation (1 + yaw_scale_error)
// times its angle (the simulator's: 3 %); the odometry frame is rotated and shifted from the
// mosaic's (only displacements mean anything).
std::vector<std::optional<OdometryPose>> wheel_odometry(const std::vector<PlanarPose>& truth,
                                                        double scale_error, double noise_rel,
                                                        uint32_t seed,
                                                        double yaw_scale_error = 0.03) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise_rel);
  PlanarPose odom{3.0, -2.0, 0.7};
  std::vector<std::optional<OdometryPose>> out;
  out.push_back(OdometryPose{odom.x_m, odom.y_m, odom.theta_rad});
  for (size_t i = 1; i < truth.size(); ++i) {
    PlanarPose step = truth[i - 1].inverse() * truth[i];
    const double f = (1.0 + scale_error) * (1.0 + n(rng));
    step.x_m *= f;
    step.y_m *= f;
    step.theta_rad *= 1.0 + yaw_scale_error;
    odom = odom * step;
    out.push_back(OdometryPose{odom.x_m, odom.y_m, odom.theta_rad});
  }
  return out;
}

std::vector<HeightCheckFrame> frames_of(const std::vector<PlanarPose>& chain,
                                        const std::vector<std::optional<OdometryPose>>& odom) {
  std::vector<HeightCheckFrame> f(chain.size());
  for (size_t i = 0; i < chain.size(); ++i) {
    f[i].T_mosaic_base = chain[i];
    if (odom[i]) f[i].T_odom_base = PlanarPose{odom[i]->x_m, odom[i]->y_m, odom[i]->yaw_rad};
  }
  return f;
}

HeightCheck check(const std::vector<HeightCheckFrame>& f, double configured_above_m = kAboveCamM,
                  const HeightCheckOptions& o = {}) {
  return check_ceiling_height(f, kCamInBase, kCamHeightM + configured_above_m, configured_above_m,
                              o);
}

// Turning on the spot, `turns` full turns at 0.05 rad per frame.
std::vector<PlanarPose> turns_on_the_spot(double turns) {
  std::vector<PlanarPose> p;
  const int n = static_cast<int>(turns * 2.0 * M_PI / 0.05);
  for (int i = 0; i <= n; ++i) p.push_back({1.0, 2.0, 0.05 * i});
  return p;
}

std::vector<PlanarPose> straight(double length_m, double step_m = 0.02) {
  std::vector<PlanarPose> p;
  const int n = static_cast<int>(std::lround(length_m / step_m));
  for (int i = 0; i <= n; ++i) p.push_back({step_m * i, 0.0, 0.0});
  return p;
}

// Without noise the optical centre's chords scale exactly by k, turns included (the base's own
// path does not: it is off by (1 - k)(R_j - R_i) c, 1.4 cm over a half turn at k = 0.9).
TEST(HeightCheck, AnExactChainUnderAWrongHeightGivesItsScaleExactly) {
  const ts::SyntheticPath path = ts::rounded_rectangle(0.0, 0.02);  // 18.3 m, turns of 1 m radius
  const auto odom = wheel_odometry(path.truth, 0.0, 0.0, 1, 0.0);
  for (const double k : {0.9, 1.0, 1.1}) {
    // The chain is k times too long when the configured height is k times the true one.
    const HeightCheck h = check(frames_of(scaled_chain(path.truth, k), odom), k * kAboveCamM);
    ASSERT_TRUE(h.estimated()) << to_string(h.status);
    EXPECT_NEAR(h.scale_ratio, k, 1e-9);
    EXPECT_NEAR(h.scale_ratio_spread, 0.0, 1e-9);
    EXPECT_NEAR(h.estimated_above_camera_m, kAboveCamM, 1e-9);
    EXPECT_NEAR(h.estimated_height_m, kCamHeightM + kAboveCamM, 1e-9);
    EXPECT_NEAR(h.relative_error(), 1.0 / k - 1.0, 1e-9);
    EXPECT_EQ(h.disagrees, k != 1.0) << k;
    // 18.3 m in 0.75 m windows: 24, none rejected; the turns' windows (1.57 m of arc each) have
    // chords of 0.73 m at least, none is skipped.
    EXPECT_EQ(h.windows, 24);
    EXPECT_EQ(h.windows_rejected, 0);
    EXPECT_EQ(h.windows_turning, 0);
    EXPECT_TRUE(h.validate().empty());
  }
}

// The mosaic builder under a height 10 % too high (every observed offset 1.1 times the true
// one, 3 mm of noise per landmark) and the simulator's odometry (1.5 % long, 1 % noise per step).
TEST(HeightCheck, AHeightTenPercentTooHighIsFoundThroughTheMosaicBuilder) {
  const ts::SyntheticCeiling ceiling = ts::make_synthetic_ceiling(3, -2.5, 90, -1.5, 70);
  const ts::SyntheticPath path = ts::rounded_rectangle(0.0, 0.02);
  const auto odom = wheel_odometry(path.truth, 0.015, 0.01, 5);
  for (const double k : {1.0, 1.1}) {
    std::mt19937 rng(11);
    std::normal_distribution<double> noise(0.0, 0.003);
    MosaicBuilderOptions bo;
    bo.loop.enabled = false;  // the scaled chain does not drift: nothing to close
    MosaicBuilder builder(bo);
    for (const PlanarPose& T : path.truth) {
      CeilingObservation o = ts::see_synthetic(ceiling, T, rng);
      for (cv::Point2d& p : o.p_base_m) {
        p = k * (p - kCamInBase) + kCamInBase + cv::Point2d(noise(rng), noise(rng));
      }
      builder.add_frame(o);
    }
    const HeightCheck h = check(height_check_frames(builder.frames(), odom), k * kAboveCamM);
    ASSERT_TRUE(h.estimated()) << to_string(h.status);
    // s = k / 1.015 (the odometry reads long): 0.985 k; the estimate is 1.015 times the true
    // height above the camera. Measured: see the printout; bound 1 % around that.
    std::printf(
        "k %.2f: s %.4f spread %.4f sigma %.4f, above camera %.3f m (true %.3f), "
        "windows %d rejected %d\n",
        k, h.scale_ratio, h.scale_ratio_spread, h.scale_ratio_sigma, h.estimated_above_camera_m,
        kAboveCamM, h.windows, h.windows_rejected);
    EXPECT_NEAR(h.scale_ratio, k / 1.015, 0.01 * k);
    EXPECT_NEAR(h.estimated_above_camera_m, 1.015 * kAboveCamM, 0.01 * kAboveCamM);
    EXPECT_GE(h.windows, 20);
    EXPECT_EQ(h.disagrees, k != 1.0) << k;
  }
}

// A loss (no pose for 30 frames), a re-localisation that jumps the chain, an unflagged jump of
// 0.4 m (over max_step_m: a break) and one of 8 cm (a window's outlier), an odometry reset.
TEST(HeightCheck, LossesJumpsAndResetsCostWindowsNotTheEstimate) {
  const auto truth = straight(12.0);  // 600 steps
  const auto odom_clean = wheel_odometry(truth, 0.0, 0.0, 1);
  const double k = 1.1;
  std::vector<HeightCheckFrame> f = frames_of(scaled_chain(truth, k), odom_clean);
  for (size_t i = 100; i < 130; ++i) f[i].T_mosaic_base.reset();  // lost
  f[200].jump = true;                                             // re-localised
  for (size_t i = 200; i < f.size(); ++i) f[i].T_mosaic_base->y_m += 0.05;
  for (size_t i = 300; i < f.size(); ++i) f[i].T_mosaic_base->x_m += 0.4;   // a jump, unflagged
  for (size_t i = 420; i < f.size(); ++i) f[i].T_mosaic_base->x_m += 0.08;  // small one
  for (size_t i = 500; i < f.size(); ++i) f[i].T_odom_base->x_m -= 5.0;     // odometry reset
  const HeightCheck h = check(f, k * kAboveCamM);
  ASSERT_TRUE(h.estimated()) << to_string(h.status);
  EXPECT_NEAR(h.scale_ratio, k, 1e-9);  // the 8 cm window (ratio ~1.2) rejected
  EXPECT_EQ(h.windows_rejected, 1);
  // Windows: 100 frames (2 m) then the loss: 2; 130-200: 1; 200-300: 2; 300-500: 5 (one
  // rejected); 500-600: 2. 12 ratios, 11 kept.
  EXPECT_EQ(h.windows, 11);
  EXPECT_TRUE(h.disagrees);

  // Without the rejection the 8 cm window would have moved the mean by 0.1 / 12 (0.8 %).
  HeightCheckOptions loose;
  loose.outlier_sigmas = 1e9;
  EXPECT_GT(check(f, k * kAboveCamM, loose).scale_ratio, k + 0.005);
}

TEST(HeightCheck, TurnsOnTheSpotGiveNoEstimate) {
  const auto truth = turns_on_the_spot(3.0);
  const auto odom = wheel_odometry(truth, 0.015, 0.01, 2);
  const HeightCheck h = check(frames_of(scaled_chain(truth, 1.1), odom), 1.1 * kAboveCamM);
  EXPECT_EQ(h.status, HeightCheckStatus::kTooFewWindows);
  EXPECT_EQ(h.windows, 0);
  EXPECT_FALSE(h.disagrees);
  EXPECT_EQ(h.scale_ratio, 0.0);
  EXPECT_TRUE(h.validate().empty());

  // Tight circles (radius 0.2 m): the base travels, the chords stay short: skipped as turning.
  std::vector<PlanarPose> circles;
  for (int i = 0; i <= 1000; ++i) {
    const double a = 0.1 * i;  // 2 cm per frame
    circles.push_back({0.2 * std::sin(a), 0.2 - 0.2 * std::cos(a), a});
  }
  const HeightCheck c =
      check(frames_of(scaled_chain(circles, 1.1), wheel_odometry(circles, 0.0, 0.0, 3)));
  EXPECT_EQ(c.status, HeightCheckStatus::kTooFewWindows);
  EXPECT_EQ(c.windows, 0);
  EXPECT_EQ(c.windows_turning, 26);  // 20 m of circles in 0.75 m windows (chords <= 0.4 m)
}

TEST(HeightCheck, ATooShortTourOrOneWithoutOdometryGivesNoEstimate) {
  const auto truth = straight(2.9);  // 3 windows, min_windows 4
  const auto odom = wheel_odometry(truth, 0.0, 0.0, 1);
  const HeightCheck h = check(frames_of(scaled_chain(truth, 1.1), odom), 1.1 * kAboveCamM);
  EXPECT_EQ(h.status, HeightCheckStatus::kTooFewWindows);
  EXPECT_EQ(h.windows, 3);
  HeightCheckOptions three;
  three.min_windows = 3;
  EXPECT_TRUE(
      check(frames_of(scaled_chain(truth, 1.1), odom), 1.1 * kAboveCamM, three).estimated());

  std::vector<HeightCheckFrame> no_odom = frames_of(scaled_chain(truth, 1.1), odom);
  for (auto& f : no_odom) f.T_odom_base.reset();
  EXPECT_EQ(check(no_odom).status, HeightCheckStatus::kNoOdometry);
  EXPECT_EQ(check({}).status, HeightCheckStatus::kNoOdometry);
  // Odometry on every other frame only: no step between two usable frames.
  std::vector<HeightCheckFrame> sparse = frames_of(scaled_chain(truth, 1.1), odom);
  for (size_t i = 0; i < sparse.size(); i += 2) sparse[i].T_odom_base.reset();
  EXPECT_EQ(check(sparse).status, HeightCheckStatus::kNoOdometry);
}

TEST(HeightCheck, TheBuildersFlagsBreakWindows) {
  std::vector<MosaicFrameResult> r(4);
  std::vector<std::optional<OdometryPose>> o(4, OdometryPose{1.0, 2.0, 0.5});
  r[1].localised = true;
  r[2].localised = true;
  r[2].relocalised = true;
  r[3].localised = true;
  r[3].closed_loop = true;
  o[1].reset();
  const auto f = height_check_frames(r, o);
  ASSERT_EQ(f.size(), 4u);
  EXPECT_FALSE(f[0].T_mosaic_base.has_value());
  EXPECT_TRUE(f[0].T_odom_base.has_value());
  EXPECT_NEAR(f[0].T_odom_base->theta_rad, 0.5, 0.0);
  EXPECT_FALSE(f[1].T_odom_base.has_value());
  EXPECT_FALSE(f[1].jump);
  EXPECT_TRUE(f[2].jump);
  EXPECT_TRUE(f[3].jump);
  EXPECT_THROW(height_check_frames(r, {}), std::invalid_argument);
}

TEST(HeightCheck, BadOptionsAndHeightsAreRefused) {
  const std::vector<HeightCheckFrame> none;
  auto refused = [&](HeightCheckOptions o, const std::string& field) {
    try {
      check(none, kAboveCamM, o);
      ADD_FAILURE() << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("height_check." + field), std::string::npos) << e.what();
    }
  };
  HeightCheckOptions o;
  o.window_m = 0.0;
  refused(o, "window_m");
  o = {};
  o.min_chord_m = 1.0;  // > window_m
  refused(o, "min_chord_m");
  o = {};
  o.max_step_m = -1.0;
  refused(o, "max_step_m");
  o = {};
  o.outlier_sigmas = 0.0;
  refused(o, "outlier_sigmas");
  o = {};
  o.min_windows = 1;
  refused(o, "min_windows");
  o = {};
  o.warn_relative = std::nan("");
  refused(o, "warn_relative");
  o = {};
  o.warn_sigmas = -1.0;
  refused(o, "warn_sigmas");
  EXPECT_THROW(check_ceiling_height(none, kCamInBase, 2.6, 0.0), std::invalid_argument);
  EXPECT_THROW(check_ceiling_height(none, kCamInBase, 1.0, 1.45), std::invalid_argument);
  EXPECT_EQ(height_check_status_from_string("too_few_windows"), HeightCheckStatus::kTooFewWindows);
  EXPECT_THROW(height_check_status_from_string("bogus"), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::ceiling
