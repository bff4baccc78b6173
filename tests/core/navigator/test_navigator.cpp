// Navigator on tours rendered in sim's box room (test_world.hpp): replaying the taught frames
// walks the key images in order to the end and stops there; same frames give bit-identical
// commands; vanishing features hold the last command for hold_s of frame time, then stop with a
// reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "core/mapping/teacher.hpp"
#include "core/navigator/navigator.hpp"
#include "core/navigator/test_world.hpp"

namespace pepper::core::navigator {
namespace {

const CameraIntrinsics& camera() { return test::shared_tour().camera; }
const test::BoxWorld& world() { return test::shared_world(); }
const test::SharedTour& tour() { return test::shared_tour(); }

std::vector<StepResult> replay(const std::vector<Frame>& frames, const NavigatorOptions& o = {}) {
  Navigator nav(tour().map, o);
  std::vector<StepResult> out;
  for (const Frame& f : frames) out.push_back(nav.step(f));
  return out;
}

// Replays the tour's frames (stamps compressed by time_divisor, so the commands cover
// 1/time_divisor of the taught distance per frame) and records, for every segment left by a
// switch after the first, the distance commanded on it and its taught length (taught time x
// vnhv.teach_speed_m_s; the test tour's map keeps no distances).
struct SwitchGap {
  double driven_m;
  double taught_m;
};
struct SwitchRun {
  std::vector<SwitchGap> gaps;
  int by_distance = 0;  ///< frames with the "passed IN by travel (commands)" criterion bit
  int by_odometry = 0;  ///< frames with the "passed IN by travel (odometry)" criterion bit
};
// The test tour's map with each key image's taught pose as its odometry (exact odometry).
memory::VisualMemory map_with_taught_odometry() {
  memory::VisualMemory map = tour().map;
  for (memory::KeyImage& k : map.key_images) {
    const sim::Pose2D& p = tour().path.at(static_cast<size_t>(k.source_frame_index));
    k.odom = OdometryPose{p.x_m, p.y_m, p.yaw_rad};
  }
  return map;
}

// with_odometry: the map keeps each key image's taught pose as its odometry and every frame
// carries the taught path's pose (exact odometry).
SwitchRun replay_switch_gaps(const NavigatorOptions& o, int64_t time_divisor,
                             bool with_odometry = false) {
  Navigator nav(with_odometry ? map_with_taught_odometry() : tour().map, o);
  const auto& keys = tour().map.key_images;
  const int64_t t0 = tour().frames.front().t_ns;
  SwitchRun out;
  double driven_m = 0.0;
  bool started = false;
  Command last;
  int64_t last_t_ns = t0;
  int ip = -1, in = -1;
  for (const Frame& taught : tour().frames) {
    Frame f = taught;
    f.t_ns = t0 + (taught.t_ns - t0) / time_divisor;
    if (with_odometry) {
      const sim::Pose2D& p = tour().path.at(static_cast<size_t>(taught.index));
      f.odom = OdometryPose{p.x_m, p.y_m, p.yaw_rad};
    }
    if (!last.stop) driven_m += last.v_m_s * static_cast<double>(f.t_ns - last_t_ns) * 1e-9;
    const StepResult r = nav.step(f);
    if (r.telemetry.switch_criterion & localization::kCriterionPassedByDistance) ++out.by_distance;
    if (r.telemetry.switch_criterion & localization::kCriterionPassedByOdometry) ++out.by_odometry;
    if (r.telemetry.switched && started) {
      out.gaps.push_back({driven_m, static_cast<double>(keys[in].t_ns - keys[ip].t_ns) * 1e-9 *
                                        o.vnhv.teach_speed_m_s});
    }
    if (r.telemetry.switched) {
      started = true;
      driven_m = 0.0;
    }
    ip = r.telemetry.ip;
    in = r.telemetry.in;
    last = r.command;
    last_t_ns = f.t_ns;
  }
  return out;
}

TEST(Navigator, SameFramesGiveIdenticalCommands) {
  std::vector<Frame> frames(tour().frames.begin() + 50, tour().frames.begin() + 70);  // turn
  const auto a = replay(frames);
  const auto b = replay(frames);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].command.v_m_s, b[i].command.v_m_s) << i;
    EXPECT_EQ(a[i].command.omega_rad_s, b[i].command.omega_rad_s) << i;
    EXPECT_EQ(a[i].command.reason, b[i].command.reason) << i;
    EXPECT_EQ(a[i].telemetry.in, b[i].telemetry.in) << i;
    EXPECT_EQ(a[i].telemetry.n_points_next, b[i].telemetry.n_points_next) << i;
  }
}

// The hold mechanics, with the IBVS law (whose demand is undefined without features). The VNHV
// controller (the default) is checked at the end of the test.
TEST(Navigator, VanishingFeaturesHoldThenStopWithReason) {
  NavigatorOptions o;
  o.controller = ControllerKind::kIbvs;
  o.hold_s = 1.0;  // 5 frames at 5 Hz
  Navigator nav(tour().map, o);
  std::vector<Frame> frames(tour().frames.begin(), tour().frames.begin() + 10);
  Command last;
  for (const Frame& f : frames) last = nav.step(f).command;
  ASSERT_FALSE(last.stop);
  const int64_t t_last_good = frames.back().t_ns;
  // Twelve blank frames, 0.2 s apart, after the last good one.
  const auto blank_steps = [&](Navigator& n) {
    const cv::Mat blank(camera().height_px, camera().width_px, CV_8UC1, cv::Scalar(128));
    std::vector<StepResult> out;
    for (int i = 1; i <= 12; ++i) {
      Frame f;
      f.gray = blank;
      f.t_ns = t_last_good + i * 200'000'000LL;
      f.index = 100 + i;
      out.push_back(n.step(f));
    }
    return out;
  };
  const std::vector<StepResult> blind = blank_steps(nav);
  // Frames at +0.2 .. +1.0 s: held (identical command, state kHolding).
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(blind[i].telemetry.state, NavState::kHolding) << i;
    EXPECT_FALSE(blind[i].command.stop);
    EXPECT_EQ(blind[i].command.omega_rad_s, last.omega_rad_s);
    EXPECT_EQ(blind[i].command.v_m_s, last.v_m_s);
    EXPECT_EQ(blind[i].telemetry.hold_elapsed_ns, (i + 1) * 200'000'000LL);
  }
  // +1.2 s: stop, features lost; afterwards still stopped while relocalising on blank frames.
  for (int i = 5; i < 8; ++i) {
    EXPECT_TRUE(blind[i].command.stop) << i;
    EXPECT_EQ(blind[i].command.reason, StopReason::kFeaturesLost) << i;
    EXPECT_EQ(blind[i].telemetry.state, NavState::kLost) << i;
  }
  EXPECT_TRUE(blind[6].telemetry.localization_ran);
  // Features come back: relocalised, moving again.
  Frame back = tour().frames[12];
  back.t_ns = t_last_good + 2'600'000'000LL;
  const StepResult r = nav.step(back);
  EXPECT_TRUE(r.telemetry.localization_ran);
  EXPECT_EQ(r.telemetry.state, NavState::kNavigating);
  EXPECT_FALSE(r.command.stop);

  // VNHV: the same blank frames also end in a stop for lost features. Its deviation filter
  // predicts its last estimate for up to vnhv.filter.max_prediction_s after the last accepted
  // fix, and the hold follows, so the stop comes at the latest one frame after
  // max_prediction_s + hold_s (1 + 1 s: +2.2 s at 5 Hz). How early depends on when the last
  // fix before the blank frames was accepted: 2 blank frames of prediction (stop at +1.6 s)
  // before issue 22, 5 since (+2.2 s; also with the five-point RANSAC capped at 300 samples,
  // which is how the cap first "broke" this test when it asserted +1.6 s).
  NavigatorOptions v = o;
  v.controller = ControllerKind::kVnhv;
  Navigator vnav(tour().map, v);
  for (const Frame& f : frames) vnav.step(f);
  const std::vector<StepResult> vblind = blank_steps(vnav);
  const double bound_s = v.vnhv.filter.max_prediction_s + v.hold_s + 0.2;
  // vblind[i] is at +0.2 (i + 1) s.
  const auto stop_index = static_cast<size_t>(std::lround(bound_s / 0.2)) - 1;
  ASSERT_LT(stop_index, vblind.size());
  EXPECT_TRUE(vblind[stop_index].command.stop) << "no stop by +" << bound_s << " s";
  EXPECT_EQ(vblind[stop_index].command.reason, StopReason::kFeaturesLost);
  for (const StepResult& b : vblind) EXPECT_LE(std::abs(b.command.omega_rad_s), 0.5);
}

TEST(Navigator, StopsForGoodWhenASegmentIsOverdue) {
  // The robot makes no progress (the same view again and again, as when the end of a tour
  // cannot be recognised): no switch ever happens, so after the overdue time the navigator
  // stops and stays stopped even though it still sees its features.
  NavigatorOptions o;
  o.segment_overdue_factor = 0.5;  // the test tour's segments last several seconds
  o.segment_overdue_min_s = 3.0;
  Navigator nav(tour().map, o);
  const Frame& view = tour().frames[5];
  std::vector<StepResult> out;
  for (int i = 0; i < 40; ++i) {  // 8 s at 5 Hz
    Frame f = view;
    f.t_ns = view.t_ns + i * 200'000'000LL;
    f.index = i;
    out.push_back(nav.step(f));
  }
  ASSERT_EQ(out.front().telemetry.state, NavState::kNavigating);
  ASSERT_FALSE(out.front().command.stop);
  const localization::Segment first{out.front().telemetry.ip, out.front().telemetry.in, {}};
  const auto& keys = tour().map.key_images;
  const double taught_s = (keys[first.next].t_ns - keys[first.prev].t_ns) * 1e-9;
  const double allowed_s = std::max(3.0, 0.5 * taught_s);
  ASSERT_LT(allowed_s, 7.0) << "the test tour's first segment is too long for this test";
  int first_stop = -1;
  for (int i = 0; i < 40; ++i) {
    if (out[i].command.stop && first_stop < 0) first_stop = i;
    if (first_stop >= 0) {
      EXPECT_TRUE(out[i].command.stop) << i;
      EXPECT_EQ(out[i].command.reason, StopReason::kSegmentOverdue) << i;
      EXPECT_EQ(out[i].telemetry.state, NavState::kOverdue) << i;
    }
  }
  ASSERT_GE(first_stop, 0);
  for (int i = 0; i < first_stop; ++i) EXPECT_EQ(out[i].telemetry.in, first.next) << i;
  // The first stop comes with the first frame past the allowed time.
  EXPECT_NEAR(first_stop * 0.2, allowed_s, 0.2 + 1e-9);
  // reset() clears it: the same view navigates again.
  nav.reset();
  Frame f = view;
  f.t_ns = view.t_ns + 100 * 200'000'000LL;
  EXPECT_FALSE(nav.step(f).command.stop);
  // Off: never overdue.
  o.segment_overdue_factor = 0.0;
  Navigator never(tour().map, o);
  for (int i = 0; i < 40; ++i) {
    Frame g = view;
    g.t_ns = view.t_ns + i * 200'000'000LL;
    EXPECT_FALSE(never.step(g).command.stop) << i;
  }
}

// The final image fades: the taught frames up to the end (the ratio with the final image
// reaches about 1), but arrival_scale_ratio is set out of reach, then blank frames (nothing
// matches any more, as in a close-up of the furniture that ends a tour). Without odometry (map
// and frames) the navigator counts those frames as arrival (kArrivalFadeRatio) and stops with
// kTourComplete; with odometry the fade is not arrival, the odometry is: while it reads the
// robot 10 frames short of the end, the navigator drives the rest on odometry (dead reckoning)
// instead of stopping (at the end it is arrival on odometry).
TEST(Navigator, ArrivalWhenTheFinalImageFadesWithoutOdometry) {
  auto run = [](bool odometry) {
    NavigatorOptions o;
    o.controller = ControllerKind::kIbvs;  // the hold's timing below is the IBVS law's
    o.arrival_scale_ratio = 1.9;  // never reached: only the fade can complete the tour
    o.hold_s = 0.6;
    Navigator nav(odometry ? map_with_taught_odometry() : tour().map, o);
    std::vector<StepResult> out;
    for (const Frame& taught : tour().frames) {
      Frame f = taught;
      const sim::Pose2D& p = tour().path.at(static_cast<size_t>(taught.index));
      if (odometry) f.odom = OdometryPose{p.x_m, p.y_m, p.yaw_rad};
      out.push_back(nav.step(f));
    }
    const int final_in = static_cast<int>(tour().map.key_images.size()) - 1;
    EXPECT_EQ(out.back().telemetry.in, final_in);
    EXPECT_FALSE(out.back().command.stop);
    const cv::Mat blank(camera().height_px, camera().width_px, CV_8UC1, cv::Scalar(128));
    const Frame& short_of_end = tour().frames.at(tour().frames.size() - 11);
    const sim::Pose2D& there = tour().path.at(static_cast<size_t>(short_of_end.index));
    for (int i = 1; i <= 6; ++i) {
      Frame f;
      f.gray = blank;
      f.t_ns = tour().frames.back().t_ns + i * 200'000'000LL;
      f.index = 10'000 + i;
      if (odometry) f.odom = OdometryPose{there.x_m, there.y_m, there.yaw_rad};
      out.push_back(nav.step(f));
    }
    return std::vector<StepResult>(out.end() - 6, out.end());
  };
  const auto faded = run(false);
  // The consecutive-frame rule (switching.consecutive_frames) applies as for a measured ratio;
  // the first blank frame may still keep stale KLT tracks from the previous frame (measured:
  // 12 points), so the stop comes after n or n + 1 blank frames, and stays.
  const int n = localization::SwitcherOptions{}.consecutive_frames;
  for (int i = 0; i < n - 1; ++i) EXPECT_FALSE(faded[i].command.stop) << i;
  for (int i = n; i < 6; ++i) {
    EXPECT_TRUE(faded[i].command.stop) << i;
    EXPECT_EQ(faded[i].command.reason, StopReason::kTourComplete) << i;
  }
  const auto with_odometry = run(true);
  for (const StepResult& r : with_odometry) {
    EXPECT_NE(r.command.reason, StopReason::kTourComplete) << r.telemetry.frame_index;
  }
  // Vision sees nothing: the odometry drives the taught path's last 10 frames (dead
  // reckoning), and arrival will be the odometry's past the final pose.
  EXPECT_FALSE(with_odometry.back().command.stop);
  EXPECT_EQ(with_odometry.back().telemetry.state, NavState::kDeadReckoning);
}

TEST(Navigator, BlindSwitchesWaitUntilTheCommandsDroveTheSegment) {
  auto switch_gaps = [](double fraction) {
    NavigatorOptions o;
    o.min_scale_points = 100'000;
    o.arrival_min_scale_points = 100'000;
    o.min_scale_lines = 0;
    o.blind_switch_min_driven_fraction = fraction;
    o.vnhv.teach_speed_m_s = 0.1;
    return replay_switch_gaps(o, /*time_divisor=*/2).gaps;
  };
  const auto guarded = switch_gaps(0.6);
  ASSERT_GE(guarded.size(), 3u);
  for (const SwitchGap& g : guarded) EXPECT_GE(g.driven_m, 0.6 * g.taught_m - 1e-9);
  const auto free = switch_gaps(0.0);
  int sooner = 0;
  for (const SwitchGap& g : free) sooner += g.driven_m < 0.6 * g.taught_m ? 1 : 0;
  EXPECT_GT(sooner, 0);
}

// "Passed IN by travel" without odometry: with the scale ratio unknown on every frame, a segment
// is left once the commands drove twice its taught length (taught lengths made short here,
// 0.02 m/s x taught time, so that the rule has to act before the count rules do). With the
// odometry in the map and the frames, the commanded distance is never consulted (the odometry
// source of the rule decides).
TEST(Navigator, PassedByTravelUsesTheCommandsOnlyWithoutOdometry) {
  auto run = [](bool with_odometry) {
    NavigatorOptions o;
    o.min_scale_points = 100'000;  // no scale ratio, ever
    o.arrival_min_scale_points = 100'000;
    o.min_scale_lines = 0;
    o.blind_switch_min_driven_fraction = 0.0;
    o.vnhv.teach_speed_m_s = 0.02;
    return replay_switch_gaps(o, /*time_divisor=*/1, with_odometry);
  };
  const SwitchRun blind = run(false);
  ASSERT_GE(blind.gaps.size(), 3u);
  EXPECT_GT(blind.by_distance, 0);
  // The switch comes on the second frame past the mark (consecutive_frames 2): at most two
  // frames of 0.15 m/s x 0.2 s beyond 2 x the taught length.
  int late = 0;
  for (const SwitchGap& g : blind.gaps) {
    EXPECT_LE(g.driven_m, 2.0 * g.taught_m + 2 * 0.15 * 0.2 + 1e-9);
    late += g.driven_m > g.taught_m ? 1 : 0;
  }
  EXPECT_GT(late, 0) << "some segment should need the rule (driven past its taught length)";
  const SwitchRun odometry = run(true);
  EXPECT_EQ(odometry.by_distance, 0);
  EXPECT_GT(odometry.by_odometry, 0);
}

// "Passed IN by travel (odometry)" while the scale ratio is known: the estimate must be past IN
// by 2 sigmas along the robot. Here vision cannot switch (the guard wants IN's points at 1.9x
// their taught size), so every switch is the odometry's; before
// this rule took known ratios the replay stalled at the first IN.
TEST(Navigator, PassedByOdometryWithAKnownScaleNeedsTwoSigmasPastIn) {
  NavigatorOptions o;
  o.switching.min_next_scale_ratio = 1.9;
  Navigator nav(map_with_taught_odometry(), o);
  int switches = 0, known_ratio_frames = 0;
  for (const Frame& taught : tour().frames) {
    Frame f = taught;
    const sim::Pose2D& p = tour().path.at(static_cast<size_t>(taught.index));
    f.odom = OdometryPose{p.x_m, p.y_m, p.yaw_rad};
    const StepResult r = nav.step(f);
    const Telemetry& t = r.telemetry;
    switches += t.switched ? 1 : 0;
    if ((t.switch_criterion & localization::kCriterionPassedByOdometry) &&
        std::isfinite(t.next_scale_ratio)) {
      ++known_ratio_frames;
      EXPECT_GE(t.odom_past_next_m, 2.0 * t.odom_along_sigma_m) << "frame " << f.index;
    }
  }
  EXPECT_GE(switches, 3);
  EXPECT_GT(known_ratio_frames, 0);
}

// A map that keeps the distance driven during teach (KeyImage::travelled_m) gives the segments
// their metric length from it, whatever vnhv.teach_speed_m_s says; without it the navigator
// falls back to taught time x teach_speed_m_s. The tour was driven at 0.225 m/s: the same
// commands with the right speed and no distances, as with distances and a speed 20x too high.
TEST(Navigator, TaughtLengthsComeFromTheMapsTravelledDistance) {
  memory::VisualMemory with_distance = tour().map;
  const int64_t t0_ns = with_distance.key_images.front().t_ns;
  for (auto& k : with_distance.key_images) {
    k.travelled_m = 0.225 * static_cast<double>(k.t_ns - t0_ns) * 1e-9;
  }
  auto run = [&](const memory::VisualMemory& map, double teach_speed_m_s) {
    NavigatorOptions o;
    o.controller = ControllerKind::kVnhv;  // its lateral scale and the blind-switch guard use it
    o.vnhv.teach_speed_m_s = teach_speed_m_s;
    Navigator nav(map, o);
    std::vector<StepResult> out;
    for (const Frame& f : tour().frames) out.push_back(nav.step(f));
    return out;
  };
  const auto by_time = run(tour().map, 0.225);
  const auto by_distance = run(with_distance, 4.5);
  const auto by_wrong_time = run(tour().map, 4.5);  // so the comparison can fail
  ASSERT_EQ(by_time.size(), by_distance.size());
  int differ_wrong = 0, located = 0;
  for (size_t i = 0; i < by_time.size(); ++i) {
    EXPECT_NEAR(by_distance[i].command.omega_rad_s, by_time[i].command.omega_rad_s, 1e-9) << i;
    EXPECT_EQ(by_distance[i].command.v_m_s, by_time[i].command.v_m_s) << i;
    EXPECT_EQ(by_distance[i].telemetry.in, by_time[i].telemetry.in) << i;
    located += std::isfinite(by_time[i].telemetry.vnhv_lateral_m) ? 1 : 0;
    if (std::abs(by_wrong_time[i].command.omega_rad_s - by_time[i].command.omega_rad_s) > 1e-6)
      ++differ_wrong;
  }
  EXPECT_GT(located, 0);
  EXPECT_GT(differ_wrong, 0) << "the taught length should matter on this tour";
}

TEST(Navigator, NotLocalisedOnAnUnknownViewStops) {
  Navigator nav(tour().map);
  Frame f;
  f.gray = cv::Mat(camera().height_px, camera().width_px, CV_8UC1, cv::Scalar(90));
  const StepResult r = nav.step(f);
  EXPECT_TRUE(r.command.stop);
  EXPECT_EQ(r.command.reason, StopReason::kNotLocalized);
  EXPECT_EQ(nav.state(), NavState::kNotLocalized);
}

TEST(Navigator, StartsMidTourOnTheRightSegment) {
  // Start at frame 45 (mid first straight): the segment must contain the frame's position.
  Navigator nav(tour().map);
  const StepResult r = nav.step(tour().frames[45]);
  ASSERT_FALSE(r.command.stop) << to_string(r.command.reason);
  const auto& keys = tour().map.key_images;
  EXPECT_LE(keys[r.telemetry.ip].source_frame_index, 45 + 2);
  // IN is the key image after the frame, or (the paper's neighbour rule on a straight run: an
  // image behind the robot contains the whole current view and can share more) the one before
  // it; then INN is ahead and the switching rules advance within a few frames.
  const int in = r.telemetry.in;
  const bool in_ahead = keys[in].source_frame_index >= 45 - 2;
  const bool inn_ahead = in + 1 < static_cast<int>(keys.size()) &&
                         keys[in + 1].source_frame_index >= 45 - 2;
  EXPECT_TRUE(in_ahead || inn_ahead) << "IN " << in << " at frame " << keys[in].source_frame_index;
}

// Lines only / points only: the navigator matches nothing of the other kind, so neither its
// counts nor its control use it; VNHV, which reconstructs the segment from points, has no
// estimate with lines only and steers with the lines' IBVS law.
TEST(Navigator, SingleModalitySeesOnlyItsKind) {
  const std::vector<Frame> frames(tour().frames.begin() + 20, tour().frames.begin() + 70);
  for (const ControllerKind controller : {ControllerKind::kIbvs, ControllerKind::kVnhv}) {
    NavigatorOptions o;
    o.controller = controller;
    o.vnhv.teach_speed_m_s = 0.225;
    o.features = control::FeatureMode::kLinesOnly;
    int lines_used = 0, vnhv_estimates = 0;
    for (const StepResult& r : replay(frames, o)) {
      EXPECT_EQ(r.telemetry.n_points_next, 0);
      EXPECT_FALSE(r.telemetry.used_points);
      lines_used += r.telemetry.used_lines ? 1 : 0;
      vnhv_estimates += std::isfinite(r.telemetry.vnhv_lateral_m) ? 1 : 0;
      // No points, no segment model: 0 with VNHV (IBVS steers), -1 when IBVS is the controller.
      if (controller == ControllerKind::kIbvs) EXPECT_EQ(r.telemetry.vnhv_model_points, -1);
      else EXPECT_LE(r.telemetry.vnhv_model_points, 0);
    }
    EXPECT_GT(lines_used, 40) << to_string(controller);
    EXPECT_EQ(vnhv_estimates, 0) << to_string(controller);

    o.features = control::FeatureMode::kPointsOnly;
    int steered_by_points = 0;  // the points' IBVS law, or VNHV's estimate from the points
    for (const StepResult& r : replay(frames, o)) {
      EXPECT_EQ(r.telemetry.n_lines_next, 0);
      EXPECT_FALSE(r.telemetry.used_lines);
      steered_by_points +=
          r.telemetry.used_points || std::isfinite(r.telemetry.vnhv_lateral_m) ? 1 : 0;
    }
    EXPECT_GT(steered_by_points, 40) << to_string(controller);
  }
}

TEST(Navigator, ContractViolationsThrow) {
  Navigator nav(tour().map);
  EXPECT_THROW(nav.step(Frame{}), std::invalid_argument);
  Frame small;
  small.gray = cv::Mat(10, 10, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(nav.step(small), std::invalid_argument);
  nav.step(tour().frames[5]);
  EXPECT_THROW(nav.step(tour().frames[4]), std::invalid_argument);  // time goes backwards
  NavigatorOptions bad;
  bad.hold_s = -1;
  EXPECT_THROW(Navigator(tour().map, bad), std::invalid_argument);
}

struct ClosedLoopEnd {
  StepResult last;
  int switches = 0;
  int vnhv_frames = 0;  ///< frames with a VNHV deviation estimate
  double along_m = 0.0, lateral_m = 0.0, yaw_err_rad = 0.0;  ///< vs the taught final pose
  /// Largest distance to the taught path from the turn on (after 2.5 m: the tour's first leg,
  /// where the 10 cm start offset is driven out, is left out).
  double max_off_path_m = 0.0;
  double rms_off_path_m = 0.0;  ///< over the same frames
};

// Distance from (x, y) to the taught path's polyline.
double distance_to_tour_path_m(double x_m, double y_m) {
  const auto& path = tour().path;
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    const double ax = path[i].x_m, ay = path[i].y_m;
    const double bx = path[i + 1].x_m - ax, by = path[i + 1].y_m - ay;
    const double len2 = bx * bx + by * by;
    const double u = len2 > 0 ? std::clamp(((x_m - ax) * bx + (y_m - ay) * by) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, std::hypot(x_m - ax - u * bx, y_m - ay - u * by));
  }
  return best;
}

ClosedLoopEnd drive_closed_loop(const NavigatorOptions& options) {
  Navigator nav(tour().map, options);
  sim::Pose2D pose{-3.0, -2.0 + 0.10, -0.10};
  const double dt = 0.2;
  ClosedLoopEnd out;
  int last_in = 0;
  double travelled_m = 0.0, sum_sq = 0.0;
  int n_off = 0;
  for (int frames = 0; frames < 400; ++frames) {
    Frame f;
    f.gray = world().render(pose, camera());
    f.t_ns = static_cast<int64_t>(frames * dt * 1e9);
    f.index = frames;
    out.last = nav.step(f);
    const StepResult& r = out.last;
    if (r.command.stop) break;
    EXPECT_GE(r.telemetry.in, last_in);  // key-image indices only increase
    last_in = r.telemetry.in;
    out.switches += r.telemetry.switched ? 1 : 0;
    out.vnhv_frames += std::isfinite(r.telemetry.vnhv_lateral_m) ? 1 : 0;
    if (std::isfinite(r.telemetry.vnhv_lateral_m)) {  // an estimate needs a segment model
      EXPECT_GE(r.telemetry.vnhv_model_points,
                std::min(options.vnhv.pose.min_points, options.vnhv.straight_min_points));
    }
    EXPECT_TRUE(std::isfinite(r.command.omega_rad_s));
    const double w = r.command.omega_rad_s, v = r.command.v_m_s;  // exact unicycle arc
    if (std::abs(w) < 1e-9) {
      pose.x_m += v * dt * std::cos(pose.yaw_rad);
      pose.y_m += v * dt * std::sin(pose.yaw_rad);
    } else {
      pose.x_m += v / w * (std::sin(pose.yaw_rad + w * dt) - std::sin(pose.yaw_rad));
      pose.y_m -= v / w * (std::cos(pose.yaw_rad + w * dt) - std::cos(pose.yaw_rad));
    }
    pose.yaw_rad += w * dt;
    travelled_m += std::abs(v) * dt;
    if (travelled_m > 2.5) {
      const double d = distance_to_tour_path_m(pose.x_m, pose.y_m);
      out.max_off_path_m = std::max(out.max_off_path_m, d);
      sum_sq += d * d;
      ++n_off;
    }
  }
  out.rms_off_path_m = n_off > 0 ? std::sqrt(sum_sq / n_off) : 0.0;
  // Final pose against the taught end, in the end's heading frame.
  const sim::Pose2D end = tour().path.back();
  const double dx = pose.x_m - end.x_m, dy = pose.y_m - end.y_m;
  out.along_m = dx * std::cos(end.yaw_rad) + dy * std::sin(end.yaw_rad);
  out.lateral_m = -dx * std::sin(end.yaw_rad) + dy * std::cos(end.yaw_rad);
  out.yaw_err_rad = pose.yaw_rad - end.yaw_rad;
  return out;
}

// Closed loop: the robot starts 10 cm left of the taught start and 0.1 rad off; the commands
// move a simulated unicycle (camera 0.05 m ahead of the axis) in the same world at 5 Hz. It must
// walk the key images in order, reach the end and stop there, close to the taught final pose.
// Bounds: the measured final errors with margin; the centroid law corrects lateral offsets only
// weakly (docs/method/navigator.md). Measured on sim's images: along -2.4 cm, lateral 11.3 cm,
// yaw -0.025 rad (on the ray-casting renderer these tests used before: -3.9 cm, 6.5 cm,
// -0.015 rad). The lateral bound had been raised from 25 to 45 cm when KLT started at the
// lines' shift in turns (then 40 cm measured); it is back at 25 cm.
TEST(Navigator, ClosedLoopFollowsTheTourAndStopsAtTheEnd) {
  NavigatorOptions ibvs;
  ibvs.controller = ControllerKind::kIbvs;  // the IBVS law alone (VNHV is the default: below)
  const ClosedLoopEnd e = drive_closed_loop(ibvs);
  EXPECT_EQ(e.last.command.reason, StopReason::kTourComplete);
  EXPECT_EQ(e.last.telemetry.in, static_cast<int>(tour().map.key_images.size()) - 1);
  EXPECT_EQ(e.switches, static_cast<int>(tour().map.key_images.size()) - 2);
  EXPECT_EQ(e.vnhv_frames, 0);
  EXPECT_LT(std::abs(e.along_m), 0.30) << "along " << e.along_m;
  EXPECT_LT(std::abs(e.lateral_m), 0.25) << "lateral " << e.lateral_m;
  EXPECT_LT(std::abs(e.yaw_err_rad), 0.15);
}

// The same drive with the VNHV controller (teach speed of this tour: 0.225 m/s). It must use
// its own estimate, not only the IBVS fallback, and end closer laterally: measured on sim's
// images along -0.006 m, lateral -0.031 m, yaw 0.043 rad, 169 frames with an estimate (Kp 9,
// Kd 6; on the earlier ray-casting renderer -0.021, -0.014, 0.015, 162); the bounds leave margin.
TEST(Navigator, ClosedLoopWithVnhvFollowsTheTour) {
  NavigatorOptions o;
  o.controller = ControllerKind::kVnhv;
  o.vnhv.teach_speed_m_s = 0.225;
  // This tour has 7 key images, so its segments include the turn; the default hands segments
  // turning > 0.1 rad to IBVS, or to their arcs (next test). The chord law is tested here.
  o.vnhv.max_segment_turn_rad = 10.0;
  const ClosedLoopEnd e = drive_closed_loop(o);
  EXPECT_EQ(e.last.command.reason, StopReason::kTourComplete);
  EXPECT_EQ(e.last.telemetry.in, static_cast<int>(tour().map.key_images.size()) - 1);
  EXPECT_EQ(e.switches, static_cast<int>(tour().map.key_images.size()) - 2);
  EXPECT_GT(e.vnhv_frames, 100) << "VNHV rarely had an estimate";
  EXPECT_LT(std::abs(e.along_m), 0.30) << "along " << e.along_m;
  EXPECT_LT(std::abs(e.lateral_m), 0.15) << "lateral " << e.lateral_m;
  EXPECT_LT(std::abs(e.yaw_err_rad), 0.15);
}

// The default VNHV (VnhvOptions::max_arc_turn_rad = 1, Kp 9, Kd 6): straight segments on their
// chord, the turning ones on their taught arc, curvature fed forward. Judged on the distance to
// the taught path from the turn on (the evaluation's measure) against the product's targets
// (lateral RMS <= 5 cm, max <= 15 cm; README "Closed-loop evaluation"), and on the final pose.
// Measured from this start: RMS 2.49 cm, max 5.07 cm, end lateral -1.3 cm, yaw 0.014 rad.
// Whether the arcs beat IBVS on the turning segments (max_arc_turn_rad = 0) is not decided on
// this 5 Hz, 4.5 cm-per-frame tour: the test used to assert it from this one start (1.80 against
// 1.91 cm RMS), but from five starts (10 cm left / 0.1 rad right as here, 10 cm right / 0.1 rad
// left, 5 cm / 0, 0 / -0.05 rad, 15 cm / 0.05 rad) the two tie on average (1.83 and 1.83 cm) on
// the ray-casting renderer these tests used before, and the arcs lose on sim's images (2.51
// against 2.13 cm; from this start 2.49 against 1.84), images that differ from the earlier ones
// by 0.02 grey levels on average. The arcs are the default on the mock-robot evaluations'
// evidence (docs/method/control.md "Turns"); the [ measured ] line prints both variants.
TEST(Navigator, ClosedLoopWithVnhvArcsFollowsTheTour) {
  NavigatorOptions o;
  o.controller = ControllerKind::kVnhv;
  o.vnhv.teach_speed_m_s = 0.225;
  o.vnhv.max_arc_turn_rad = 1.0;
  o.vnhv.kp_1_m2 = 9.0;
  o.vnhv.kd_1_m = 6.0;
  const ClosedLoopEnd e = drive_closed_loop(o);
  o.vnhv.max_arc_turn_rad = 0.0;
  const ClosedLoopEnd ibvs_turns = drive_closed_loop(o);
  EXPECT_EQ(e.last.command.reason, StopReason::kTourComplete);
  EXPECT_EQ(e.last.telemetry.in, static_cast<int>(tour().map.key_images.size()) - 1);
  EXPECT_GT(e.vnhv_frames, 100) << "VNHV rarely had an estimate";
  EXPECT_LT(std::abs(e.along_m), 0.30) << "along " << e.along_m;
  EXPECT_LT(std::abs(e.lateral_m), 0.05) << "lateral " << e.lateral_m;
  EXPECT_LT(std::abs(e.yaw_err_rad), 0.05);
  std::cout << "[ measured ] arcs: end lateral " << e.lateral_m << " m, max off path "
            << e.max_off_path_m << " m, rms " << e.rms_off_path_m << " m; IBVS on the turns: "
            << ibvs_turns.lateral_m << ", " << ibvs_turns.max_off_path_m << ", "
            << ibvs_turns.rms_off_path_m << "\n";
  EXPECT_LE(e.rms_off_path_m, 0.05) << "over the product's lateral RMS target";
  EXPECT_LE(e.max_off_path_m, 0.15) << "over the product's lateral maximum target";
  EXPECT_EQ(ibvs_turns.last.command.reason, StopReason::kTourComplete);
}

}  // namespace
}  // namespace pepper::core::navigator
