// A tour taught by hand, as the teach UI's keyboard drive does it (drive intents, turns on the
// spot), replayed with the shipped navigator on the mock robot (issue 30: "the in-place turns of
// a hand-driven teach are followed, not cut"). Ground truth: the mock robot's base pose.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <filesystem>
#include <optional>

#include "core/memory/visual_memory.hpp"
#include "session/replay_session.hpp"
#include "session/robot_connection.hpp"
#include "session/session_link.hpp"
#include "session/teach_session.hpp"
#include "sim/mock_robot.hpp"

namespace pepper::app {
namespace {

namespace fs = std::filesystem;

const std::string kWorld = std::string("mock:") + PEPPER_SOURCE_DIR + "/worlds/robotics_room.yaml";

fs::path fresh_dir(const std::string& name) {
  auto p = fs::temp_directory_path() / ("pepper_hand_taught_" + name);
  fs::remove_all(p);
  return p;
}

naoqi_bridge::CameraRequest qvga() {
  naoqi_bridge::CameraRequest r;
  r.width_px = 320;
  r.height_px = 240;
  return r;
}

double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

/// The operator's keyboard: drive straight for a distance, turn on the spot by an angle, in
/// turn; then finish. Each leg is judged on the robot's ground truth (the operator's eyes).
class HandDrive {
 public:
  struct Leg {
    double distance_m = 0.0;  ///< > 0: drive straight this far
    double turn_rad = 0.0;    ///< != 0: turn on the spot by this angle
  };
  HandDrive(const sim::MockRobot& robot, std::vector<Leg> legs)
      : robot_(robot), legs_(std::move(legs)) {}

  /// The session drains the intent queue on every frame: one intent, then "nothing more".
  std::optional<teach_ui::Intent> next() {
    sent_ = !sent_;
    if (!sent_) return std::nullopt;
    const sim::Pose2D p = robot_.ground_truth().base;
    if (!leg_start_) leg_start_ = p;
    while (leg_ < legs_.size() && leg_done(p)) {
      ++leg_;
      leg_start_ = p;
    }
    teach_ui::Intent i;
    if (leg_ >= legs_.size()) {
      i.kind = finished_ ? teach_ui::IntentKind::kDriveReleased : teach_ui::IntentKind::kFinishTeach;
      finished_ = true;
      return i;
    }
    const Leg& l = legs_[leg_];
    i.kind = teach_ui::IntentKind::kDrive;
    if (l.distance_m > 0.0) {
      i.v_m_s = 0.2;
    } else {
      // Slow down near the end of the turn, as an operator does.
      const double left = std::abs(l.turn_rad) - std::abs(wrap(p.yaw_rad - leg_start_->yaw_rad));
      i.omega_rad_s = std::copysign(left > 0.2 ? 0.4 : 0.15, l.turn_rad);
    }
    return i;
  }

 private:
  bool leg_done(const sim::Pose2D& p) const {
    const Leg& l = legs_[leg_];
    if (l.distance_m > 0.0) {
      return std::hypot(p.x_m - leg_start_->x_m, p.y_m - leg_start_->y_m) >= l.distance_m;
    }
    return std::abs(wrap(p.yaw_rad - leg_start_->yaw_rad)) >= std::abs(l.turn_rad) - 0.01;
  }

  const sim::MockRobot& robot_;
  std::vector<Leg> legs_;
  size_t leg_ = 0;
  std::optional<sim::Pose2D> leg_start_;
  bool finished_ = false;
  bool sent_ = false;
};

TEST(HandTaughtTour, TurnsOnTheSpotAreFollowedToTheEnd) {
  // Teach: 5 m east, a left turn on the spot, 3.2 m north, another, 1.5 m west (robotics_room,
  // around its central tables).
  RobotConnection teach_robot = open_robot(kWorld, {});
  TeachSessionOptions t;
  t.map_dir = fresh_dir("map");
  t.camera = qvga();
  t.max_frames = 3000;  // a broken drive ends anyway
  SessionLink teach_link(nullptr, nullptr);
  HandDrive drive(*teach_robot.mock, {{5.0, 0.0},
                                      {0.0, M_PI / 2},
                                      {3.2, 0.0},
                                      {0.0, M_PI / 2},
                                      {1.5, 0.0}});
  teach_link.set_intent_source([&] { return drive.next(); });
  const TeachResult taught = run_teach_session(teach_robot, t, teach_link);
  ASSERT_TRUE(taught.ok()) << taught.outcome << ": " << taught.error;
  const sim::Pose2D taught_end = teach_robot.mock->ground_truth().base;
  ASSERT_GT(taught_end.y_m, 4.5) << "the drive script did not get round";

  // Replay from the taught start with the defaults.
  RobotConnection replay_robot = open_robot(kWorld, {});
  ReplaySessionOptions r;
  r.camera = qvga();
  r.max_frames = 1500;
  r.give_up_lost_s = 10.0;
  r.give_up_not_localised_s = 10.0;
  SessionLink replay_link(nullptr, nullptr);
  const ReplayResult result =
      run_replay_session(replay_robot, core::memory::load_map(t.map_dir), r, replay_link);
  const sim::Pose2D end = replay_robot.mock->ground_truth().base;
  const double error_m = std::hypot(end.x_m - taught_end.x_m, end.y_m - taught_end.y_m);
  const double heading_error_rad = std::abs(wrap(end.yaw_rad - taught_end.yaw_rad));
  RecordProperty("end_error_mm", static_cast<int>(std::lround(1000 * error_m)));
  RecordProperty("end_heading_error_mrad", static_cast<int>(std::lround(1000 * heading_error_rad)));
  EXPECT_EQ(result.outcome, "tour_complete") << result.detail;
  EXPECT_LT(error_m, 0.15) << "replay ended at (" << end.x_m << ", " << end.y_m << "), taught end ("
                           << taught_end.x_m << ", " << taught_end.y_m << ")";
  EXPECT_LT(heading_error_rad, 0.1);
  // The replay's own verdict (no ground truth) agrees: arrived, with an estimated offset near
  // the true one.
  EXPECT_EQ(result.arrival.verdict, "arrived") << result.detail;
  EXPECT_NE(result.arrival.source, "none");
  EXPECT_NEAR(result.arrival.offset_m, error_m, 0.1) << result.detail;
  RecordProperty("estimated_end_offset_mm", static_cast<int>(std::lround(1000 * result.arrival.offset_m)));
}

TEST(ArrivalVerdict, WithinBothTolerancesIsArrivedElseNotAlignedOrUnknown) {
  core::navigator::Telemetry t;
  EXPECT_EQ(judge_arrival(t, 0.15, 0.1).verdict, "unknown");  // no estimate
  t.arrival_source = core::navigator::Telemetry::ArrivalSource::kVision;
  t.arrival_along_m = -0.09;
  t.arrival_lateral_m = 0.12;
  t.arrival_heading_rad = 0.05;
  Arrival a = judge_arrival(t, 0.16, 0.1);
  EXPECT_EQ(a.verdict, "arrived");
  EXPECT_EQ(a.source, "vision");
  EXPECT_NEAR(a.offset_m, 0.15, 1e-12);
  EXPECT_EQ(judge_arrival(t, 0.14, 0.1).verdict, "not_aligned");  // 15 cm off
  t.arrival_heading_rad = -0.2;
  EXPECT_EQ(judge_arrival(t, 0.16, 0.1).verdict, "not_aligned");  // turned too far
  t.arrival_source = core::navigator::Telemetry::ArrivalSource::kOdometry;
  t.arrival_heading_rad = 0.0;
  EXPECT_EQ(judge_arrival(t, 0.16, 0.1).source, "odometry");
  t.arrival_along_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(judge_arrival(t, 0.16, 0.1).verdict, "unknown");
}

}  // namespace
}  // namespace pepper::app
