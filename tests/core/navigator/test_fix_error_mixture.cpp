// FixErrorMixture: a segment's fixes are the room's (a small shared error) or a moved object's
// (a large one). Fixes near the odometry keep "room" and correct the estimate as a small shared
// error would; fixes that keep reading far from it make "moved" likely and hardly move it; a
// drifted estimate (large variance) is still corrected by the room's fixes.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "core/navigator/fix_error_mixture.hpp"

namespace pepper::core::navigator {
namespace {

FixErrorMixtureOptions options() {
  FixErrorMixtureOptions o;
  o.usual_sigma = {0.05, 0.01, 0.005};
  o.moved_sigma = {0.5, 0.3, 0.1};
  o.noise_sigma = {0.05, 0.01, 0.003};
  o.moved_prior = 0.1;
  return o;
}

// `n` fixes reading `offset` (robot axes) from the truth plus white noise, on an estimate that
// starts at the truth with sigmas `sigma`; returns the estimate's final error.
Axes3 follow(FixErrorMixture& m, const Axes3& sigma, const Axes3& offset, int n,
             unsigned seed = 1) {
  std::mt19937 rng(seed);
  const FixErrorMixtureOptions o = options();
  m.begin(o, {sigma[0] * sigma[0], sigma[1] * sigma[1], sigma[2] * sigma[2]});
  Axes3 est{0, 0, 0};
  for (int i = 0; i < n; ++i) {
    Axes3 y{};
    for (int a = 0; a < 3; ++a) {
      std::normal_distribution<double> noise(0.0, 0.5 * o.noise_sigma[a]);
      y[a] = offset[a] + noise(rng) - est[a];
    }
    const Axes3 d = m.update(y, 1.0);
    for (int a = 0; a < 3; ++a) est[a] += d[a];
  }
  return est;
}

TEST(FixErrorMixture, TheRoomsFixesCorrectADriftedEstimate) {
  // After a blind stretch the estimate is 12 cm and 0.05 rad off (sigmas 15 cm, 0.06 rad): the
  // room's fixes bring it back, and the segment stays "room".
  FixErrorMixture m;
  const Axes3 e = follow(m, {0.3, 0.15, 0.06}, {0.0, -0.12, -0.05}, 40);
  EXPECT_LT(std::abs(e[1] + 0.12), 0.02);
  EXPECT_LT(std::abs(e[2] + 0.05), 0.006);
  EXPECT_GT(m.usual_probability(), 0.9);
}

TEST(FixErrorMixture, AMovedObjectsFixesHardlyMoveAConfidentEstimate) {
  // A confident estimate (1.5 cm, 0.006 rad) and a segment whose fixes all read 12 cm and
  // 0.06 rad off (a moved, turned shelf): "moved" wins and the estimate stays near the truth.
  FixErrorMixture m;
  const Axes3 e = follow(m, {0.05, 0.015, 0.006}, {0.0, 0.12, 0.06}, 60);
  EXPECT_LT(m.usual_probability(), 0.01);
  EXPECT_LT(std::abs(e[1]), 0.02);
  EXPECT_LT(std::abs(e[2]), 0.01);
}

TEST(FixErrorMixture, ASmallSharedErrorIsTakenAsTheRooms) {
  // 1 cm off across, the size of the room's own model error: "room" stays likely and the
  // estimate moves part of the way, as one measurement with the room's sigma would.
  FixErrorMixture m;
  const Axes3 e = follow(m, {0.05, 0.015, 0.006}, {0.0, 0.01, 0.0}, 60);
  EXPECT_GT(m.usual_probability(), 0.5);
  EXPECT_GT(e[1], 0.004);
  EXPECT_LT(e[1], 0.01);
}

TEST(FixErrorMixture, FixesThatAgreeAfterAPlacementKeepTheRoom) {
  // A placed estimate (sigma 0.5 m, 0.1 rad) 3 cm and 0.01 rad off, and fixes that agree with
  // the truth: the first fix takes the estimate there and the following ones keep "room".
  // The collapsed first version of this filter made "moved" win here.
  FixErrorMixture m;
  const Axes3 e = follow(m, {0.5, 0.5, 0.1}, {0.0, 0.03, 0.01}, 40);
  EXPECT_GT(m.usual_probability(), 0.5);
  EXPECT_NEAR(e[1], 0.03, 0.01);
  EXPECT_NEAR(e[2], 0.01, 0.003);
  // Right after a placement, fixes cannot tell the room's error from a moved object's (the
  // estimate's own error is as large as either): the variance keeps the small chance of "moved"
  // until a new segment's fixes separate them, but it is far below the placement's.
  const Axes3 v = m.variance();
  EXPECT_LT(std::sqrt(v[1]), 0.1);
}

TEST(FixErrorMixture, ANewSegmentStartsFromThePrior) {
  FixErrorMixture m;
  follow(m, {0.05, 0.015, 0.006}, {0.0, 0.12, 0.06}, 30);
  ASSERT_LT(m.usual_probability(), 0.01);
  m.begin(options(), {0.0025, 0.0004, 0.0001});
  EXPECT_NEAR(m.usual_probability(), 0.9, 1e-12);
  const Axes3 expected = m.expected();
  EXPECT_EQ(expected[1], 0.0);
}

TEST(FixErrorMixture, TheGateIsTheRooms) {
  // The resection's prior is the room's expectation: a moved object's hypothesis must not widen
  // the gate it is to be kept out by.
  FixErrorMixture m;
  m.begin(options(), {0.0004, 0.0004, 0.0001});
  const Axes3 v = m.expected_var();
  const FixErrorMixtureOptions o = options();
  for (int a = 0; a < 3; ++a) {
    const double room = std::pow(o.usual_sigma[a], 2) + std::pow(o.noise_sigma[a], 2);
    EXPECT_NEAR(v[a], (a == 2 ? 0.0001 : 0.0004) + room, 1e-12);
  }
}

TEST(FixErrorMixture, VariancesStayPositiveAndFinite) {
  FixErrorMixture m;
  m.begin(options(), {1e-10, 1e-10, 1e-10});
  for (int i = 0; i < 200; ++i) {
    const double s = (i % 2) ? 1.0 : -1.0;
    m.update({s * 0.3, s * 0.2, s * 0.1}, i % 3 ? 1.0 : 1e-3);
    const Axes3 var = m.variance();
    for (int a = 0; a < 3; ++a) {
      ASSERT_TRUE(std::isfinite(var[a]));
      ASSERT_GT(var[a], 0.0);
    }
    m.rescale(i % 3, var[i % 3], 3.0 * var[i % 3]);
    m.grow(i % 3, 0.001);
    const Axes3 ev = m.expected_var();
    for (int a = 0; a < 3; ++a) ASSERT_GT(ev[a], 0.0);
  }
}

TEST(FixErrorMixture, ASourceOfOneAxisMovesOnlyThatAxis) {
  // The lines' heading measures the heading alone (NaN elsewhere): a moved shelf's lines, 0.12
  // rad turned, on a confident estimate make "moved" likely and leave the heading near the truth;
  // the unmeasured axes' estimate and variances are untouched.
  FixErrorMixture m;
  const Axes3 var{0.0025, 0.0004, 0.006 * 0.006};
  m.begin(options(), var);
  const double nan = std::nan("");
  double heading = 0.0;
  for (int i = 0; i < 30; ++i) {
    const Axes3 d = m.update({nan, nan, 0.12 - heading}, 1.0);
    EXPECT_EQ(d[0], 0.0);
    EXPECT_EQ(d[1], 0.0);
    heading += d[2];
  }
  EXPECT_LT(m.usual_probability(), 0.01);
  EXPECT_LT(std::abs(heading), 0.01);
  EXPECT_NEAR(m.variance()[0], var[0], 1e-15);
  EXPECT_NEAR(m.variance()[1], var[1], 1e-15);
  // A heading the room's lines agree with (2 mrad off) keeps "room" and is taken.
  m.begin(options(), var);
  heading = 0.0;
  for (int i = 0; i < 30; ++i) heading += m.update({nan, nan, 0.002 - heading}, 1.0)[2];
  EXPECT_GT(m.usual_probability(), 0.5);
  EXPECT_GT(heading, 0.0005);
  // Nothing measured: nothing moves, and the odds stay the prior's.
  m.begin(options(), var);
  const Axes3 d = m.update({nan, nan, nan}, 1.0);
  EXPECT_EQ(d[2], 0.0);
  EXPECT_NEAR(m.usual_probability(), 0.9, 1e-12);
}

TEST(FixErrorMixture, AnAxisNotModelledIsNaNAndRefusesMeasurements) {
  // The floor lines model the across axis alone: the other axes' sigmas are NaN.
  const double nan = std::nan("");
  FixErrorMixtureOptions o;
  o.usual_sigma = {nan, 0.04, nan};
  o.moved_sigma = {nan, 0.3, nan};
  o.noise_sigma = {nan, 0.01, nan};
  FixErrorMixture m;
  m.begin(o, {0.0, 0.0009, -1.0});  // the other axes' variances are not read
  EXPECT_FALSE(m.models(0));
  EXPECT_TRUE(m.models(1));
  const Axes3 d = m.update({nan, 0.01, nan}, 1.0);
  EXPECT_EQ(d[0], 0.0);
  EXPECT_GT(d[1], 0.0);
  EXPECT_EQ(d[2], 0.0);
  EXPECT_TRUE(std::isnan(m.variance()[0]));
  EXPECT_LT(m.variance()[1], 0.0009);
  EXPECT_TRUE(std::isnan(m.expected()[2]));
  EXPECT_TRUE(std::isnan(m.expected_var()[2]));
  EXPECT_THROW(m.update({0.01, 0.01, nan}, 1.0), std::invalid_argument);
  EXPECT_THROW(m.grow(0, 0.01), std::invalid_argument);
  EXPECT_THROW(m.rescale(2, 1.0, 0.5), std::invalid_argument);
  // Some but not all of an axis's sigmas NaN, or no axis modelled: refused.
  FixErrorMixtureOptions half = o;
  half.noise_sigma[0] = 0.01;
  EXPECT_THROW(m.begin(half, {1.0, 1.0, 1.0}), std::invalid_argument);
  FixErrorMixtureOptions none = o;
  none.usual_sigma[1] = none.moved_sigma[1] = none.noise_sigma[1] = nan;
  EXPECT_THROW(m.begin(none, {1.0, 1.0, 1.0}), std::invalid_argument);
}

TEST(FixErrorMixture, BadInputIsRefused) {
  FixErrorMixture m;
  const Axes3 var{0.01, 0.01, 0.01};
  FixErrorMixtureOptions o = options();
  o.moved_prior = 1.0;
  EXPECT_THROW(m.begin(o, var), std::invalid_argument);
  o = options();
  o.noise_sigma[2] = 0.0;
  EXPECT_THROW(m.begin(o, var), std::invalid_argument);
  o = options();
  o.usual_sigma[0] = -1.0;
  EXPECT_THROW(m.begin(o, var), std::invalid_argument);
  EXPECT_THROW(m.begin(options(), {0.01, 0.0, 0.01}), std::invalid_argument);
  m.begin(options(), var);
  EXPECT_THROW(m.update({0, 0, 0}, 0.0), std::invalid_argument);
  EXPECT_THROW(m.update({0, 0, 0}, 1.5), std::invalid_argument);
  EXPECT_THROW(m.update({0, HUGE_VAL, 0}, 1.0), std::invalid_argument);
  EXPECT_THROW(m.rescale(3, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(m.grow(0, -0.1), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::navigator
