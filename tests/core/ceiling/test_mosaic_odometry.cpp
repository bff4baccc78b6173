// MosaicBuilder with the robot's odometry as the motion prior (issue 24; docs/method/ceiling.md,
// "The odometry as the motion prior"), on synthetic teaches: a ceiling that repeats itself every
// 0.6 m (one tile's points and descriptors copied over the whole hall, like a plain tile grid),
// a turn at the end of a corridor where the camera sees no ceiling, and odometry that drifts by
// 2 % of each step's translation and rotation.
// The figures are printed: build/tests/core_tests --gtest_filter='MosaicOdometry*'
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <random>
#include <vector>

#include "core/ceiling/mosaic_builder.hpp"
#include "synthetic_ceiling.hpp"

namespace pepper::core::ceiling {
namespace {

using test_support::SyntheticCeiling;

constexpr double kStepM = 0.02;  // between frames: 0.3 m/s at 15 Hz
constexpr int kJunk = 10;        // junk landmarks in every frame
constexpr double kTileM = 0.6;

// One 0.6 m tile of 6 x 6 jittered points with random descriptors, repeated over x in
// [-1.2, 6], y in [-1.8, 1.8]: every point has copies 0.6 m away along both axes, with the same
// descriptor and the same jitter. Only the odometry tells two periods apart.
SyntheticCeiling tiled_ceiling(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.015, 0.015);
  std::vector<cv::Point2d> tile;
  std::vector<cv::Mat> tile_descriptors;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      tile.emplace_back(0.1 * i + u(rng), 0.1 * j + u(rng));
      tile_descriptors.push_back(test_support::random_descriptor(rng));
    }
  SyntheticCeiling c;
  std::vector<cv::Mat> rows;
  for (int ti = -2; ti < 10; ++ti)
    for (int tj = -3; tj < 3; ++tj)
      for (size_t k = 0; k < tile.size(); ++k) {
        c.points_world.emplace_back(ti * kTileM + tile[k].x, tj * kTileM + tile[k].y);
        rows.push_back(tile_descriptors[k]);
      }
  cv::vconcat(rows, c.descriptors);
  return c;
}

using Leg = test_support::SyntheticLeg;
using Tour = test_support::SyntheticLegTour;

Tour drive(const std::vector<Leg>& legs) { return test_support::drive_legs({0.0, 0.0, 0.0}, legs); }

// Down a corridor 3 m, a U-turn on the spot (left, 40 frames) and 0.2 m on without seeing the
// ceiling, then 1.6 m back under the ceiling mapped on the way out.
Tour u_turn() {
  const double turn = M_PI / 40.0;
  return drive({{{kStepM, 0.0, 0.0}, 150, false},
                {{0.0, 0.0, turn}, 40, true},
                {{kStepM, 0.0, 0.0}, 10, true},
                {{kStepM, 0.0, 0.0}, 80, false}});
}

std::vector<MosaicFrameResult> teach(const SyntheticCeiling& c, const Tour& tour,
                                     const MosaicBuilderOptions& options, bool with_odometry) {
  std::mt19937 rng(3);
  MosaicBuilder builder(options);
  for (size_t k = 0; k < tour.truth.size(); ++k) {
    const CeilingObservation o =
        test_support::see_synthetic(c, tour.truth[k], rng, kJunk, tour.blind[k] != 0);
    builder.add_frame(o, with_odometry ? std::optional<OdometryPose>(tour.odom[k]) : std::nullopt);
  }
  return builder.frames();
}

double pose_error_m(const Tour& tour, const std::vector<MosaicFrameResult>& frames, size_t k) {
  const PlanarPose truth = tour.truth[0].inverse() * tour.truth[k];
  return std::hypot(frames[k].T_mosaic_base.x_m - truth.x_m,
                    frames[k].T_mosaic_base.y_m - truth.y_m);
}

size_t first_seeing_after_blind(const Tour& t) {
  size_t k = 0;
  while (k < t.blind.size() && !t.blind[k]) ++k;
  while (k < t.blind.size() && t.blind[k]) ++k;
  return k;
}

// The premise: without odometry the frames seen again after the U-turn are posed a whole
// period (or more) off, or not at all for a while; with it every one of them is posed where
// the robot is (exact observations: the fit is exact, the odometry only chose the period).
TEST(MosaicOdometry, AfterABlindUTurnUnderRepeatedTilesTheOdometryPicksTheRightTile) {
  const SyntheticCeiling c = tiled_ceiling(31);
  const Tour tour = u_turn();
  const size_t back = first_seeing_after_blind(tour);
  const auto with = teach(c, tour, {}, true);
  const auto without = teach(c, tour, {}, false);
  int without_right = 0;
  for (size_t k = back; k < tour.truth.size(); ++k)
    if (without[k].localised && pose_error_m(tour, without, k) < 0.01) ++without_right;
  std::printf("[ odom ] after the U-turn (%zu frames): posed within 1 cm, without odometry %d\n",
              tour.truth.size() - back, without_right);
  EXPECT_LT(without_right, static_cast<int>(tour.truth.size() - back) / 2);
  for (size_t k = back; k < tour.truth.size(); ++k) {
    ASSERT_TRUE(with[k].localised) << k;
    EXPECT_LT(pose_error_m(tour, with, k), 1e-6) << k;
    EXPECT_FALSE(with[k].relocalised) << k;  // the guided matching from the prediction posed it
    EXPECT_FALSE(with[k].odometry_posed) << k;
  }
  // Before the loss both are the same chain.
  for (size_t k = 0; k < 150; ++k) {
    ASSERT_TRUE(with[k].localised && without[k].localised) << k;
    EXPECT_EQ(with[k].T_mosaic_base.x_m, without[k].T_mosaic_base.x_m) << k;
  }
}

// A corridor's end: 3 m along x, a left turn of 90 degrees on the spot and 0.4 m on with a wall
// filling the view, then 2 m along y under ceiling the teach never saw (y from 0.7 m; the way
// out saw |y| <= 0.6 m).
// Without odometry nothing after the turn matches the mosaic: the rest of the teach has no pose.
// With it the first frame after the turn is posed by the odometry, its landmarks become
// candidates there and the frames after it chain on them: every frame is posed, off by no more
// than what the odometry drifted across the turn, and the chain after it is exact relative to
// its first frame.
TEST(MosaicOdometry, ATurnOntoUnmappedCeilingIsChainedThroughTheOdometry) {
  const SyntheticCeiling c = test_support::make_synthetic_ceiling(8, -1.0, 60, -1.5, 50);
  const double turn = 0.5 * M_PI / 30.0;
  const Tour tour = drive({{{kStepM, 0.0, 0.0}, 150, false},
                           {{0.0, 0.0, turn}, 30, true},
                           {{kStepM, 0.0, 0.0}, 20, true},
                           {{kStepM, 0.0, 0.0}, 100, false}});
  const size_t back = first_seeing_after_blind(tour);
  const auto with = teach(c, tour, {}, true);
  const auto without = teach(c, tour, {}, false);
  int without_posed = 0;
  for (size_t k = back; k < tour.truth.size(); ++k) without_posed += without[k].localised ? 1 : 0;
  EXPECT_EQ(without_posed, 0);  // the premise
  // The frames after the turn are posed by the odometry until one has moved landmark_step_m
  // (0.1 m, 5 frames) from the last creation and puts its landmarks in as candidates; the next
  // frame fits on them.
  size_t first_fit = back;
  while (first_fit < tour.truth.size() && with[first_fit].odometry_posed) {
    ASSERT_TRUE(with[first_fit].localised) << first_fit;
    ++first_fit;
  }
  ASSERT_LE(first_fit, back + 6);
  const size_t ref = first_fit - 1;  // the odometry-posed frame whose landmarks were chained on
  ASSERT_GT(with[ref].added, 50);
  // The odometry's own error across the turn: 2 % of 90 degrees.
  const double turn_error_rad = 0.02 * 0.5 * M_PI;
  const PlanarPose T0 = tour.truth[0].inverse();
  double worst_m = 0.0;
  for (size_t k = first_fit; k < tour.truth.size(); ++k) {
    ASSERT_TRUE(with[k].localised && !with[k].odometry_posed) << k;
    worst_m = std::max(worst_m, pose_error_m(tour, with, k));
    const PlanarPose truth = T0 * tour.truth[k];
    EXPECT_LT(std::abs(wrap_angle_rad(with[k].T_mosaic_base.theta_rad - truth.theta_rad)),
              turn_error_rad + 1e-3)
        << k;
    // Relative to the frame that placed the new landmarks, the chain is exact.
    const PlanarPose rel_est = with[ref].T_mosaic_base.inverse() * with[k].T_mosaic_base;
    const PlanarPose rel_true = tour.truth[ref].inverse() * tour.truth[k];
    EXPECT_NEAR(rel_est.x_m, rel_true.x_m, 1e-6) << k;
    EXPECT_NEAR(rel_est.y_m, rel_true.y_m, 1e-6) << k;
  }
  std::printf("[ odom ] turn onto unmapped ceiling: %zu frames seeing after it, the first %zu "
              "posed by the odometry, worst position error %.1f mm\n",
              tour.truth.size() - back, first_fit - back, 1e3 * worst_m);
  // 2.5 m at the turn's heading error, plus 2 % of the 0.5 m driven on the odometry.
  EXPECT_LT(worst_m, 2.5 * turn_error_rad + 0.02 * 0.5 + 0.005);
}

// A frame that sees nothing at all (the whole view a wall) is posed by the odometry too, so the
// chain is not cut there (a cut is a break of the relay chain, which the replay never drives);
// without odometry it is lost.
TEST(MosaicOdometry, AFrameThatSeesNothingIsPosedByTheOdometry) {
  const SyntheticCeiling c = test_support::make_synthetic_ceiling(9, -1.0, 40, -1.5, 30);
  std::mt19937 rng(2);
  MosaicBuilder with, without;
  for (int k = 0; k < 20; ++k) {
    const PlanarPose truth{kStepM * k, 0.0, 0.0};
    const CeilingObservation o = test_support::see_synthetic(c, truth, rng);
    with.add_frame(o, OdometryPose{truth.x_m, 0.0, 0.0});
    without.add_frame(o);
  }
  const MosaicFrameResult a = with.add_frame(CeilingObservation{}, OdometryPose{0.4, 0.0, 0.0});
  EXPECT_TRUE(a.localised && a.odometry_posed);
  EXPECT_NEAR(a.T_mosaic_base.x_m, 0.4, 1e-9);
  EXPECT_EQ(a.added, 0);
  EXPECT_FALSE(without.add_frame(CeilingObservation{}).localised);
}

// Readings given but the prior switched off: the build is the one without readings.
TEST(MosaicOdometry, SwitchedOffItBuildsAsWithoutReadings) {
  const SyntheticCeiling c = tiled_ceiling(32);
  const Tour tour = u_turn();
  MosaicBuilderOptions off;
  off.odometry_prior = false;
  const auto a = teach(c, tour, off, true);
  const auto b = teach(c, tour, {}, false);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].localised, b[k].localised) << k;
    EXPECT_EQ(a[k].T_mosaic_base.x_m, b[k].T_mosaic_base.x_m) << k;
    EXPECT_EQ(a[k].T_mosaic_base.y_m, b[k].T_mosaic_base.y_m) << k;
    EXPECT_EQ(a[k].inliers, b[k].inliers) << k;
  }
}

}  // namespace
}  // namespace pepper::core::ceiling
