// Metrics of the closed-loop evaluation against hand-computed cases (pepper_app/src/evaluation/
// metrics.hpp): projection and signed lateral deviation on a polyline, tracking along a loop,
// RMS, omega-rate RMS, percentiles, key images per metre, converged-part statistics.
#include "evaluation/metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace pepper::app::evaluation {
namespace {

constexpr double kTol = 1e-12;  // exact arithmetic on small numbers

// L-shaped path: 4 m east, then 3 m north (length 7 m).
Polyline l_path() { return Polyline({{0, 0}, {4, 0}, {4, 3}}); }

TEST(Polyline, ProjectsWithSignedLateralDeviation) {
  const Polyline p = l_path();
  EXPECT_NEAR(p.length_m(), 7.0, kTol);
  // Left of the eastward piece (north of it): +0.5 at s = 2.
  PathProjection a = p.project({2.0, 0.5});
  EXPECT_NEAR(a.s_m, 2.0, kTol);
  EXPECT_NEAR(a.lateral_m, 0.5, kTol);
  // Right of it (south): -0.3.
  EXPECT_NEAR(p.project({2.0, -0.3}).lateral_m, -0.3, kTol);
  // East of the northward piece is its right: foot (4, 1), s = 4 + 1, lateral -1.
  a = p.project({5.0, 1.0});
  EXPECT_NEAR(a.s_m, 5.0, kTol);
  EXPECT_NEAR(a.lateral_m, -1.0, kTol);
  EXPECT_NEAR(a.foot_m.x(), 4.0, kTol);
  // Inside the corner (3.8, 0.5): 0.2 from the second piece, 0.5 from the first -> second, left.
  a = p.project({3.8, 0.5});
  EXPECT_NEAR(a.lateral_m, 0.2, 1e-9);
  EXPECT_NEAR(a.s_m, 4.5, 1e-9);
  // Past the end (north of (4, 3)): the last piece is extended, lateral is perpendicular.
  a = p.project({4.2, 4.0});
  EXPECT_NEAR(a.s_m, 8.0, kTol);
  EXPECT_NEAR(a.lateral_m, -0.2, kTol);
  // Before the start: the first piece is extended backwards.
  a = p.project({-1.0, 0.1});
  EXPECT_NEAR(a.s_m, -1.0, kTol);
  EXPECT_NEAR(a.lateral_m, 0.1, kTol);
  // Point at arc length.
  EXPECT_NEAR(p.at(5.5).y(), 1.5, kTol);
  EXPECT_NEAR(p.at(-1.0).x(), 0.0, kTol);
}

TEST(Polyline, RejectsDegenerateInput) {
  EXPECT_THROW(Polyline({{1, 1}}), std::invalid_argument);
  EXPECT_THROW(Polyline({{1, 1}, {1, 1}}), std::invalid_argument);
}

TEST(PathTracker, FollowsALoopWithoutJumpingToItsEnd) {
  // A square loop whose end (0, 0.3) comes back near its start (0, 0).
  const Polyline loop({{0, 0}, {4, 0}, {4, 4}, {0, 4}, {0, 0.3}});
  // Whole-path projection of (0.05, 0.2) picks the end piece (x = 0, distance 0.05)...
  EXPECT_GT(loop.project({0.05, 0.2}).s_m, 10.0);
  // ...the tracker starts in the first half and picks the first piece (distance 0.2, s = 0.05).
  PathTracker t(loop, 0.5 * loop.length_m());
  PathProjection pr = t.update({0.05, 0.2});
  EXPECT_NEAR(pr.s_m, 0.05, kTol);
  EXPECT_NEAR(pr.lateral_m, 0.2, kTol);
  // Walk around: the tracker follows (windows of 0.5 m back, 1.5 m ahead).
  for (double s = 0.5; s < loop.length_m(); s += 0.5) pr = t.update(loop.at(s));
  EXPECT_GT(pr.s_m, 15.0);
}

TEST(Statistics, RmsMaxPercentile) {
  const std::vector<double> v{3.0, -4.0};
  EXPECT_NEAR(rms(v), std::sqrt(12.5), kTol);  // sqrt((9 + 16) / 2)
  EXPECT_NEAR(max_abs(v), 4.0, kTol);
  EXPECT_TRUE(std::isnan(rms(std::vector<double>{})));
  // 1..5: median 3; p95 at position 0.95 * 4 = 3.8 -> 4 + 0.8 * (5 - 4) = 4.8.
  EXPECT_NEAR(percentile({5, 1, 3, 2, 4}, 0.5), 3.0, kTol);
  EXPECT_NEAR(percentile({5, 1, 3, 2, 4}, 0.95), 4.8, kTol);
}

TEST(Statistics, OmegaRateRms) {
  // Omega 0, 0.1, 0.1, -0.1 rad/s at 10 Hz: rates 1, 0, -2 rad/s^2 -> sqrt(5 / 3).
  const std::vector<double> w{0.0, 0.1, 0.1, -0.1};
  const std::vector<double> t{0.0, 0.1, 0.2, 0.3};
  EXPECT_NEAR(rate_rms(w, t), std::sqrt(5.0 / 3.0), 1e-9);
  // A repeated stamp is skipped: rates 1, -2 -> sqrt(5 / 2).
  const std::vector<double> t2{0.0, 0.1, 0.1, 0.2};
  EXPECT_NEAR(rate_rms(w, t2), std::sqrt(2.5), 1e-9);
  EXPECT_TRUE(std::isnan(rate_rms(std::vector<double>{1.0}, std::vector<double>{0.0})));
}

TEST(Statistics, KeyImagesPerMetre) {
  EXPECT_NEAR(key_images_per_m(19, 9.5), 2.0, kTol);
  EXPECT_TRUE(std::isnan(key_images_per_m(3, 0.0)));
}

TEST(LateralStats, SinusoidAroundAStraightPathAfterTheSkippedStart) {
  // Path: the x axis. Replayed path: 0.3 m off for the first metre (converging), then a
  // sinusoid of amplitude 3 cm and period 1 m: RMS 3/sqrt(2) cm, max 3 cm once converged.
  const Polyline path({{0, 0}, {10, 0}});
  std::vector<double> travelled, lateral;
  for (int i = 0; i <= 8000; ++i) {
    const double x = i * 0.001;
    const double y = x < 1.0 ? 0.3 * (1.0 - x) : 0.03 * std::sin(2 * M_PI * (x - 1.0));
    travelled.push_back(x);
    lateral.push_back(path.project({x, y}).lateral_m);
  }
  const DeviationStats s = lateral_stats(travelled, lateral, 1.0);
  EXPECT_GE(s.samples, 7000);  // x = 1.000 .. 8.000 by 1 mm (the first may round either way)
  EXPECT_LE(s.samples, 7001);
  EXPECT_NEAR(s.rms_m, 0.03 / std::sqrt(2.0), 2e-5);  // 7 whole periods (+1 sample)
  EXPECT_NEAR(s.max_m, 0.03, 1e-6);
  // |y| first < 5 cm on the converging line 0.3 (1 - x) < 0.05 -> x > 0.8333.
  EXPECT_NEAR(s.first_under_5cm_m, 0.834, 1e-3);
  EXPECT_THROW(lateral_stats(travelled, std::vector<double>{1.0}, 0.0), std::invalid_argument);
}

TEST(LateralStats, ConvergedPartStartsOnceUnderTheThreshold) {
  // Distance rule (0.5 m) and threshold rule (5 cm): the kept samples are 0.04, 0.08, 0.02
  // (from 2 m): max 0.08, RMS sqrt((0.0016 + 0.0064 + 0.0004) / 3) = sqrt(0.0028).
  const std::vector<double> travelled{0, 1, 2, 3, 4};
  const std::vector<double> lateral{0.2, -0.1, 0.04, -0.08, 0.02};
  const DeviationStats s = lateral_stats(travelled, lateral, 0.5, 0.05);
  EXPECT_EQ(s.samples, 3);
  EXPECT_NEAR(s.converged_from_m, 2.0, kTol);
  EXPECT_NEAR(s.max_m, 0.08, kTol);
  EXPECT_NEAR(s.rms_m, std::sqrt(0.0028), 1e-12);
  // Distance rule alone: from 1 m, max 0.1.
  EXPECT_NEAR(lateral_stats(travelled, lateral, 0.5).max_m, 0.1, kTol);
  // Never under 1 cm: no converged part.
  const DeviationStats never = lateral_stats(travelled, lateral, 0.5, 0.01);
  EXPECT_EQ(never.samples, 0);
  EXPECT_LT(never.converged_from_m, 0.0);
  EXPECT_TRUE(std::isnan(never.rms_m));
}

}  // namespace
}  // namespace pepper::app::evaluation
