// bounded_move.hpp: the pose a constant twist reaches in a horizon, and back (issue 23). The
// client and the mock NAOqi server must agree exactly, or a deadman-bounded replay would drive
// differently from a plain one.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "naoqi_bridge/qi/bounded_move.hpp"

namespace qi = pepper::naoqi_bridge::qi;

TEST(BoundedMove, StraightLineIsVelocityTimesHorizon) {
  const auto p = qi::pose_after({0.2, -0.05, 0.0}, 0.25);
  EXPECT_DOUBLE_EQ(p.x_m, 0.05);
  EXPECT_DOUBLE_EQ(p.y_m, -0.0125);
  EXPECT_DOUBLE_EQ(p.theta_rad, 0.0);
}

TEST(BoundedMove, QuarterTurnEndsOnTheCircle) {
  // v = 0.5 m/s, omega = pi/2 rad/s for 1 s: a quarter of a circle of radius 1/pi to the left.
  const double r = 0.5 / (M_PI / 2.0);
  const auto p = qi::pose_after({0.5, 0.0, M_PI / 2.0}, 1.0);
  EXPECT_NEAR(p.x_m, r, 1e-12);
  EXPECT_NEAR(p.y_m, r, 1e-12);
  EXPECT_NEAR(p.theta_rad, M_PI / 2.0, 1e-12);
}

TEST(BoundedMove, RoundTripsForTurnsBothWaysAndSideways) {
  for (const double omega : {-2.0, -0.3, -1e-12, 0.0, 1e-7, 0.4, 2.0}) {
    for (const double vy : {-0.1, 0.0, 0.2}) {
      const pepper::core::BaseVelocity v{0.15, vy, omega};
      const auto back = qi::velocity_reaching(qi::pose_after(v, 0.25), 0.25);
      EXPECT_NEAR(back.v_x_m_s, v.v_x_m_s, 1e-9) << omega << " " << vy;
      EXPECT_NEAR(back.v_y_m_s, v.v_y_m_s, 1e-9) << omega << " " << vy;
      EXPECT_NEAR(back.omega_rad_s, v.omega_rad_s, 1e-12) << omega << " " << vy;
    }
  }
}

TEST(BoundedMove, RefusesNonFiniteValuesAndNonPositiveHorizons) {
  EXPECT_THROW(qi::pose_after({NAN, 0.0, 0.0}, 0.25), std::invalid_argument);
  EXPECT_THROW(qi::pose_after({0.1, 0.0, INFINITY}, 0.25), std::invalid_argument);
  EXPECT_THROW(qi::pose_after({0.1, 0.0, 0.0}, 0.0), std::invalid_argument);
  EXPECT_THROW(qi::velocity_reaching({0.1, 0.0, 0.0}, -1.0), std::invalid_argument);
  EXPECT_THROW(qi::velocity_reaching({0.1, NAN, 0.0}, 0.25), std::invalid_argument);
}
