// CeilingNavigator on synthetic observations (no rendering): a ceiling of points with random
// ORB-like descriptors is the mosaic (mosaic frame = world frame), the tour's relay poses are
// given, and a unicycle integrates the commands, so the law, the switching rule and the stops
// can be checked against known poses.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <optional>
#include <random>
#include <stdexcept>

#include "core/ceiling/ceiling_navigator.hpp"
#include "synthetic_ceiling.hpp"

namespace pepper::core::ceiling {
namespace {

namespace nav = core::navigator;

constexpr int64_t kFrameNs = 66'666'667;  // 15 Hz

using Ceiling = test_support::SyntheticCeiling;

// Points every 0.1 m (jittered) over x in [-1, 7], y in [-2, 5]: the tours below and their
// views stay inside.
Ceiling make_ceiling(uint32_t seed) {
  return test_support::make_synthetic_ceiling(seed, -1.0, 80, -2.0, 70);
}

Mosaic mosaic_of(const Ceiling& c) {
  Mosaic m;
  m.px_per_m = 120.0;
  for (size_t k = 0; k < c.points_world.size(); ++k) {
    MosaicLandmark l;
    l.id = static_cast<int64_t>(k);
    l.position_m = c.points_world[k];
    l.descriptor = c.descriptors.row(static_cast<int>(k)).clone();
    m.landmarks.push_back(l);
  }
  return m;
}

// What a base at T_world_base sees, or, with blind, random junk only (a view the mosaic does
// not know).
CeilingObservation see(const Ceiling& c, const PlanarPose& T_world_base, std::mt19937& rng,
                       bool blind = false) {
  return test_support::see_synthetic(c, T_world_base, rng, blind ? 80 : 0, blind);
}

CeilingTour tour_of(const std::vector<PlanarPose>& relays) {
  CeilingTour t;
  t.frames = 100 * static_cast<int64_t>(relays.size());
  for (size_t i = 0; i < relays.size(); ++i) {
    RelayImageRecord r;
    r.frame = 100 * static_cast<int64_t>(i);
    r.T_mosaic_base = relays[i];
    t.relay_images.push_back(r);
  }
  return t;
}

// A 4 m straight tour along +x from the origin, relay images 1 m apart.
CeilingTour straight_tour() {
  return tour_of({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}});
}

// 2 m straight, a 90 degree left turn of radius 1 m cut into 3 relay segments, 1.5 m straight.
CeilingTour turning_tour() {
  std::vector<PlanarPose> r = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  for (int k = 1; k <= 3; ++k) {
    const double a = k * M_PI / 6.0;
    r.push_back({2.0 + std::sin(a), 1.0 - std::cos(a), a});
  }
  r.push_back({3.0, 2.5, M_PI / 2});
  return tour_of(r);
}

CeilingNavigator make_navigator(const Ceiling& c, const CeilingTour& tour,
                                CeilingNavigatorOptions o = {}) {
  return CeilingNavigator(mosaic_of(c), tour, CeilingCamera{}, {0.07, 0.0}, o);
}

// Integrates the command over one frame (unicycle).
PlanarPose drive(const PlanarPose& p, const nav::Command& c) {
  if (c.stop) return p;
  const double dt = kFrameNs * 1e-9;
  const double th = p.theta_rad + 0.5 * c.omega_rad_s * dt;
  return {p.x_m + c.v_m_s * dt * std::cos(th), p.y_m + c.v_m_s * dt * std::sin(th),
          wrap_angle_rad(p.theta_rad + c.omega_rad_s * dt)};
}

// Distance from the taught path: the straight tour's x axis, or the turning tour's straight,
// quarter circle (centre (2, 1), radius 1) and straight.
double distance_to_path(bool turning, const PlanarPose& p) {
  if (!turning || p.x_m <= 2.0) return std::abs(p.y_m);
  if (p.y_m >= 1.0) return std::abs(p.x_m - 3.0);
  return std::abs(std::hypot(p.x_m - 2.0, p.y_m - 1.0) - 1.0);
}

TEST(CeilingNavigator, TurnsTowardsThePathFromEitherSide) {
  const Ceiling c = make_ceiling(3);
  std::mt19937 rng(1);
  for (const double y0 : {0.2, -0.2}) {
    CeilingNavigator n = make_navigator(c, straight_tour());
    const auto r = n.step_observation(see(c, {0.5, y0, 0.0}, rng), 0, std::nullopt);
    ASSERT_FALSE(r.step.command.stop) << y0;
    EXPECT_TRUE(r.ceiling.fix);
    EXPECT_FALSE(r.ceiling.prior_used);  // first fix: over the whole mosaic
    EXPECT_NEAR(r.ceiling.T_mosaic_base.y_m, y0, 1e-6);
    EXPECT_NEAR(r.step.telemetry.vnhv_lateral_m, y0, 1e-6);
    // Left of the path (y > 0) turns right (omega < 0), and the other way.
    EXPECT_LT(r.step.telemetry.omega_demand_rad_s * y0, 0.0) << y0;
    EXPECT_EQ(r.step.telemetry.ip, 0);
    EXPECT_EQ(r.step.telemetry.in, 1);
    EXPECT_EQ(r.step.telemetry.state, nav::NavState::kNavigating);
  }
  // Facing away from the path beyond the chained form's bound: turn on the spot, v = 0.
  CeilingNavigator n = make_navigator(c, straight_tour());
  const auto r = n.step_observation(see(c, {0.5, 0.0, 1.4}, rng), 0, std::nullopt);
  ASSERT_FALSE(r.step.command.stop);
  EXPECT_EQ(r.step.command.v_m_s, 0.0);
  EXPECT_LT(r.step.telemetry.omega_demand_rad_s, 0.0);
}

TEST(CeilingNavigator, ClosedLoopJoinsThePathSwitchesAtEachRelayAndStopsAtTheEnd) {
  const Ceiling c = make_ceiling(5);
  std::mt19937 rng(2);
  for (const bool turning : {false, true}) {
    const CeilingTour tour = turning ? turning_tour() : straight_tour();
    CeilingNavigator n = make_navigator(c, tour);
    PlanarPose truth{-0.1, 0.25, -0.15};  // 25 cm left, turned 9 degrees right
    std::vector<int> switched_at;
    int64_t t_ns = 0;
    bool complete = false;
    double max_late_m = 0.0;
    for (int k = 0; k < 15 * 90 && !complete; ++k, t_ns += kFrameNs) {
      const auto r = n.step_observation(see(c, truth, rng), t_ns, std::nullopt);
      const nav::Telemetry& tel = r.step.telemetry;
      if (tel.switched) {
        switched_at.push_back(tel.in);
        // The rule: IN is passed once the robot's projection reaches it; so at the switch the
        // robot is within a frame's travel (1 cm at 0.15 m/s) past the previous IN.
        const PlanarPose passed =
            tour.relay_images[tel.in - 1].T_mosaic_base.inverse() * r.ceiling.T_mosaic_base;
        EXPECT_GE(passed.x_m, -1e-9);
        EXPECT_LT(passed.x_m, 0.02);
      }
      if (tel.state == nav::NavState::kTourComplete) {
        complete = true;
        EXPECT_TRUE(r.step.command.stop);
        EXPECT_EQ(r.step.command.reason, nav::StopReason::kTourComplete);
        EXPECT_EQ(tel.arrival_source, nav::Telemetry::ArrivalSource::kVision);
        EXPECT_GE(tel.arrival_along_m, 0.0);
        EXPECT_LT(tel.arrival_along_m, 0.02);
        EXPECT_LT(std::abs(tel.arrival_lateral_m), 0.03);
        break;
      }
      ASSERT_FALSE(r.step.command.stop) << k;
      // After 1.5 m of the straight the 25 cm offset is gone (Kp 9, Kd 6: ~1.6 m to settle).
      if (truth.x_m > 1.5) max_late_m = std::max(max_late_m, distance_to_path(turning, truth));
      truth = drive(truth, r.step.command);
    }
    ASSERT_TRUE(complete) << turning;
    std::vector<int> expected;
    for (int i = 2; i < static_cast<int>(tour.relay_images.size()); ++i) expected.push_back(i);
    EXPECT_EQ(switched_at, expected) << turning;
    // The chord of a 30 degree arc of radius 1 m cuts it by 3.4 cm: the arc model follows it.
    EXPECT_LT(max_late_m, 0.03) << turning;
    // Further frames: still stopped, tour complete.
    const auto after = n.step_observation(see(c, truth, rng), t_ns + kFrameNs, std::nullopt);
    EXPECT_TRUE(after.step.command.stop);
    EXPECT_EQ(after.step.command.reason, nav::StopReason::kTourComplete);
  }
}

// Two relay images a centimetre apart, the second a little *behind* the first in the mosaic
// (the mosaic's pose noise is larger than such a step; room_corridor_room's relays 15 and 16,
// 1.7 cm apart, session 38): their chord points backwards, against both taught headings. The
// robot must go on along the taught heading, not turn round to follow the chord (the replay that
// did so turned 100 degrees on the spot and drove into a door frame).
TEST(CeilingNavigator, AChordShorterThanThePosesNoiseDoesNotTurnTheRobotRound) {
  const Ceiling c = make_ceiling(7);
  std::mt19937 rng(4);
  const CeilingTour tour =
      tour_of({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {1.99, 0.004, 0.01}, {3, 0, 0}, {4, 0, 0}});
  CeilingNavigator n = make_navigator(c, tour);
  PlanarPose truth{0.05, 0.02, 0.0};
  int64_t t_ns = 0;
  bool complete = false;
  double max_off_m = 0.0, max_yaw_rad = 0.0;
  for (int k = 0; k < 15 * 60 && !complete; ++k, t_ns += kFrameNs) {
    const auto r = n.step_observation(see(c, truth, rng), t_ns, std::nullopt);
    if (r.step.telemetry.state == nav::NavState::kTourComplete) {
      complete = true;
      break;
    }
    ASSERT_FALSE(r.step.command.stop) << k;
    EXPECT_GT(r.step.command.v_m_s, 0.0) << "turned on the spot at x " << truth.x_m;
    truth = drive(truth, r.step.command);
    max_off_m = std::max(max_off_m, std::abs(truth.y_m));
    max_yaw_rad = std::max(max_yaw_rad, std::abs(truth.theta_rad));
  }
  EXPECT_TRUE(complete);
  EXPECT_LT(max_off_m, 0.05);
  EXPECT_LT(max_yaw_rad, 0.2);
  EXPECT_NEAR(truth.x_m, 4.0, 0.05);
}

TEST(CeilingNavigator, StartsOnTheSegmentItStandsBeside) {
  const Ceiling c = make_ceiling(6);
  std::mt19937 rng(3);
  CeilingNavigator n = make_navigator(c, turning_tour());
  // In the turn, between relay 3 (30 deg) and 4 (60 deg), heading along it.
  const auto r = n.step_observation(see(c, {2.6, 0.3, 0.8}, rng), 0, std::nullopt);
  ASSERT_FALSE(r.step.command.stop);
  EXPECT_EQ(r.step.telemetry.in, 4);
}

TEST(CeilingNavigator, NotLocalisedAndLostStop) {
  const Ceiling c = make_ceiling(7);
  std::mt19937 rng(4);
  CeilingNavigator n = make_navigator(c, straight_tour());
  // Never localised: stop, reason not localised, no segment.
  auto r = n.step_observation(see(c, {0.5, 0, 0}, rng, /*blind=*/true), 0, std::nullopt);
  EXPECT_TRUE(r.step.command.stop);
  EXPECT_EQ(r.step.command.reason, nav::StopReason::kNotLocalized);
  EXPECT_EQ(r.step.telemetry.in, -1);
  // Localised, then blind without odometry: stop at once (features lost), and a later view of
  // the mosaic recovers without a prior.
  r = n.step_observation(see(c, {0.5, 0, 0}, rng), kFrameNs, std::nullopt);
  ASSERT_FALSE(r.step.command.stop);
  r = n.step_observation(see(c, {0.51, 0, 0}, rng, true), 2 * kFrameNs, std::nullopt);
  EXPECT_TRUE(r.step.command.stop);
  EXPECT_EQ(r.step.command.reason, nav::StopReason::kFeaturesLost);
  EXPECT_EQ(n.state(), nav::NavState::kLost);
  r = n.step_observation(see(c, {0.51, 0, 0}, rng), 3 * kFrameNs, std::nullopt);
  EXPECT_FALSE(r.step.command.stop);
  EXPECT_FALSE(r.ceiling.prior_used);
  EXPECT_EQ(r.step.telemetry.in, 1);
}

// The coasting bound is the odometry's error model (core/odometry.hpp): driving straight on, the
// possible error after s metres is about 0.03 s + 0.005 s^2 (distance error plus the heading
// error the metres add), 0.03 m at 0.873 m; the robot here also steers back from 5 cm off the
// path, and each radian it turns adds heading error, so it stops a little sooner.
TEST(CeilingNavigator, CoastsOnOdometryThenStops) {
  const Ceiling c = make_ceiling(8);
  std::mt19937 rng(5);
  CeilingNavigatorOptions o;
  o.coast_max_error_m = 0.03;
  o.coast_max_s = 100.0;
  CeilingNavigator n = make_navigator(c, straight_tour(), o);
  // The odometry frame differs from the mosaic frame by an arbitrary transform.
  const PlanarPose T_odom_world{5.0, -2.0, 1.0};
  auto odom_of = [&](const PlanarPose& w) {
    const PlanarPose p = T_odom_world * w;
    return std::optional<OdometryPose>(OdometryPose{p.x_m, p.y_m, p.theta_rad});
  };
  PlanarPose truth{0.5, 0.05, 0.0};
  auto r = n.step_observation(see(c, truth, rng), 0, odom_of(truth));
  ASSERT_FALSE(r.step.command.stop);
  int coasting = 0;
  int64_t t_ns = kFrameNs;
  double last_coasted_m = 0.0;
  for (; t_ns < 300 * kFrameNs; t_ns += kFrameNs) {
    truth = drive(truth, r.step.command);
    r = n.step_observation(see(c, truth, rng, /*blind=*/true), t_ns, odom_of(truth));
    if (r.step.command.stop) break;
    ++coasting;
    EXPECT_EQ(r.step.telemetry.state, nav::NavState::kDeadReckoning);
    // The odometry's prediction is exact here.
    EXPECT_NEAR(r.ceiling.T_mosaic_base.x_m, truth.x_m, 1e-9);
    EXPECT_NEAR(r.ceiling.T_mosaic_base.y_m, truth.y_m, 1e-9);
    EXPECT_LE(r.ceiling.coast_error_m, 0.03);
    last_coasted_m = r.ceiling.coasted_m;
  }
  ASSERT_TRUE(r.step.command.stop);
  EXPECT_EQ(r.step.command.reason, nav::StopReason::kFeaturesLost);
  EXPECT_GT(last_coasted_m, 0.75);
  EXPECT_LT(last_coasted_m, 0.875);
  EXPECT_GE(coasting, 50);

  // The time bound too: 0.5 s at 15 Hz.
  o.coast_max_s = 0.5;
  CeilingNavigator m = make_navigator(c, straight_tour(), o);
  truth = {0.5, 0.0, 0.0};
  r = m.step_observation(see(c, truth, rng), 0, odom_of(truth));
  int frames = 0;
  for (t_ns = kFrameNs; !r.step.command.stop && frames < 100; t_ns += kFrameNs, ++frames) {
    truth = drive(truth, r.step.command);
    r = m.step_observation(see(c, truth, rng, true), t_ns, odom_of(truth));
  }
  EXPECT_EQ(frames, 8);  // the frame 8 x 66.7 ms after the fix is beyond 0.5 s
}

// A quarter turn on the spot while blind (a corridor's end facing a wall) adds heading error
// but no position error: the robot coasts through it, and the heading error it leaves makes
// the straight coast after it shorter: (0.03 + 0.05 x pi/2) s + 0.005 s^2 = 0.03 at 0.27 m.
TEST(CeilingNavigator, CoastsThroughATurnOnTheSpotThenStopsSoonerAfterIt) {
  const Ceiling c = make_ceiling(8);
  std::mt19937 rng(5);
  CeilingNavigator n = make_navigator(c, straight_tour());
  auto odom_of = [](const PlanarPose& w) {
    return std::optional<OdometryPose>(OdometryPose{w.x_m, w.y_m, w.theta_rad});
  };
  PlanarPose truth{0.5, 0.0, 0.0};
  auto r = n.step_observation(see(c, truth, rng), 0, odom_of(truth));
  ASSERT_FALSE(r.step.command.stop);
  int64_t t_ns = kFrameNs;
  // The odometry reports the turn whatever was commanded: the base turned (the test drives it).
  for (int k = 0; k < 30; ++k, t_ns += kFrameNs) {
    truth.theta_rad += M_PI / 60.0;
    r = n.step_observation(see(c, truth, rng, true), t_ns, odom_of(truth));
    ASSERT_FALSE(r.step.command.stop) << k;
    EXPECT_EQ(r.step.telemetry.state, nav::NavState::kDeadReckoning);
    EXPECT_LT(r.ceiling.coast_error_m, 1e-9);
  }
  double coasted_after_turn_m = 0.0;
  for (int k = 0; k < 100 && !r.step.command.stop; ++k, t_ns += kFrameNs) {
    truth = truth * PlanarPose{0.01, 0.0, 0.0};
    r = n.step_observation(see(c, truth, rng, true), t_ns, odom_of(truth));
    if (!r.step.command.stop) coasted_after_turn_m = r.ceiling.coasted_m;
  }
  ASSERT_TRUE(r.step.command.stop);
  EXPECT_EQ(r.step.command.reason, nav::StopReason::kFeaturesLost);
  EXPECT_GT(coasted_after_turn_m, 0.25);
  EXPECT_LT(coasted_after_turn_m, 0.28);
}

TEST(CeilingNavigator, StopsForGoodAtABreakOfTheRelayChain) {
  const Ceiling c = make_ceiling(9);
  std::mt19937 rng(6);
  CeilingTour tour = straight_tour();
  tour.breaks = {1};  // relay 1 -> 2
  CeilingNavigator n = make_navigator(c, tour);
  PlanarPose truth{0.8, 0.0, 0.0};
  auto r = n.step_observation(see(c, truth, rng), 0, std::nullopt);
  ASSERT_FALSE(r.step.command.stop);
  int64_t t_ns = kFrameNs;
  for (int k = 0; k < 100 && !r.step.command.stop; ++k, t_ns += kFrameNs) {
    truth = drive(truth, r.step.command);
    r = n.step_observation(see(c, truth, rng), t_ns, std::nullopt);
  }
  ASSERT_TRUE(r.step.command.stop);
  EXPECT_EQ(r.step.command.reason, nav::StopReason::kRelayBreak);
  EXPECT_NEAR(truth.x_m, 1.0, 0.02);  // at relay 1, where the broken segment begins
  r = n.step_observation(see(c, truth, rng), t_ns, std::nullopt);
  EXPECT_EQ(r.step.command.reason, nav::StopReason::kRelayBreak);
}

TEST(CeilingNavigator, RefusesBadInput) {
  const Ceiling c = make_ceiling(10);
  CeilingNavigatorOptions o;
  o.coast_max_error_m = -1.0;
  EXPECT_THROW(make_navigator(c, straight_tour(), o), std::invalid_argument);
  o = {};
  o.vnhv.kp_1_m2 = 0.0;
  EXPECT_THROW(make_navigator(c, straight_tour(), o), std::invalid_argument);
  CeilingTour one = straight_tour();
  one.relay_images.resize(1);
  EXPECT_THROW(make_navigator(c, one), std::invalid_argument);
  EXPECT_THROW(CeilingNavigator(Mosaic{}, straight_tour(), CeilingCamera{}, {0, 0}),
               std::invalid_argument);
  CeilingNavigator n = make_navigator(c, straight_tour());
  std::mt19937 rng(1);
  n.step_observation(see(c, {0.5, 0, 0}, rng), 10, std::nullopt);
  EXPECT_THROW(n.step_observation(see(c, {0.5, 0, 0}, rng), 5, std::nullopt),
               std::invalid_argument);
  Frame f;
  f.gray = cv::Mat(240, 320, CV_8UC1, cv::Scalar(0));  // the camera is VGA
  f.t_ns = 20;
  EXPECT_THROW(n.step(f), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::ceiling
