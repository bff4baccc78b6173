// The teach drive's distance from the robot's odometry, or from commanded speeds where frames
// have none (core/mapping/drive_odometer.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/mapping/drive_odometer.hpp"

namespace pepper::core::mapping {
namespace {

constexpr int64_t kMs = 1'000'000;

TEST(DriveOdometer, IntegratesTheSpeedInForceOverEachInterval) {
  DriveOdometer odo;
  EXPECT_EQ(odo.on_frame(5'000 * kMs, 0.7), 0.0);  // the first frame: nothing driven yet
  // 0.25 m/s for 200 ms, then 0.1 m/s for 100 ms, then backwards at 0.2 m/s for 50 ms.
  EXPECT_NEAR(odo.on_frame(5'200 * kMs, 0.25), 0.05, 1e-12);
  EXPECT_NEAR(odo.on_frame(5'300 * kMs, 0.1), 0.06, 1e-12);
  EXPECT_NEAR(odo.on_frame(5'350 * kMs, -0.2), 0.07, 1e-12);
  EXPECT_NEAR(odo.travelled_m(), 0.07, 1e-12);
}

TEST(DriveOdometer, StampsThatDoNotAdvanceAddNothing) {
  DriveOdometer odo;
  odo.on_frame(1'000 * kMs, 0.0);
  EXPECT_NEAR(odo.on_frame(1'100 * kMs, 0.5), 0.05, 1e-12);
  EXPECT_NEAR(odo.on_frame(1'100 * kMs, 0.5), 0.05, 1e-12);  // repeated stamp
  EXPECT_NEAR(odo.on_frame(900 * kMs, 0.5), 0.05, 1e-12);    // older stamp
  // The interval is measured from the newest stamp seen, not from the older one.
  EXPECT_NEAR(odo.on_frame(1'200 * kMs, 0.5), 0.10, 1e-12);
}

TEST(DriveOdometer, NonFiniteSpeedIsRefused) {
  DriveOdometer odo;
  odo.on_frame(0, 0.1);
  EXPECT_THROW(odo.on_frame(kMs, std::numeric_limits<double>::quiet_NaN()),
               std::invalid_argument);
  EXPECT_THROW(odo.on_frame(kMs, std::numeric_limits<double>::infinity()), std::invalid_argument);
  EXPECT_EQ(odo.travelled_m(), 0.0);
}

// Where both frames of an interval carry odometry, the interval is the odometry's step, whatever
// was commanded (a base held back by its acceleration limit, a blocked base).
TEST(DriveOdometer, OdometryMeasuresWhatTheBaseDid) {
  DriveOdometer odo;
  EXPECT_EQ(odo.on_frame(0, 0.25, OdometryPose{1.0, 2.0, 0.3}), 0.0);
  // 100 ms at a commanded 0.25 m/s, but the base moved (0.03, 0.04): 5 cm.
  EXPECT_NEAR(odo.on_frame(100 * kMs, 0.25, OdometryPose{1.03, 2.04, 0.35}), 0.05, 1e-12);
  // Turning on the spot: the odometry's position does not move, nothing is driven.
  EXPECT_NEAR(odo.on_frame(200 * kMs, 0.0, OdometryPose{1.03, 2.04, 0.9}), 0.05, 1e-12);
  EXPECT_NEAR(odo.from_odometry_m(), 0.05, 1e-12);
  EXPECT_EQ(odo.odometry_jumps(), 0);
}

// A frame without odometry: the intervals on both sides of it fall back to the commanded speed
// (the odometry step across the gap is not counted twice or lost).
TEST(DriveOdometer, FramesWithoutOdometryUseTheCommandedSpeed) {
  DriveOdometer odo;
  odo.on_frame(0, 0.2, OdometryPose{0.0, 0.0, 0.0});
  EXPECT_NEAR(odo.on_frame(100 * kMs, 0.2, OdometryPose{0.021, 0.0, 0.0}), 0.021, 1e-12);
  EXPECT_NEAR(odo.on_frame(200 * kMs, 0.2), 0.041, 1e-12);  // no odometry: 0.2 m/s x 0.1 s
  EXPECT_NEAR(odo.on_frame(300 * kMs, 0.2, OdometryPose{0.063, 0.0, 0.0}), 0.061, 1e-12);
  EXPECT_NEAR(odo.on_frame(400 * kMs, 0.2, OdometryPose{0.084, 0.0, 0.0}), 0.082, 1e-12);
  EXPECT_NEAR(odo.from_odometry_m(), 0.042, 1e-12);
}

// An odometry step faster than Pepper can drive (a reset to the origin) is not believed.
TEST(DriveOdometer, OdometryJumpsAreNotBelieved) {
  DriveOdometer odo;
  odo.on_frame(0, 0.2, OdometryPose{12.0, -3.0, 1.0});
  // 1 m/s allowed over 100 ms is 0.1 m; the reading jumped 12.4 m.
  EXPECT_NEAR(odo.on_frame(100 * kMs, 0.2, OdometryPose{0.0, 0.0, 0.0}), 0.02, 1e-12);
  EXPECT_EQ(odo.odometry_jumps(), 1);
  EXPECT_NEAR(odo.on_frame(200 * kMs, 0.2, OdometryPose{0.02, 0.0, 0.0}), 0.04, 1e-12);
  EXPECT_THROW(odo.on_frame(300 * kMs, 0.2,
                            OdometryPose{std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0}),
               std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::mapping
