// The teach drive's distance from commanded speeds (core/mapping/drive_odometer.hpp).
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

}  // namespace
}  // namespace pepper::core::mapping
