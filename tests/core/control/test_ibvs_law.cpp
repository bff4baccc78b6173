#include <gtest/gtest.h>

#include <cmath>

#include "core/control/ibvs_law.hpp"

namespace pepper::core::control {
namespace {

constexpr double kExact = 1e-12;  // a handful of floating-point operations

TEST(IbvsLaw, LinesOnlyHandComputed) {
  IbvsInput in;
  in.lines = ModalityError{0.1, 0.2, 0.9};
  // omega = -1 * 0.9 * (0.7*0.1 + 0.3*0.2) / 0.81 = -0.13 / 0.9 = -0.144444...
  const IbvsResult r = compute_ibvs_omega(in, {});
  ASSERT_TRUE(r.omega_rad_s);
  EXPECT_NEAR(*r.omega_rad_s, -0.13 / 0.9, kExact);
  EXPECT_TRUE(r.used_lines);
  EXPECT_FALSE(r.used_points);
}

TEST(IbvsLaw, PointsOnlyHandComputed) {
  IbvsInput in;
  in.points = ModalityError{-0.05, -0.1, 1.2};
  // omega = -1.2 * (-0.035 - 0.03) / 1.44 = 0.065 / 1.2
  const IbvsResult r = compute_ibvs_omega(in, {});
  ASSERT_TRUE(r.omega_rad_s);
  EXPECT_NEAR(*r.omega_rad_s, 0.065 / 1.2, kExact);
  EXPECT_TRUE(r.used_points);
}

TEST(IbvsLaw, BothModalitiesHandComputed) {
  IbvsInput in;
  in.lines = ModalityError{0.1, 0.2, 0.9};
  in.points = ModalityError{-0.05, -0.1, 1.2};
  // num = 0.9*0.13 + 1.2*(-0.065) = 0.117 - 0.078 = 0.039; den = 0.81 + 1.44 = 2.25
  IbvsOptions opt;
  opt.lambda = 2.0;
  const IbvsResult r = compute_ibvs_omega(in, opt);
  ASSERT_TRUE(r.omega_rad_s);
  EXPECT_NEAR(*r.omega_rad_s, -2.0 * 0.039 / 2.25, kExact);
  // Modes drop the other modality from numerator and denominator.
  opt.mode = FeatureMode::kLinesOnly;
  EXPECT_NEAR(*compute_ibvs_omega(in, opt).omega_rad_s, -2.0 * 0.13 / 0.9, kExact);
  opt.mode = FeatureMode::kPointsOnly;
  EXPECT_NEAR(*compute_ibvs_omega(in, opt).omega_rad_s, 2.0 * 0.065 / 1.2, kExact);
}

TEST(IbvsLaw, FeedForwardWeightsAndMissingNextNext) {
  IbvsInput in;
  in.points = ModalityError{0.0, 0.1, 1.0};
  // Only INN disagrees: the feed-forward alone turns: omega = -0.3 * 0.1.
  EXPECT_NEAR(*compute_ibvs_omega(in, {}).omega_rad_s, -0.03, kExact);
  IbvsOptions no_ff;
  no_ff.g1 = 1.0;
  no_ff.g2 = 0.0;
  EXPECT_NEAR(*compute_ibvs_omega(in, no_ff).omega_rad_s, 0.0, kExact);
  // Last segment (no INN): the whole weight goes to IN.
  in.points = ModalityError{0.1, std::nullopt, 1.0};
  EXPECT_NEAR(*compute_ibvs_omega(in, {}).omega_rad_s, -0.1, kExact);
}

TEST(IbvsLaw, PositiveErrorTurnsRightAndDrivesErrorToZero) {
  // Features to the right of where the key image saw them (Xa > XN) -> turn right (omega < 0):
  // a right turn moves image content left (dx/dt = J omega with J > 0).
  IbvsInput in;
  in.points = ModalityError{0.2, 0.2, 1.04};
  const double omega = *compute_ibvs_omega(in, {}).omega_rad_s;
  EXPECT_LT(omega, 0.0);
  EXPECT_NEAR(1.04 * omega, -0.2, kExact);  // de/dt = J omega = -lambda e
}

TEST(IbvsLaw, NoUsableModalityGivesNoCommand) {
  EXPECT_FALSE(compute_ibvs_omega({}, {}).omega_rad_s);
  IbvsInput in;
  in.lines = ModalityError{0.1, 0.1, 0.0};  // horizontal lines carry no yaw information
  EXPECT_FALSE(compute_ibvs_omega(in, {}).omega_rad_s);
  in.lines = ModalityError{std::nan(""), 0.1, 1.0};
  EXPECT_FALSE(compute_ibvs_omega(in, {}).omega_rad_s);
  IbvsInput pts_only;
  pts_only.points = ModalityError{0.1, 0.1, 1.0};
  IbvsOptions lines_mode;
  lines_mode.mode = FeatureMode::kLinesOnly;
  EXPECT_FALSE(compute_ibvs_omega(pts_only, lines_mode).omega_rad_s);
}

TEST(IbvsLaw, ValidateNamesBadFields) {
  IbvsOptions opt;
  EXPECT_TRUE(opt.validate().empty());
  opt.g1 = 1.5;
  opt.lambda = -1.0;
  const auto errors = opt.validate();
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].find("g1"), std::string::npos);
  EXPECT_NE(errors[1].find("lambda"), std::string::npos);
  EXPECT_THROW(compute_ibvs_omega({}, opt), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::control
