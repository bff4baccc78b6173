// The VNHV deviation filter (core/control/deviation_filter.hpp): unicycle prediction from the
// commands, noise reduction on a simulated drive, outlier gating with restart, staleness.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/control/deviation_filter.hpp"

namespace pepper::core::control {
namespace {

constexpr int64_t kFrameNs = 66'666'667;  // 15 Hz

TEST(DeviationFilter, NoEstimateBeforeTheFirstMeasurement) {
  DeviationFilter f;
  EXPECT_FALSE(f.estimate(0));
  f.predict(0.15, 0.1, kFrameNs);  // nothing to predict yet
  EXPECT_FALSE(f.estimate(kFrameNs));
  EXPECT_EQ(f.correct({0.1, -0.2}, kFrameNs), DeviationFilter::Correction::kStarted);
  const auto e = f.estimate(kFrameNs);
  ASSERT_TRUE(e);
  EXPECT_DOUBLE_EQ(e->lateral_m, 0.1);
  EXPECT_DOUBLE_EQ(e->heading_rad, -0.2);
}

TEST(DeviationFilter, PredictionIntegratesTheUnicycle) {
  DeviationFilter f;
  f.correct({0.1, 0.2}, 0);
  // Straight at 0.2 m/s for 14 frames (within max_prediction_s): y grows by 0.2 sin(0.2) t.
  int64_t t = 0;
  for (int i = 0; i < 14; ++i) f.predict(0.2, 0.0, t += kFrameNs);
  auto e = f.estimate(t);
  ASSERT_TRUE(e);
  EXPECT_NEAR(e->lateral_m, 0.1 + 0.2 * std::sin(0.2) * 14 * kFrameNs * 1e-9, 1e-12);
  EXPECT_NEAR(e->heading_rad, 0.2, 1e-15);
  // Turning at -0.4 rad/s for 0.5 s: on the arc y(t) = y0 + (v / w) (cos(th0) - cos(th0 + w t)).
  DeviationFilter g;
  g.correct({0.0, 0.2}, 0);
  t = 0;
  for (int i = 0; i < 500; ++i) g.predict(0.2, -0.4, t += 1'000'000);
  e = g.estimate(t);
  ASSERT_TRUE(e);
  EXPECT_NEAR(e->heading_rad, 0.0, 1e-12);
  EXPECT_NEAR(e->lateral_m, 0.2 / -0.4 * (std::cos(0.2) - std::cos(0.0)), 1e-9);
}

TEST(DeviationFilter, PredictionAlongACurvedPath) {
  // Following a left arc of curvature 0.5 /m exactly (omega = kappa v): no change relative to it.
  DeviationFilter f;
  f.correct({0.0, 0.0}, 0);
  int64_t t = 0;
  for (int i = 0; i < 10; ++i) f.predict(0.2, 0.1, t += kFrameNs, 0.5);
  auto e = f.estimate(t);
  ASSERT_TRUE(e);
  EXPECT_NEAR(e->lateral_m, 0.0, 1e-12);
  EXPECT_NEAR(e->heading_rad, 0.0, 1e-12);
  // Driving straight while the path turns left: the heading relative to it falls at kappa v
  // (first step exact: theta = 0, y = 0).
  DeviationFilter g;
  g.correct({0.0, 0.0}, 0);
  g.predict(0.2, 0.0, kFrameNs, 0.5);
  e = g.estimate(kFrameNs);
  ASSERT_TRUE(e);
  EXPECT_NEAR(e->heading_rad, -0.1 * kFrameNs * 1e-9, 1e-12);
  EXPECT_LT(e->lateral_m, 0.0);  // drifting outside (right of) the left turn
  EXPECT_THROW(g.predict(0.2, 0.0, 2 * kFrameNs, std::nan("")), std::invalid_argument);
}

// A robot drives with a known command sequence; the measurements are the truth plus noise of
// the filter's assumed sigma. The filtered estimate must be closer to the truth than they are.
TEST(DeviationFilter, ReducesMeasurementNoiseOnASimulatedDrive) {
  DeviationFilterOptions o;
  DeviationFilter f(o);
  std::mt19937 rng(3);
  std::normal_distribution<double> ny(0.0, o.measurement_sigma_m), nt(0.0, o.measurement_sigma_rad);
  double y = 0.2, th = -0.1;
  double raw_sq = 0.0, filt_sq = 0.0, raw_th_sq = 0.0, filt_th_sq = 0.0;
  int n = 0;
  for (int i = 0; i < 150; ++i) {
    const int64_t t = i * kFrameNs;
    const double v = 0.15, w = -0.6 * y - 0.5 * th;  // some stabilising command
    if (i > 0) f.predict(v, w, t);
    const SegmentDeviation z{y + ny(rng), th + nt(rng)};
    f.correct(z, t);
    if (i >= 15) {  // after the start-up
      const auto e = f.estimate(t);
      ASSERT_TRUE(e);
      raw_sq += (z.lateral_m - y) * (z.lateral_m - y);
      filt_sq += (e->lateral_m - y) * (e->lateral_m - y);
      raw_th_sq += (z.heading_rad - th) * (z.heading_rad - th);
      filt_th_sq += (e->heading_rad - th) * (e->heading_rad - th);
      ++n;
    }
    const double dt = kFrameNs * 1e-9;  // truth: the same unicycle
    y += v * std::sin(th + 0.5 * w * dt) * dt;
    th += w * dt;
  }
  EXPECT_LT(std::sqrt(filt_sq / n), 0.5 * std::sqrt(raw_sq / n));
  EXPECT_LT(std::sqrt(filt_th_sq / n), 0.5 * std::sqrt(raw_th_sq / n));
}

TEST(DeviationFilter, GatesOutliersAndRestartsWhenTheyPersist) {
  DeviationFilterOptions o;
  o.max_rejections = 3;
  DeviationFilter f(o);
  int64_t t = 0;
  f.correct({0.05, 0.0}, t);
  for (int i = 0; i < 10; ++i) {
    f.predict(0.15, 0.0, t += kFrameNs);
    EXPECT_EQ(f.correct({0.05, 0.0}, t), DeviationFilter::Correction::kAccepted);
  }
  // A heading jump of 1 rad (the two-view failure this filter exists for): rejected, twice.
  for (int i = 0; i < 2; ++i) {
    f.predict(0.15, 0.0, t += kFrameNs);
    EXPECT_EQ(f.correct({0.05, 1.0}, t), DeviationFilter::Correction::kRejected);
    const auto e = f.estimate(t);
    ASSERT_TRUE(e);
    EXPECT_NEAR(e->heading_rad, 0.0, 1e-12);
  }
  // A good measurement in between resets the count...
  f.predict(0.15, 0.0, t += kFrameNs);
  EXPECT_EQ(f.correct({0.05, 0.0}, t), DeviationFilter::Correction::kAccepted);
  // ... so it takes three consecutive ones to restart on the measurement.
  for (int i = 0; i < 3; ++i) {
    f.predict(0.15, 0.0, t += kFrameNs);
    const auto c = f.correct({0.5, 0.0}, t);
    EXPECT_EQ(c, i < 2 ? DeviationFilter::Correction::kRejected
                       : DeviationFilter::Correction::kRestarted);
  }
  const auto e = f.estimate(t);
  ASSERT_TRUE(e);
  EXPECT_DOUBLE_EQ(e->lateral_m, 0.5);
}

TEST(DeviationFilter, PredictionAloneExpires) {
  DeviationFilterOptions o;
  o.max_prediction_s = 0.5;
  DeviationFilter f(o);
  f.correct({0.0, 0.0}, 0);
  f.predict(0.15, 0.0, 500'000'000);
  EXPECT_TRUE(f.estimate(500'000'000));
  f.predict(0.15, 0.0, 500'000'001);
  EXPECT_FALSE(f.estimate(500'000'001));
  f.reset();
  EXPECT_FALSE(f.estimate(500'000'001));
}

// A weighted measurement counts as one with its variance divided by the weight: a quarter-weight
// fix moves the estimate less than a full one, and one that starts the filter leaves it uncertain
// enough that the next full-weight measurement takes over most of the way.
TEST(DeviationFilter, AWeightScalesTheMeasurementNoise) {
  auto after = [](double weight) {
    DeviationFilter f;
    f.correct({0.0, 0.0}, 0);
    f.predict(0.0, 0.0, kFrameNs);
    f.correct({0.1, 0.0}, kFrameNs, weight);
    return f.estimate(kFrameNs)->lateral_m;
  };
  const double full = after(1.0), quarter = after(0.25);
  EXPECT_GT(full, 0.04);  // equal variances: about halfway
  EXPECT_LT(full, 0.06);
  EXPECT_GT(quarter, 0.005);
  EXPECT_LT(quarter, 0.5 * full);

  DeviationFilter g;
  g.correct({0.2, 0.0}, 0, 0.05);  // started by a doubtful fix
  g.predict(0.0, 0.0, kFrameNs);
  g.correct({0.0, 0.0}, kFrameNs);
  EXPECT_LT(std::abs(g.estimate(kFrameNs)->lateral_m), 0.02);

  DeviationFilter h;
  EXPECT_THROW(h.correct({0.0, 0.0}, 0, 0.0), std::invalid_argument);
  EXPECT_THROW(h.correct({0.0, 0.0}, 0, 1.5), std::invalid_argument);
}

TEST(DeviationFilter, ContractViolationsThrow) {
  DeviationFilterOptions bad;
  bad.measurement_sigma_m = 0.0;
  EXPECT_THROW(DeviationFilter{bad}, std::invalid_argument);
  DeviationFilter f;
  f.correct({0.0, 0.0}, 1000);
  EXPECT_THROW(f.predict(0.1, 0.0, 999), std::invalid_argument);
  EXPECT_THROW(f.correct({0.0, 0.0}, 2000), std::invalid_argument);  // not predicted to 2000
  EXPECT_THROW(f.predict(std::nan(""), 0.0, 2000), std::invalid_argument);
  EXPECT_THROW(f.correct({std::nan(""), 0.0}, 1000), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::control
