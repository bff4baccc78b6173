// Canonical (rho, theta) form of image lines, against hand-computed values.
#include "core/features/line_segment.hpp"

#include <cmath>

#include <gtest/gtest.h>

namespace pepper::core::features {
namespace {

constexpr double kTol = 1e-12;

TEST(RhoTheta, VerticalLineHasThetaZeroAndRhoItsX) {
  // x = 0.3: normal (1, 0), either point order.
  for (const auto& [a, b] : {std::pair{cv::Point2d(0.3, -0.2), cv::Point2d(0.3, 0.4)},
                             std::pair{cv::Point2d(0.3, 0.4), cv::Point2d(0.3, -0.2)}}) {
    const RhoTheta l = rho_theta_from_points(a, b);
    EXPECT_NEAR(l.theta_rad, 0.0, kTol);
    EXPECT_NEAR(l.rho, 0.3, kTol);
  }
  const RhoTheta left = rho_theta_from_points({-0.25, 0.0}, {-0.25, 1.0});
  EXPECT_NEAR(left.rho, -0.25, kTol);  // rho keeps the sign of x
}

TEST(RhoTheta, HorizontalLineHasThetaHalfPi) {
  const RhoTheta l = rho_theta_from_points({-0.5, -0.1}, {0.5, -0.1});
  EXPECT_NEAR(l.theta_rad, M_PI_2, kTol);  // (-pi/2, pi/2]: +pi/2, not -pi/2
  EXPECT_NEAR(l.rho, -0.1, kTol);
  const RhoTheta r = rho_theta_from_points({0.5, -0.1}, {-0.5, -0.1});
  EXPECT_NEAR(r.theta_rad, M_PI_2, kTol);
  EXPECT_NEAR(r.rho, -0.1, kTol);
}

TEST(RhoTheta, DiagonalByHand) {
  // Line through (1, 0) and (0, 1): x + y = 1 -> normal (1, 1)/sqrt 2, theta = pi/4,
  // rho = 1/sqrt 2.
  const RhoTheta l = rho_theta_from_points({1.0, 0.0}, {0.0, 1.0});
  EXPECT_NEAR(l.theta_rad, M_PI_4, kTol);
  EXPECT_NEAR(l.rho, 1.0 / std::sqrt(2.0), kTol);
  // Line through (0, 0) and (1, 1): x - y = 0 -> theta = -pi/4, rho = 0.
  const RhoTheta m = rho_theta_from_points({0.0, 0.0}, {1.0, 1.0});
  EXPECT_NEAR(m.theta_rad, -M_PI_4, kTol);
  EXPECT_NEAR(m.rho, 0.0, kTol);
  // Foot of the perpendicular: the control feature X = rho cos(theta) = 0.5 for x + y = 1.
  EXPECT_NEAR(l.rho * std::cos(l.theta_rad), 0.5, kTol);
}

TEST(RhoTheta, CanonicalFormIsInRangeAndSameLine) {
  for (double theta = -7.0; theta <= 7.0; theta += 0.37) {
    for (double rho : {-0.8, 0.0, 0.45}) {
      const RhoTheta c = canonical_rho_theta(rho, theta);
      EXPECT_GT(c.theta_rad, -M_PI_2);
      EXPECT_LE(c.theta_rad, M_PI_2 + kTol);
      // Same line: the point rho * n of the original lies on the canonical line.
      const double px = rho * std::cos(theta), py = rho * std::sin(theta);
      EXPECT_NEAR(px * std::cos(c.theta_rad) + py * std::sin(c.theta_rad), c.rho, 1e-9);
    }
  }
  const RhoTheta h = canonical_rho_theta(0.2, -M_PI_2);  // -pi/2 maps to +pi/2 with -rho
  EXPECT_NEAR(h.theta_rad, M_PI_2, kTol);
  EXPECT_NEAR(h.rho, -0.2, kTol);
}

TEST(RhoTheta, HomogeneousLineContainsThePoints) {
  const cv::Point2d a(0.12, -0.3), b(-0.4, 0.25);
  const cv::Vec3d l = homogeneous_line(rho_theta_from_points(a, b));
  EXPECT_NEAR(l[0] * a.x + l[1] * a.y + l[2], 0.0, 1e-12);
  EXPECT_NEAR(l[0] * b.x + l[1] * b.y + l[2], 0.0, 1e-12);
  EXPECT_NEAR(l[0] * l[0] + l[1] * l[1], 1.0, 1e-12);
}

TEST(RhoTheta, CoincidentPointsThrow) {
  EXPECT_THROW(rho_theta_from_points({0.1, 0.1}, {0.1, 0.1}), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::features
