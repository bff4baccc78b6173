// SharedFixError: the fixes of one segment share one error, so together they move the estimate
// about as far as one measurement with that error's sigma, whatever their number; a drifted
// estimate (large variance) is still corrected; a new segment brings new evidence.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "core/navigator/shared_fix_error.hpp"

namespace pepper::core::navigator {
namespace {

constexpr double kSigmaB = 0.03;  // the shared error's sigma, a priori (m)
constexpr double kNoise = 0.01;   // a fix's own white noise (m)

// `n` fixes that all read `offset` away from the truth, on an estimate that starts at the truth
// with sigma `sigma_est`; returns the estimate's final error.
double follow_biased_fixes(SharedFixError& err, double sigma_est, double offset, int n,
                           double* final_var = nullptr) {
  double estimate = 0.0;  // the truth is 0
  double var = sigma_est * sigma_est;
  for (int i = 0; i < n; ++i) {
    estimate += err.update(var, offset - estimate, kNoise * kNoise);
  }
  if (final_var) *final_var = var;
  return estimate;
}

TEST(SharedFixError, ManyFixesOfOneSegmentCountAsAboutOne) {
  // A moved structure reads 10 cm off on every frame of a segment. Independent fixes would
  // take the estimate all the way; shared, 300 of them move it as one measurement would:
  // P / (P + sigma_b^2) of the offset.
  SharedFixError err;
  err.begin(kSigmaB);
  const double sigma_est = 0.02;
  const double moved = follow_biased_fixes(err, sigma_est, 0.10, 300);
  const double one = 0.10 * sigma_est * sigma_est / (sigma_est * sigma_est + kSigmaB * kSigmaB);
  EXPECT_NEAR(moved, one, 0.005);
  EXPECT_LT(moved, 0.04);
  // The shared error took the rest.
  EXPECT_NEAR(err.bias(), 0.10 - moved, 0.005);
}

TEST(SharedFixError, ADriftedEstimateIsStillCorrected) {
  // After a blind stretch the estimate is 20 cm off with sigma 0.2 m; unbiased fixes put it
  // back within a centimetre or two.
  SharedFixError err;
  err.begin(kSigmaB);
  double estimate = 0.20, var = 0.2 * 0.2;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, kNoise);
  for (int i = 0; i < 50; ++i) estimate += err.update(var, (0.0 + noise(rng)) - estimate,
                                                       kNoise * kNoise);
  EXPECT_LT(std::abs(estimate), 0.02);
  // What remains uncertain is about the shared error's share, not the fixes' count.
  EXPECT_GT(std::sqrt(var), 0.015);
  EXPECT_LT(std::sqrt(var), kSigmaB);
}

TEST(SharedFixError, EachNewSegmentBringsNewEvidence) {
  // The same 10 cm offset on five segments in a row: each moves the estimate further (a
  // lasting error is believed in the end), but each by less than the whole offset.
  SharedFixError err;
  double estimate = 0.0, var = 0.02 * 0.02;
  double last = 0.0;
  for (int segment = 0; segment < 5; ++segment) {
    err.begin(kSigmaB);
    for (int i = 0; i < 60; ++i) estimate += err.update(var, 0.10 - estimate, kNoise * kNoise);
    EXPECT_GT(estimate, last);
    last = estimate;
    var += 0.01 * 0.01;  // the odometry between segments
  }
  EXPECT_GT(estimate, 0.06);
  EXPECT_LT(estimate, 0.10);
}

TEST(SharedFixError, AWeakFixMovesLittle) {
  // A fix near the gate's edge has a small weight: its noise variance is divided by it.
  SharedFixError a, b;
  a.begin(kSigmaB);
  b.begin(kSigmaB);
  double va = 0.02 * 0.02, vb = va;
  const double strong = a.update(va, 0.05, kNoise * kNoise);
  const double weak = b.update(vb, 0.05, kNoise * kNoise / 0.01);
  EXPECT_GT(strong, 5.0 * weak);
  EXPECT_GT(vb, va);
}

TEST(SharedFixError, ExpectationAndItsVariance) {
  SharedFixError err;
  err.begin(kSigmaB);
  EXPECT_DOUBLE_EQ(err.expected(), 0.0);
  EXPECT_DOUBLE_EQ(err.expected_var(0.0004, 0.0001), 0.0004 + kSigmaB * kSigmaB + 0.0001);
  double var = 0.0004;
  for (int i = 0; i < 100; ++i) err.update(var, 0.05, kNoise * kNoise);
  // After many fixes at one place the next one is expected there, and more sharply.
  EXPECT_GT(err.expected(), 0.03);
  EXPECT_LT(err.expected_var(var, kNoise * kNoise), 0.0004 + kSigmaB * kSigmaB);
}

TEST(SharedFixError, RescaleFollowsAnotherSourcesUpdate) {
  SharedFixError err;
  err.begin(kSigmaB);
  double var = 0.0004;
  err.update(var, 0.05, kNoise * kNoise);
  const double c = err.cross_cov();
  ASSERT_NE(c, 0.0);
  err.rescale(var, 0.5 * var);
  EXPECT_DOUBLE_EQ(err.cross_cov(), 0.5 * c);
}

TEST(SharedFixError, AVarianceThatGrewKeepsTheJointCovarianceValid) {
  // Another source's update may turn variance from one axis into another, so the estimate's
  // variance grows (the floor lines' update, turned by the robot's yaw): the expectation's
  // variance must stay positive whatever the covariance was. Found by the generated worlds:
  // a negative variance made the resection refuse its prior.
  SharedFixError err;
  err.begin(kSigmaB);
  double var = 0.0004;
  for (int i = 0; i < 20; ++i) err.update(var, 0.05, kNoise * kNoise);
  ASSERT_LT(err.cross_cov(), 0.0);
  err.rescale(var, 50.0 * var);
  EXPECT_LE(err.cross_cov() * err.cross_cov(), 50.0 * var * err.bias_var() * (1.0 + 1e-12));
  EXPECT_GE(err.expected_var(50.0 * var, kNoise * kNoise), kNoise * kNoise);
  EXPECT_GE(err.expected_var(1e-12, kNoise * kNoise), kNoise * kNoise);
}

TEST(SharedFixError, BadInputIsRefused) {
  SharedFixError err;
  EXPECT_THROW(err.begin(0.0), std::invalid_argument);
  EXPECT_THROW(err.begin(std::nan("")), std::invalid_argument);
  err.begin(kSigmaB);
  double var = 0.0004, zero = 0.0;
  EXPECT_THROW(err.update(zero, 0.01, 1e-4), std::invalid_argument);
  EXPECT_THROW(err.update(var, 0.01, 0.0), std::invalid_argument);
  EXPECT_THROW(err.update(var, std::nan(""), 1e-4), std::invalid_argument);
  EXPECT_THROW(err.rescale(0.0, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::navigator
