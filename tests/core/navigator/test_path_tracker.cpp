// TaughtPathTracker: odometry carried along the taught path (issue 29). Poses compose as SE(2);
// progress runs along straight pieces and through turns on the spot; the estimate moves with the
// replay's odometry whatever that odometry's origin; vision fixes pull it back.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <vector>

#include "core/navigator/path_tracker.hpp"

namespace pepper::core::navigator {
namespace {

using Poses = std::vector<std::optional<OdometryPose>>;

TEST(TaughtPathTracker, ComposeAndBetweenAreInverse) {
  const OdometryPose a{1.0, -2.0, 0.7}, b{0.3, 0.4, -1.2};
  const OdometryPose ab = compose(a, b);
  const OdometryPose back = between(a, ab);
  EXPECT_NEAR(back.x_m, b.x_m, 1e-12);
  EXPECT_NEAR(back.y_m, b.y_m, 1e-12);
  EXPECT_NEAR(back.yaw_rad, b.yaw_rad, 1e-12);
  // A quarter turn left, then 1 m forward: 1 m along +y.
  const OdometryPose q = compose({0, 0, M_PI / 2}, {1, 0, 0});
  EXPECT_NEAR(q.x_m, 0.0, 1e-12);
  EXPECT_NEAR(q.y_m, 1.0, 1e-12);
}

TEST(TaughtPathTracker, UnusableWithoutEveryPose) {
  EXPECT_FALSE(TaughtPathTracker(Poses{OdometryPose{}}).usable());
  EXPECT_FALSE(TaughtPathTracker(Poses{OdometryPose{}, std::nullopt, OdometryPose{1, 0, 0}})
                   .usable());
  EXPECT_TRUE(TaughtPathTracker(Poses{OdometryPose{}, OdometryPose{1, 0, 0}}).usable());
  TaughtPathTracker t(Poses{OdometryPose{}, std::nullopt});
  EXPECT_FALSE(t.deviation().has_value());
}

// A teach that stood still keeps key images at one pose: the deviation is finite, its direction
// the taught heading (the e2e teach over the mock NAOqi server teaches such a tour; a NaN
// deviation reached the VNHV law there and ended the replay in an error).
TEST(TaughtPathTracker, KeyImagesAtOnePoseGiveAFiniteDeviation) {
  TaughtPathTracker t(Poses{OdometryPose{2.0, 1.0, M_PI / 2}, OdometryPose{2.0, 1.0, M_PI / 2}});
  ASSERT_TRUE(t.usable());
  t.set({1.9, 1.3, M_PI / 2 + 0.1}, OdometryPose{}, 0);  // 0.1 m left of the heading's line
  const auto d = t.deviation();
  ASSERT_TRUE(d.has_value());
  EXPECT_NEAR(d->lateral_m, 0.1, 1e-12);  // facing +y: x = 1.9 is left of x = 2
  EXPECT_NEAR(d->heading_rad, 0.1, 1e-12);
  EXPECT_EQ(d->curvature_1_m, 0.0);
  EXPECT_FALSE(d->in_place);
}

// Taught: 1 m along +x, a quarter turn left on the spot, 1 m along +y.
Poses l_path() {
  return {OdometryPose{0, 0, 0}, OdometryPose{1, 0, 0}, OdometryPose{1, 0, M_PI / 2},
          OdometryPose{1, 1, M_PI / 2}};
}

TEST(TaughtPathTracker, ReplayOdometryMovesTheEstimateWhateverItsOrigin) {
  TaughtPathTracker t(l_path());
  // The replay's odometry starts elsewhere and rotated: only its increments matter.
  const OdometryPose origin{5.0, 3.0, 2.0};
  t.set({0.0, 0.02, 0.0}, origin, 0);  // 2 cm left of the path at its start
  t.predict(compose(origin, {0.5, 0.0, 0.0}));
  auto d = t.deviation();
  ASSERT_TRUE(d);
  EXPECT_EQ(d->piece, 0);
  EXPECT_NEAR(d->progress, 0.5, 1e-9);
  EXPECT_NEAR(d->lateral_m, 0.02, 1e-9);
  EXPECT_NEAR(d->heading_rad, 0.0, 1e-9);
  EXPECT_FALSE(d->in_place);
  // Past the first piece's end: the turn on the spot, half done.
  t.predict(compose(origin, {1.0, 0.0, M_PI / 4}));
  d = t.deviation();
  ASSERT_TRUE(d);
  EXPECT_EQ(d->piece, 1);
  EXPECT_TRUE(d->in_place);
  EXPECT_NEAR(d->progress, 1.5, 1e-6);
  EXPECT_NEAR(d->remaining_turn_rad, M_PI / 4, 1e-9);
  // Turned (the estimate is then at (1.0, 0.01)), then 0.4 m up the last piece and 3 cm right
  // of it: (1.03, 0.41) in the taught frame, 2 cm further along in the replay's.
  t.predict(compose(origin, {1.0, -0.01, M_PI / 2}));
  t.predict(compose(origin, {1.03, 0.39, M_PI / 2 + 0.1}));
  d = t.deviation();
  ASSERT_TRUE(d);
  EXPECT_EQ(d->piece, 2);
  EXPECT_NEAR(d->lateral_m, -0.03, 1e-9);
  EXPECT_NEAR(d->heading_rad, 0.1, 1e-9);
  EXPECT_GT(d->progress, 2.3);
  EXPECT_LT(d->progress, 2.5);
}

TEST(TaughtPathTracker, ProgressNeverGoesBackNorBeyondTheEnd) {
  TaughtPathTracker t(l_path());
  t.set({1.0, 0.5, M_PI / 2}, {}, 2);
  ASSERT_EQ(t.deviation()->piece, 2);
  // Odometry says the robot went back to the start: the piece stays.
  t.predict({-1.5, 0.0, 0.0});
  EXPECT_EQ(t.deviation()->piece, 2);
  EXPECT_GE(t.deviation()->progress, 2.0);
  // Far beyond the final key image: progress is the final index.
  TaughtPathTracker u(l_path());
  u.set({1.0, 3.0, M_PI / 2}, {}, 2);
  EXPECT_DOUBLE_EQ(u.deviation()->progress, 3.0);
  // A switch moves the progress forward, never back.
  TaughtPathTracker v(l_path());
  v.set({0.1, 0.0, 0.0}, {}, 0);
  v.advance_to(2);
  EXPECT_EQ(v.deviation()->piece, 2);
  v.advance_to(0);
  EXPECT_EQ(v.deviation()->piece, 2);
}

TEST(TaughtPathTracker, VisionFixIsTakenAndTheCorrectionReported) {
  TaughtPathTracker t(l_path());
  t.set({0.5, 0.10, 0.05}, {}, 0);
  const auto [dist_m, yaw_rad] = t.correct({0.5, 0.0, 0.0});
  EXPECT_NEAR(dist_m, 0.10, 1e-12);
  EXPECT_NEAR(yaw_rad, 0.05, 1e-12);
  EXPECT_NEAR(t.estimate()->y_m, 0.0, 1e-12);
  EXPECT_NEAR(t.estimate()->yaw_rad, 0.0, 1e-12);
  // Without an estimate, a fix sets it.
  TaughtPathTracker u(l_path());
  EXPECT_EQ(u.correct({0.2, 0.0, 0.0}).first, 0.0);
  ASSERT_TRUE(u.estimate());
  EXPECT_DOUBLE_EQ(u.estimate()->x_m, 0.2);
}

TEST(TaughtPathTracker, AShiftOfTheHeadingTurnsOnlyTheHeadingAcrossTheWrap) {
  TaughtPathTracker t(l_path());
  t.set({0.5, 0.10, 3.10}, {}, 0);
  // 0.083 rad counter-clockwise of 3.10 is -3.10 across +-pi.
  t.shift({0.0, 0.0, 2.0 * M_PI - 6.20});
  EXPECT_NEAR(t.estimate()->yaw_rad, -3.10, 1e-12);
  EXPECT_DOUBLE_EQ(t.estimate()->x_m, 0.5);
  EXPECT_DOUBLE_EQ(t.estimate()->y_m, 0.10);
  // Without an estimate nothing happens.
  TaughtPathTracker u(l_path());
  u.shift({0.0, 0.0, 1.0});
  EXPECT_FALSE(u.estimate());
}

TEST(TaughtPathTracker, CurvatureOfAnArcPiece) {
  // A piece of a left arc: 0.3 m chord, heading +0.3 rad across it.
  TaughtPathTracker t(Poses{OdometryPose{0, 0, 0}, OdometryPose{0.3, 0.045, 0.3}});
  t.set({0.15, 0.0, 0.15}, {}, 0);
  const auto d = t.deviation();
  ASSERT_TRUE(d);
  EXPECT_NEAR(d->curvature_1_m, 0.3 / std::hypot(0.3, 0.045), 1e-9);
  EXPECT_NEAR(d->heading_rad, 0.0, 0.01);  // the taught heading half-way through the turn
}

}  // namespace
}  // namespace pepper::core::navigator

namespace pepper::core::navigator {
namespace {

// Key images a few centimetres apart on a 0.9 m arc (a feature-poor curve, as taught in a
// generated room): each piece is a chord, not a turn on the spot, and a robot that turned on
// the spot ahead of the path, or drifted, does not skip along it.
TEST(TaughtPathTracker, DenseArcChordsAreNotSkippedByHeadingOrDrift) {
  constexpr double kRadiusM = 0.9, kChordM = 0.025;
  Poses arc;
  for (int i = 0; i <= 60; ++i) {
    const double phi = i * kChordM / kRadiusM;
    arc.push_back(OdometryPose{kRadiusM * std::sin(phi), kRadiusM * (1 - std::cos(phi)), phi});
  }
  TaughtPathTracker t(arc);
  const OdometryPose start{0.0, 0.0, 0.0};
  t.set(*arc[0], start, 0);
  ASSERT_TRUE(t.deviation().has_value());
  // The robot turns 0.4 rad on the spot (the heading of key image 14): it has not moved along.
  t.predict({0.0, 0.0, 0.4});
  const auto turned = t.deviation();
  ASSERT_TRUE(turned.has_value());
  EXPECT_FALSE(turned->in_place);
  EXPECT_LT(turned->progress, 1.0 + TaughtPathTracker::kAdvanceSlackM / kChordM);
  // Odometry then moves the estimate 0.3 m straight ahead of it (drift, a cut corner): the
  // progress runs at most that far along the arc, plus the slack.
  t.predict(compose({0.0, 0.0, 0.4}, {0.3, 0.0, 0.0}));
  const auto ahead = t.deviation();
  ASSERT_TRUE(ahead.has_value());
  EXPECT_LE(ahead->progress, turned->progress + (0.3 + TaughtPathTracker::kAdvanceSlackM) / kChordM + 1);
  EXPECT_GT(ahead->progress, turned->progress);
}

}  // namespace
}  // namespace pepper::core::navigator
