// Closed-loop evaluation on the mock robot (pepper_app/src/evaluation): a short tour with one
// turn in a small shipped test world (data/small_room.yaml) is taught at QVGA and replayed from
// two perturbed starts; the replays must converge to the taught path and stop at its end.
// Also: disturbed worlds (moved furniture keeps the path clear, a person is added, a crowd
// crosses the path, light factor), and the JSON / table outputs.
#include "evaluation/closed_loop.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <memory>

#include "evaluation/disturbance.hpp"
#include "evaluation/metrics.hpp"
#include "evaluation/output.hpp"
#include "sim/mock_robot.hpp"
#include "sim/renderer.hpp"
#include "sim/world.hpp"
#include "support/temp_dir.hpp"

namespace pepper::app::evaluation {
namespace {

std::shared_ptr<const sim::World> small_room() {
  static const auto w = std::make_shared<const sim::World>(sim::load_world(
      std::string(PEPPER_SOURCE_DIR) + "/tests/app/evaluation/data/small_room.yaml"));
  return w;
}

EvaluationOptions qvga_options() {
  EvaluationOptions o;
  o.width_px = 320;
  o.height_px = 240;
  o.starts = 2;
  o.seed = 3;
  return o;
}

// Bounds: the run must converge and end where the tour ends (final position within 0.3 m), and
// stay near the taught path once converged. Max <= 15 cm is the product's target. RMS <= 8 cm
// is the target (5 cm) plus margin: with the default VNHV controller through the shared replay
// loop this QVGA tour measured 4.6 / 9.2 cm and 5.5 / 10.6 cm (RMS / max, runs 1 and 2; `pepper_app
// evaluate --world tests/app/evaluation/data/small_room.yaml --starts 2 --seed 3 --size 320x240`).
// The targets at VGA on the shipped worlds are figures the evaluation reports (docs/evaluation.md).
std::shared_ptr<const sim::World> test_world(const std::string& name) {
  return std::make_shared<const sim::World>(sim::load_world(
      std::string(PEPPER_SOURCE_DIR) + "/tests/app/evaluation/data/" + name + ".yaml"));
}

// Issue 29: turns facing a blank wall 1 m away (data/blank_turn_90.yaml, blank_turn_180.yaml:
// small_room with its east wall bare), taught and replayed on the mock robot with its drifting
// wheel odometry through the product's sessions. The base must never stop before the end of the
// tour, vision must drop out in the turn (frames dead reckoned) and come back (re-acquired),
// the heading from lines must correct the odometry on some frames, and the tour must complete. Without odometry's help (dead_reckoning_max_lateral_sigma_m ~ 0) the same runs
// are lost in the turn: the worlds really are blind there.
void expect_through_blank_turn(const std::string& world_name) {
  const test::TempDir tmp("blank");
  EvaluationOptions o = qvga_options();
  o.map_dir = tmp.path() / "map";
  const auto world = test_world(world_name);
  const TeachResult teach = teach_tour(world, o);
  const Evaluation ev = evaluate(teach, world, o);
  for (const RunResult& r : ev.runs) {
    SCOPED_TRACE(world_name + " run " + std::to_string(r.index) + ": " + r.outcome + " " +
                 r.detail);
    EXPECT_EQ(r.outcome, "complete");
    EXPECT_EQ(r.lost_frames, 0) << "the base stopped before the end of the tour";
    EXPECT_GT(r.dead_reckoning_frames, 0);
    EXPECT_GE(r.reacquisitions.size(), 1u);
    // Around the blind frames the view keeps the skirting board and the tiles' edges and few
    // points: the heading from lines corrects the odometry there (measured: 155-176 of ~700
    // frames in blank_turn_90).
    EXPECT_GT(r.line_heading_frames, 0);
    EXPECT_LE(r.lateral_max_m, 0.15);
  }
}

TEST(ClosedLoop, ThroughATurnFacingABlankWall90) { expect_through_blank_turn("blank_turn_90"); }
TEST(ClosedLoop, ThroughATurnFacingABlankWall180) { expect_through_blank_turn("blank_turn_180"); }

TEST(ClosedLoop, ShortTourWithOneTurnConvergesFromPerturbedStarts) {
  const test::TempDir tmp("eval");
  EvaluationOptions o = qvga_options();
  o.map_dir = tmp.path() / "map";
  const TeachResult teach = teach_tour(small_room(), o);
  ASSERT_GE(teach.map.key_images.size(), 3u);
  EXPECT_NEAR(teach.length_m, 5.2, 0.4);  // 2.8 m + 2.6 m, corner cut by the pure pursuit
  // The map keeps the distance commanded during teach: the drive's length, give or take the
  // base's lag behind its commands.
  EXPECT_EQ(teach.map.key_images.front().travelled_m, 0.0);
  EXPECT_NEAR(teach.map.key_images.back().travelled_m, teach.length_m, 0.05 * teach.length_m);
  const Evaluation ev = evaluate(teach, small_room(), o);
  ASSERT_EQ(ev.runs.size(), 2u);
  for (const RunResult& r : ev.runs) {
    SCOPED_TRACE("run " + std::to_string(r.index) + ": " + r.outcome + " " + r.detail);
    // The starts really are perturbed (not the taught start itself).
    EXPECT_GT(std::abs(r.start_lateral_m) + std::abs(r.start_yaw_rad), 0.02);
    EXPECT_TRUE(r.tour_complete);
    EXPECT_TRUE(r.success);
    EXPECT_EQ(r.outcome, "complete");
    EXPECT_LE(r.lateral_rms_m, 0.08);
    EXPECT_LE(r.lateral_max_m, 0.15);
    EXPECT_LE(r.final_error_m, 0.3);
    EXPECT_GT(r.travelled_m, 4.0);
    for (const RunSample& s : r.samples) ASSERT_TRUE(std::isfinite(s.omega_rad_s));
  }
  EXPECT_EQ(ev.summary.success_rate, 1.0);

  // Re-running one start alone (--run 2) replays exactly that start: same pose, same result.
  EvaluationOptions only_second = o;
  only_second.only_runs = {2};
  only_second.trace_dir = tmp.path() / "trace";
  const Evaluation again = evaluate(teach, small_room(), only_second);
  // Its trace is named by world, modality, disturbances and run; one JSON line per frame after
  // the key-image header.
  const auto trace = tmp.path() / "trace" / (teach.world_name + "_lines+points_none_run2.jsonl");
  std::ifstream trace_in(trace);
  ASSERT_TRUE(trace_in) << trace;
  int trace_lines = 0;
  std::string header;
  for (std::string line; std::getline(trace_in, line);) {
    if (trace_lines++ == 0) header = line;
  }
  EXPECT_GT(trace_lines, 10);
  // The header: each key image's taught ground-truth pose, yaw included (the teach's truth).
  const nlohmann::json keys = nlohmann::json::parse(header).at("taught_key_images");
  ASSERT_EQ(keys.size(), teach.key_m.size());
  ASSERT_EQ(teach.key_yaw_rad.size(), teach.key_m.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    EXPECT_DOUBLE_EQ(keys[i].at("x_m").get<double>(), teach.key_m[i].x());
    EXPECT_DOUBLE_EQ(keys[i].at("yaw_rad").get<double>(), teach.key_yaw_rad[i]);
  }
  // The small room's tour turns: the taught yaws are not all the start's.
  EXPECT_GT(std::abs(std::remainder(teach.key_yaw_rad.back() - teach.key_yaw_rad.front(),
                                    2.0 * M_PI)),
            0.1);
  ASSERT_EQ(again.runs.size(), 1u);
  EXPECT_EQ(again.runs[0].index, ev.runs[1].index);
  EXPECT_DOUBLE_EQ(again.runs[0].start_x_m, ev.runs[1].start_x_m);
  EXPECT_DOUBLE_EQ(again.runs[0].start_yaw_rad, ev.runs[1].start_yaw_rad);
  EXPECT_DOUBLE_EQ(again.runs[0].lateral_rms_m, ev.runs[1].lateral_rms_m);
}

// Issue 26: the same short tour replayed at the two ends of the light range the evaluation
// covers, x0.6 and x1.4 (the light disturbance spans [0.6, 1.4] over the runs: 2 starts take
// its two ends), with the world's window change on top. Measured (`pepper_app evaluate --world
// tests/app/evaluation/data/small_room.yaml --starts 2 --seed 3 --size 320x240 --disturbance
// light`): x0.6 3.5 / 6.6 cm, x1.4 3.8 / 6.9 cm (lateral RMS / max). On raw grey levels (the
// same command with --set features.klt.normalise_window_frac=0): x0.6 4.0 / 11.1 cm, x1.4 7.6 /
// 16.1 cm, over the 15 cm bound.
TEST(ClosedLoop, ShortTourUnderTheLightRangesEnds) {
  const test::TempDir tmp("eval_light");
  EvaluationOptions o = qvga_options();
  o.map_dir = tmp.path() / "map";
  o.disturbances = {Disturbance::kLight};
  const TeachResult teach = teach_tour(small_room(), o);
  const Evaluation ev = evaluate(teach, small_room(), o);
  ASSERT_EQ(ev.runs.size(), 2u);
  EXPECT_DOUBLE_EQ(ev.runs[0].light_factor, 0.6);
  EXPECT_DOUBLE_EQ(ev.runs[1].light_factor, 1.4);
  for (const RunResult& r : ev.runs) {
    SCOPED_TRACE("run " + std::to_string(r.index) + " light x" + std::to_string(r.light_factor) +
                 ": " + r.outcome + " " + r.detail);
    std::printf("[ measured ] light x%.1f: %s, lateral RMS %.1f cm, max %.1f cm, final %.1f cm\n",
                r.light_factor, r.outcome.c_str(), 100 * r.lateral_rms_m, 100 * r.lateral_max_m,
                100 * r.final_error_m);
    EXPECT_EQ(r.outcome, "complete");
    EXPECT_LE(r.lateral_rms_m, 0.08);  // the bounds of the unchanged-light test above
    EXPECT_LE(r.lateral_max_m, 0.15);
    EXPECT_LE(r.final_error_m, 0.3);
  }
}

TEST(ClosedLoop, OnlyRunsMustBeAmongTheStarts) {
  EvaluationOptions o = qvga_options();
  o.only_runs = {3};
  const auto errors = o.validate();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("run 3"), std::string::npos);
  o.only_runs = {1, 2};
  EXPECT_TRUE(o.validate().empty());
}

TEST(Disturbances, MovedFurnitureKeepsTheTaughtPathClear) {
  const auto& w = small_room();
  const std::vector<Eigen::Vector2d> path = w->scenario.waypoints_m;
  DisturbanceOptions o;
  o.furniture_shift_m = 0.6;  // large moves: the clearance rule must hold some back
  const DisturbedWorld d = make_disturbed_world(w, {Disturbance::kFurniture}, o, path, 5);
  ASSERT_NE(d.world, w);
  EXPECT_EQ(d.world->boxes.size(), w->boxes.size());
  // Some box moved.
  bool moved = false;
  for (size_t i = 0; i < w->boxes.size(); ++i) {
    moved |= (d.world->boxes[i].center_m - w->boxes[i].center_m).norm() > 0.05;
  }
  EXPECT_TRUE(moved);
  // Along the taught path (every 5 cm), the robot's 0.3 m disc touches nothing.
  const Polyline pl(path);
  for (double s = 0.0; s <= pl.length_m(); s += 0.05) {
    EXPECT_FALSE(d.world->collision(pl.at(s), 0.3, 0.0)) << "at s = " << s;
  }
  // Same seed, same world.
  const DisturbedWorld d2 = make_disturbed_world(w, {Disturbance::kFurniture}, o, path, 5);
  for (size_t i = 0; i < w->boxes.size(); ++i) {
    EXPECT_EQ(d.world->boxes[i].center_m, d2.world->boxes[i].center_m);
  }
}

TEST(Disturbances, DefaultLightSpansTheTargetRangeOverTheRunsWithTheWorldsWindowChange) {
  const auto& w = small_room();
  const DisturbedWorld d =
      make_disturbed_world(w, {Disturbance::kLight}, {}, w->scenario.waypoints_m, 1, 5);
  ASSERT_EQ(d.run_light_factors.size(), 5u);
  const double expected[] = {0.6, 0.8, 1.0, 1.2, 1.4};
  const sim::LightingCondition& teach = w->light("teach");
  const double windows_change = w->light("replay").windows / teach.windows;
  for (int k = 0; k < 5; ++k) {
    EXPECT_NEAR(d.light_factor_of_run(k), expected[k], 1e-12) << "run " << k;
    const sim::LightingCondition& l = d.world->light(d.lighting_of_run(k));
    EXPECT_NEAR(l.ambient, expected[k] * teach.ambient, 1e-12);
    EXPECT_NEAR(l.lamps, expected[k] * teach.lamps, 1e-12);
    EXPECT_NEAR(l.windows, expected[k] * teach.windows * windows_change, 1e-12);
  }
  // One run takes the dark end; no light disturbance: factor 0 and the teach lighting.
  const DisturbedWorld one =
      make_disturbed_world(w, {Disturbance::kLight}, {}, w->scenario.waypoints_m, 1, 1);
  EXPECT_NEAR(one.light_factor_of_run(0), 0.6, 1e-12);
  const DisturbedWorld none = make_disturbed_world(w, {}, {}, w->scenario.waypoints_m, 1, 5);
  EXPECT_EQ(none.light_factor_of_run(3), 0.0);
  EXPECT_EQ(none.lighting_of_run(3), "teach");
}

TEST(Disturbances, PersonWalksBesideThePathAndLightScales) {
  const auto& w = small_room();
  DisturbanceOptions o;
  o.light_factor = 0.6;
  const DisturbedWorld d = make_disturbed_world(w, {Disturbance::kPerson, Disturbance::kLight}, o,
                                                w->scenario.waypoints_m, 1);
  ASSERT_EQ(d.world->people.size(), w->people.size() + 1);
  EXPECT_EQ(d.lighting, "evaluation");
  EXPECT_NEAR(d.world->light("evaluation").ambient, 0.6 * w->light("teach").ambient, 1e-12);
  // The person never comes within the robot's disc of the path at any time.
  const Polyline pl(w->scenario.waypoints_m);
  const sim::MovingObstacle& p = d.world->people.back();
  for (double t = 0.0; t < 20.0; t += 0.25) {
    const Eigen::Vector3d pose = p.pose_at(t);
    EXPECT_GT(pl.project(pose.head<2>()).distance_m, 0.3 + 0.27) << "t = " << t;
  }
  o.light_factor = 5.0;
  EXPECT_THROW(make_disturbed_world(w, {Disturbance::kLight}, o, w->scenario.waypoints_m, 1),
               std::invalid_argument);
  EXPECT_EQ(parse_disturbance("drops"), Disturbance::kDrops);
  EXPECT_THROW(parse_disturbance("rain"), std::invalid_argument);
}

// room_corridor_room: the middle of the tour is a 2 m corridor with a bench and a bin, too
// narrow for a person beside the robot, so the person walks in one of the rooms instead; the
// walk stays clear of the path and of the world.
TEST(Disturbances, PersonFindsRoomWhereTheMiddleIsANarrowCorridor) {
  const auto w = std::make_shared<const sim::World>(
      sim::load_world(std::string(PEPPER_SOURCE_DIR) + "/worlds/room_corridor_room.yaml"));
  const DisturbedWorld d =
      make_disturbed_world(w, {Disturbance::kPerson}, {}, w->scenario.waypoints_m, 1);
  ASSERT_EQ(d.world->people.size(), w->people.size() + 1);
  ASSERT_FALSE(d.notes.empty());
  EXPECT_NE(d.notes.back().find("person walking"), std::string::npos) << d.notes.back();
  const Polyline pl(w->scenario.waypoints_m);
  const sim::MovingObstacle& p = d.world->people.back();
  for (double t = 0.0; t < 30.0; t += 0.25) {
    const Eigen::Vector3d pose = p.pose_at(t);
    EXPECT_GT(pl.project(pose.head<2>()).distance_m, 0.3 + 0.27) << "t = " << t;
    EXPECT_FALSE(w->collision(pose.head<2>(), 0.25, 0.0)) << "t = " << t;
  }
}

// The crowd (DisturbanceOptions::crowd_*) on the two shipped worlds of the ceiling comparison
// (docs/method/ceiling.md): every person's walk crosses the taught path; the crossings are
// spread over the tour; the taught path stays passable at every time because the people step
// aside (and would not be passable if they walked through: they really cross it); the forward
// camera of a robot driving the taught path at the teach speed sees them on many frames; one
// seed gives one crowd and another seed another.
struct CrowdCase {
  const char* world;
  size_t min_people;  // room_corridor_room's 2 m corridor leaves less room than the lab
};

class CrowdDisturbance : public ::testing::TestWithParam<CrowdCase> {};

TEST_P(CrowdDisturbance, CrossesThePathInViewAndStepsAsideForTheRobot) {
  const auto w = std::make_shared<const sim::World>(sim::load_world(
      std::string(PEPPER_SOURCE_DIR) + "/worlds/" + GetParam().world + ".yaml"));
  const std::vector<Eigen::Vector2d>& path = w->scenario.waypoints_m;
  const DisturbanceOptions o;
  const DisturbedWorld d = make_disturbed_world(w, {Disturbance::kCrowd}, o, path, 1);
  const size_t added = d.world->people.size() - w->people.size();
  std::string notes;
  for (const auto& n : d.notes) notes += n + "\n";
  EXPECT_LE(added, static_cast<size_t>(o.crowd_people)) << notes;
  EXPECT_GE(added, GetParam().min_people) << notes;
  const Polyline pl(path);
  // Crossings: a walk's leg whose ends lie on both sides of the path, at the foot point's s.
  std::vector<double> crossing_s;
  for (size_t k = w->people.size(); k < d.world->people.size(); ++k) {
    const sim::MovingObstacle& p = d.world->people[k];
    EXPECT_GT(p.keep_clear_m, 0.3 + 0.27) << p.what;
    int crossings = 0;
    for (size_t i = 1; i < p.path_m.size(); ++i) {
      const PathProjection a = pl.project(p.path_m[i - 1]), b = pl.project(p.path_m[i]);
      if (a.lateral_m * b.lateral_m < 0.0) {
        ++crossings;
        crossing_s.push_back(pl.project(0.5 * (p.path_m[i - 1] + p.path_m[i])).s_m);
      }
    }
    EXPECT_EQ(crossings, o.crowd_crossings) << p.what << "\n" << notes;
  }
  ASSERT_FALSE(crossing_s.empty());
  const auto [lo, hi] = std::minmax_element(crossing_s.begin(), crossing_s.end());
  EXPECT_GT(*hi - *lo, 0.5 * pl.length_m()) << "crossings bunched in one place";

  // Passable: the robot's 0.3 m disc anywhere on the path, at any time, touches no one, because
  // they step aside; the same walks without stepping aside do hit it somewhere.
  auto walkers = std::make_shared<sim::World>(*d.world);
  for (auto& p : walkers->people) p.keep_clear_m = 0.0;
  bool kinematic_hit = false;
  for (double s = 0.0; s <= pl.length_m(); s += 0.1) {
    for (double t = 0.0; t <= 60.0; t += 0.5) {
      const auto hit = d.world->collision(pl.at(s), 0.3, t);
      ASSERT_FALSE(hit) << "s " << s << " t " << t << ": " << *hit;
      kinematic_hit = kinematic_hit || walkers->collision(pl.at(s), 0.3, t);
    }
  }
  EXPECT_TRUE(kinematic_hit) << "the walks never reach the robot's lane";

  // Seen: the forward camera (head at pitch 0) of a robot on the taught path at the teach speed,
  // every 0.5 s; a frame "sees the crowd" when >= 3 % of its pixels differ by more than 10 grey
  // levels from the same view without the crowd (renders without noise).
  sim::RenderOptions ro;
  ro.noise_sigma_grey = 0.0;
  ro.motion_blur_exposure_s = 0.0;
  sim::Renderer renderer(ro);
  const sim::CameraMount mount;
  const double speed = w->scenario.teach_speed_m_s;
  int frames = 0, seen = 0;
  for (double t = 0.0; t * speed <= pl.length_m(); t += 0.5, ++frames) {
    const double s = t * speed;
    const Eigen::Vector2d p = pl.at(s);
    const Eigen::Vector2d ahead = pl.at(std::min(s + 0.3, pl.length_m())) - pl.at(std::max(s - 0.3, 0.0));
    Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();
    T_world_base.translation() = Eigen::Vector3d(p.x(), p.y(), 0.0);
    T_world_base.linear() =
        Eigen::AngleAxisd(std::atan2(ahead.y(), ahead.x()), Eigen::Vector3d::UnitZ())
            .toRotationMatrix();
    sim::ViewState view;
    view.T_world_cam = T_world_base * mount.T_base_cam(0.0, 0.0);
    view.intrinsics = core::CameraIntrinsics::pepper_top_vga().scaled_to(320, 240);
    view.light = w->light("teach");
    view.t_s = t;
    view.robot_base_m = p;
    const cv::Mat with = renderer.render(*d.world, view).clone();
    const cv::Mat without = renderer.render(*w, view);
    cv::Mat diff;
    cv::absdiff(with, without, diff);
    if (cv::countNonZero(diff > 10) >= 0.03 * diff.total()) ++seen;
  }
  std::cout << "[measured] " << GetParam().world << ": " << added << " crowd people, "
            << crossing_s.size() << " crossings from s = " << *lo << " to " << *hi << " m of "
            << pl.length_m() << " m; " << seen << " of " << frames
            << " forward frames on the taught drive see the crowd\n";
  EXPECT_GE(seen, frames / 4) << seen << " of " << frames << " frames see the crowd";

  // One seed, one crowd; another seed, another.
  const DisturbedWorld again = make_disturbed_world(w, {Disturbance::kCrowd}, o, path, 1);
  const DisturbedWorld other = make_disturbed_world(w, {Disturbance::kCrowd}, o, path, 2);
  ASSERT_EQ(again.world->people.size(), d.world->people.size());
  bool differs = other.world->people.size() != d.world->people.size();
  for (size_t k = 0; k < d.world->people.size(); ++k) {
    EXPECT_EQ(again.world->people[k].path_m, d.world->people[k].path_m);
    EXPECT_EQ(again.world->people[k].speed_m_s, d.world->people[k].speed_m_s);
    EXPECT_EQ(again.world->people[k].start_offset_m, d.world->people[k].start_offset_m);
    if (!differs && k < other.world->people.size()) {
      differs = other.world->people[k].path_m != d.world->people[k].path_m ||
                other.world->people[k].speed_m_s != d.world->people[k].speed_m_s;
    }
  }
  EXPECT_TRUE(differs);
  EXPECT_EQ(parse_disturbance("crowd"), Disturbance::kCrowd);
  EXPECT_EQ(disturbance_label({Disturbance::kFurniture, Disturbance::kCrowd}), "furniture+crowd");
}

INSTANTIATE_TEST_SUITE_P(ShippedWorlds, CrowdDisturbance,
                         ::testing::Values(CrowdCase{"robotics_room", 5},
                                           CrowdCase{"room_corridor_room", 5}),
                         [](const auto& info) { return std::string(info.param.world); });

TEST(Disturbances, CrowdOptionsAreValidated) {
  DisturbanceOptions o;
  o.crowd_people = 21;
  o.crowd_speed_max_m_s = 0.2;  // below the minimum speed
  const auto errors = o.validate();
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].find("disturbance.crowd_people"), std::string::npos);
  EXPECT_NE(errors[1].find("disturbance.crowd_speed_max_m_s"), std::string::npos);
}

TEST(Output, JsonHasSummaryAndRuns) {
  Evaluation e;
  e.world_name = "w";
  e.features = "lines+points";
  RunResult a, b;
  a.success = true;
  a.lateral_rms_m = 0.02;
  a.lateral_max_m = 0.06;
  a.final_error_m = 0.1;
  b.index = 1;
  b.success = false;
  b.lateral_rms_m = 0.04;
  b.lateral_max_m = 0.12;
  b.final_error_m = 0.3;
  a.verified_lines_mean = 40.0;
  a.verified_points_mean = 100.0;
  b.verified_lines_mean = 20.0;  // b's points: none measured (NaN), left out of the mean
  e.runs = {a, b};
  e.summary = summarize(e.runs, 10, 5.0);
  EXPECT_NEAR(e.summary.success_rate, 0.5, 1e-12);
  EXPECT_NEAR(e.summary.lateral_rms_m, 0.03, 1e-12);  // mean of per-run RMS
  EXPECT_NEAR(e.summary.lateral_max_m, 0.12, 1e-12);  // max over runs
  EXPECT_NEAR(e.summary.key_images_per_m, 2.0, 1e-12);
  EXPECT_NEAR(e.summary.verified_lines_mean, 30.0, 1e-12);  // mean over runs
  EXPECT_NEAR(e.summary.verified_points_mean, 100.0, 1e-12);
  const auto j = to_json({e});
  EXPECT_NEAR(j["summary"]["verified_lines_mean"].get<double>(), 30.0, 1e-12);
  EXPECT_TRUE(j["runs"][1]["verified_points_mean"].is_null());
  EXPECT_EQ(j["summary"]["success_rate"].get<double>(), 0.5);
  EXPECT_NEAR(j["summary"]["lateral_rms_m"].get<double>(), 0.03, 1e-12);
  EXPECT_EQ(j["runs"].size(), 2u);
  EXPECT_EQ(j["evaluations"][0]["world"], "w");
  EXPECT_NE(summary_table({e}).find("1/2"), std::string::npos);
}

// `evaluate --plots` writes one small top view per run beside the combined one (the matrix index,
// bench/closed_loop/combine.py --html, shows them): run N alone, a failed run marked pure red
// (BGR 0,0,255, a colour no other series uses) where it ended.
TEST(Output, PlotsHaveATopViewPerRunWithTheFailureMarked) {
  const test::TempDir tmp("plots");
  Evaluation e;
  e.world_name = "small_room";
  e.features = "lines+points";
  TeachResult teach;
  for (int i = 0; i <= 20; ++i) teach.path_m.emplace_back(1.0 + 0.1 * i, 1.0);
  RunResult ok, failed;
  failed.index = 1;
  failed.success = false;
  failed.outcome = "lost";
  for (int i = 0; i <= 20; ++i) {
    RunSample smp;
    smp.x_m = 1.0 + 0.1 * i;
    smp.y_m = 1.05;
    ok.samples.push_back(smp);
    if (i <= 8) failed.samples.push_back(smp);
  }
  ok.success = true;
  ok.outcome = "complete";
  e.runs = {ok, failed};
  const auto files = write_plots(e, teach, *small_room(), tmp.path(), "p_");
  auto red_pixels = [](const cv::Mat& img) {
    int n = 0;
    for (int r = 0; r < img.rows; ++r) {
      for (int c = 0; c < img.cols; ++c) {
        const auto& px = img.at<cv::Vec3b>(r, c);
        n += px[0] == 0 && px[1] == 0 && px[2] == 255;
      }
    }
    return n;
  };
  const cv::Mat run1 = cv::imread((tmp.path() / "p_run1_top_view.png").string(), cv::IMREAD_COLOR);
  const cv::Mat run2 = cv::imread((tmp.path() / "p_run2_top_view.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(run1.empty());
  ASSERT_FALSE(run2.empty());
  EXPECT_EQ(run1.cols, 480);
  EXPECT_EQ(run1.rows, 400);
  EXPECT_EQ(red_pixels(run1), 0) << "a run that succeeded has no end-of-failure mark";
  EXPECT_GT(red_pixels(run2), 10) << "the failed run is marked where it ended";
  EXPECT_TRUE(std::filesystem::exists(tmp.path() / "p_top_view.png"));
  EXPECT_EQ(std::count(files.begin(), files.end(), tmp.path() / "p_run2_top_view.png"), 1);
}

}  // namespace
}  // namespace pepper::app::evaluation
