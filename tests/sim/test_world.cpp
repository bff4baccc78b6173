// World files: every shipped world loads, validates and has a drivable taught path; malformed
// files give errors that name the file, the line and the key.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "sim/world.hpp"

namespace pepper::sim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

const std::filesystem::path kWorlds = std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds";

std::vector<std::filesystem::path> shipped_worlds() {
  std::vector<std::filesystem::path> out;
  for (const auto& e : std::filesystem::directory_iterator(kWorlds))
    if (e.path().extension() == ".yaml") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

TEST(World, AtLeastFourWorldsShipped) {
  const auto worlds = shipped_worlds();
  EXPECT_GE(worlds.size(), 4u);
  for (const char* name : {"robotics_room.yaml", "room_corridor_room.yaml", "white_corridor.yaml",
                           "window_corridor.yaml"})
    EXPECT_TRUE(std::filesystem::exists(kWorlds / name)) << name;
}

TEST(World, EveryShippedWorldLoadsWithADrivableTaughtPath) {
  for (const auto& file : shipped_worlds()) {
    SCOPED_TRACE(file.string());
    World w;
    ASSERT_NO_THROW(w = load_world(file));
    EXPECT_GT(w.quads.size(), 20u);
    EXPECT_GE(w.walls.size(), 4u);
    EXPECT_TRUE(w.lighting.count("teach"));
    EXPECT_TRUE(w.lighting.count("replay"));
    ASSERT_GE(w.scenario.waypoints_m.size(), 2u);
    EXPECT_GT(w.scenario.path_length_m(), 10.0);
    // Every point of the taught path keeps a 0.3 m robot clear of every obstacle, with margin.
    const auto& p = w.scenario.waypoints_m;
    for (size_t i = 1; i < p.size(); ++i) {
      for (double f = 0.0; f <= 1.0; f += 0.01) {
        const Eigen::Vector2d q = p[i - 1] + f * (p[i] - p[i - 1]);
        const auto hit = w.collision(q, 0.35, 0.0);
        EXPECT_FALSE(hit.has_value())
            << "segment " << i << " at " << q.transpose() << " hits " << hit.value_or("");
      }
    }
    for (const Pose2D& s : w.scenario.replay_starts)
      EXPECT_FALSE(w.collision({s.x_m, s.y_m}, 0.3, 0.0).has_value());
    for (const Texture& t : w.textures) {
      EXPECT_GT(t.levels(), 4) << t.name();
      EXPECT_LE(t.width_px(), 1024) << t.name();
    }
  }
}

TEST(World, CorridorWorldHasTwoRightAngleTurnsOverAbout22m) {
  const World w = load_world(kWorlds / "room_corridor_room.yaml");
  EXPECT_NEAR(w.scenario.path_length_m(), 22.0, 1.0);
  const auto& p = w.scenario.waypoints_m;
  int right_angles = 0;
  for (size_t i = 1; i + 1 < p.size(); ++i) {
    const Eigen::Vector2d a = (p[i] - p[i - 1]).normalized(), b = (p[i + 1] - p[i]).normalized();
    if (std::abs(a.dot(b)) < 1e-6) ++right_angles;
  }
  EXPECT_EQ(right_angles, 2);
}

TEST(World, WindowCorridorLightDiffersBetweenTeachAndReplay) {
  const World w = load_world(kWorlds / "window_corridor.yaml");
  EXPECT_NE(w.light("teach").ambient, w.light("replay").ambient);
  EXPECT_NE(w.light("teach").windows, w.light("replay").windows);
  EXPECT_THROW(w.light("dusk"), WorldError);
}

const char* kMinimal = R"(
textures:
  paint: {type: noise, mean: 180, contrast: 10}
floor: {texture: paint}
walls:
  - points: [[0, 0], [4, 0], [4, 3], [0, 3]]
    closed: true
    texture: paint
)";

TEST(World, MinimalWorldParses) {
  const World w = parse_world(kMinimal, "mem.yaml", kWorlds);
  EXPECT_EQ(w.walls.size(), 4u);
  EXPECT_EQ(w.name, "mem");
  EXPECT_TRUE(w.collision({0.1, 1.5}, 0.3, 0.0).has_value());
  EXPECT_FALSE(w.collision({2.0, 1.5}, 0.3, 0.0).has_value());
}

std::string error_of(const std::string& yaml) {
  try {
    parse_world(yaml, "bad_world.yaml", kWorlds);
  } catch (const WorldError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(World, BadNumberNamesFileLineAndKey) {
  const std::string yaml = std::string(kMinimal) + "    height_m: tall\n";
  // Line 9 of the text (the leading newline is line 1).
  EXPECT_THAT(error_of(yaml), AllOf(HasSubstr("bad_world.yaml:9"), HasSubstr("walls[0].height_m"),
                                    HasSubstr("expected a number")));
}

TEST(World, UnknownKeyIsRefusedByName) {
  EXPECT_THAT(error_of(std::string(kMinimal) + "    hieght_m: 2.5\n"),
              AllOf(HasSubstr("bad_world.yaml:9"), HasSubstr("walls[0].hieght_m"),
                    HasSubstr("unknown key")));
}

TEST(World, UnknownTextureNamesKeyAndTexture) {
  EXPECT_THAT(
      error_of(R"(
textures:
  paint: {type: uniform}
floor: {texture: carpet}
walls:
  - {points: [[0, 0], [1, 0]], texture: paint}
)"),
      AllOf(HasSubstr("bad_world.yaml:4"), HasSubstr("floor.texture"), HasSubstr("'carpet'")));
}

TEST(World, MissingImageFileIsReported) {
  EXPECT_THAT(error_of(R"(
textures:
  photo: {type: image, file: textures/does_not_exist.jpg}
floor: {texture: photo}
walls:
  - {points: [[0, 0], [1, 0]], texture: photo}
)"),
              AllOf(HasSubstr("textures.photo"), HasSubstr("does_not_exist.jpg")));
}

TEST(World, YamlSyntaxErrorNamesFileAndLine) {
  EXPECT_THAT(error_of("textures:\n  paint: {type: uniform\nfloor: x\n"),
              AllOf(HasSubstr("bad_world.yaml:"), HasSubstr("YAML syntax error")));
}

TEST(World, FeatureThatDoesNotFitTheWallIsRefused) {
  const std::string yaml = std::string(kMinimal) + "    doors: [{at_m: 3.8, width_m: 0.9}]\n";
  EXPECT_THAT(error_of(yaml), HasSubstr("walls[0].doors[0]"));
}

TEST(World, UnknownTextureTypeListsTheValidOnes) {
  EXPECT_THAT(
      error_of("textures:\n  a: {type: marble}\n"),
      AllOf(HasSubstr("bad_world.yaml:2"), HasSubstr("textures.a.type"), HasSubstr("checker")));
}

TEST(World, StartInsideAWallIsRefused) {
  const std::string yaml = std::string(kMinimal) + "teach: {waypoints: [[0.1, 1.5], [2, 1.5]]}\n";
  EXPECT_THAT(error_of(yaml), HasSubstr("collides"));
}

TEST(World, OpeningsArePassableDoorsAreNot) {
  const std::string yaml = std::string(kMinimal) +
                           "    openings: [{at_m: 2.0, width_m: 1.0}]\n"
                           "    doors: [{at_m: 5.5, width_m: 0.9, texture: paint}]\n";
  const World w = parse_world(yaml, "mem.yaml", kWorlds);
  EXPECT_FALSE(w.collision({2.0, 0.0}, 0.3, 0.0).has_value());  // in the opening at x = 2
  EXPECT_TRUE(w.collision({4.0, 1.5}, 0.3, 0.0).has_value());   // the door at y = 1.5
  // The opening spans x = 1.5..2.5 and the wall pieces end flat there (0.1 m thick): a 0.3 m
  // disc 0.17 m off the opening's centre has 3 cm to spare, 0.21 m off it touches.
  EXPECT_FALSE(w.collision({2.17, 0.0}, 0.3, 0.0).has_value());
  EXPECT_FALSE(w.collision({1.83, 0.0}, 0.3, 0.0).has_value());
  EXPECT_TRUE(w.collision({2.21, 0.0}, 0.3, 0.0).has_value());
  EXPECT_TRUE(w.collision({1.79, 0.0}, 0.3, 0.0).has_value());
  // Beside a wall: its face is half the thickness from its line.
  EXPECT_FALSE(w.collision({3.0, 0.36}, 0.3, 0.0).has_value());
  EXPECT_TRUE(w.collision({3.0, 0.34}, 0.3, 0.0).has_value());
}

TEST(World, MovingObstacleWalksBackAndForth) {
  MovingObstacle m;
  m.path_m = {{0, 0}, {2, 0}};
  m.speed_m_s = 1.0;
  EXPECT_NEAR(m.pose_at(0.5).x(), 0.5, 1e-12);
  EXPECT_NEAR(m.pose_at(3.0).x(), 1.0, 1e-12);             // 3 m walked: 2 out, 1 back
  EXPECT_NEAR(std::abs(m.pose_at(3.0).z()), M_PI, 1e-12);  // heading back
  m.loop = true;
  EXPECT_NEAR(m.pose_at(3.0).x(), 1.0, 1e-12);
}

// A person who keeps clear (crowd disturbance) steps aside from the robot: where its walk
// passes within keep_clear_m of the base it stands keep_clear_m away on the ray from the base
// through its walk's position, and walks its path elsewhere; the collision test of the robot's
// disc then never touches it, while the same walk without keep_clear_m does.
TEST(World, PersonWhoKeepsClearStepsAsideFromTheRobot) {
  World w;
  MovingObstacle m;
  m.path_m = {{-3, 0}, {3, 0}};  // crosses the robot's position (0, 0.2) at t = 3 s
  m.speed_m_s = 1.0;
  m.what = "walker";
  w.people.push_back(m);
  const Eigen::Vector2d robot(0.0, 0.2);
  for (double t = 0.0; t <= 6.0; t += 0.05) {
    EXPECT_EQ(w.people[0].pose_near(t, robot), w.people[0].pose_at(t)) << "kinematic, t " << t;
  }
  EXPECT_TRUE(w.collision(robot, 0.3, 3.0));  // the kinematic walk runs into the robot
  w.people[0].keep_clear_m = 0.7;
  bool stepped_aside = false;
  for (double t = 0.0; t <= 6.0; t += 0.05) {
    const Eigen::Vector3d walk = w.people[0].pose_at(t);
    const Eigen::Vector3d near = w.people[0].pose_near(t, robot);
    const double walk_distance = (walk.head<2>() - robot).norm();
    if (walk_distance >= 0.7) {
      EXPECT_EQ(near, walk) << "t " << t;
    } else {
      stepped_aside = true;
      EXPECT_NEAR((near.head<2>() - robot).norm(), 0.7, 1e-12) << "t " << t;
      // Same side of the robot as its walk's position (on the ray through it).
      EXPECT_GT((near.head<2>() - robot).dot(walk.head<2>() - robot), 0.0) << "t " << t;
      EXPECT_EQ(near.z(), walk.z());
    }
    EXPECT_FALSE(w.collision(robot, 0.3, t)) << "t " << t;
  }
  EXPECT_TRUE(stepped_aside);
  EXPECT_EQ(w.people[0].pose_near(3.0, std::nullopt), w.people[0].pose_at(3.0));  // no robot
}

}  // namespace
}  // namespace pepper::sim

namespace pepper::sim {
namespace {

TEST(World, ReplayStartsArePerturbedWithinRangesDeterministically) {
  const World w = load_world(kWorlds / "robotics_room.yaml");
  const Scenario& s = w.scenario;
  ASSERT_FALSE(s.replay_starts.empty());
  const Pose2D exact = s.replay_start(1, 0);
  EXPECT_EQ(exact.x_m, s.replay_starts[1].x_m);
  EXPECT_EQ(exact.yaw_rad, s.replay_starts[1].yaw_rad);
  bool moved = false;
  for (size_t k = 0; k < 20; ++k) {
    const Pose2D base = s.replay_starts[k % s.replay_starts.size()];
    const Pose2D p = s.replay_start(k, 42);
    const Pose2D again = s.replay_start(k, 42);
    EXPECT_EQ(p.x_m, again.x_m);
    EXPECT_EQ(p.y_m, again.y_m);
    const double d = std::hypot(p.x_m - base.x_m, p.y_m - base.y_m);
    EXPECT_LE(d, std::hypot(s.perturb_along_m, s.perturb_lateral_m) + 1e-12);
    EXPECT_LE(std::abs(p.yaw_rad - base.yaw_rad), s.perturb_yaw_rad + 1e-12);
    moved = moved || d > 0.01;
    EXPECT_FALSE(w.collision({p.x_m, p.y_m}, 0.3, 0.0).has_value());
  }
  EXPECT_TRUE(moved);
}

}  // namespace
}  // namespace pepper::sim

namespace pepper::sim {
namespace {

// The footprint drawn in reports and the UI: a 1 m x 0.5 m box at (1, 2) turned by 90 degrees
// covers x in [0.75, 1.25] and y in [1.5, 2.5], corners counter-clockwise.
TEST(World, BoxCornersAreTheTurnedFootprint) {
  BoxObstacle b;
  b.center_m = Eigen::Vector2d(1.0, 2.0);
  b.half_size_m = Eigen::Vector2d(0.5, 0.25);
  b.yaw_rad = M_PI / 2;
  const auto c = b.corners_m();
  const Eigen::Vector2d expected[4] = {{1.25, 1.5}, {1.25, 2.5}, {0.75, 2.5}, {0.75, 1.5}};
  double area2 = 0.0;  // shoelace: > 0 for counter-clockwise
  for (size_t k = 0; k < 4; ++k) {
    EXPECT_NEAR((c[k] - expected[k]).norm(), 0.0, 1e-12) << k;
    const auto& p = c[k];
    const auto& q = c[(k + 1) % 4];
    area2 += p.x() * q.y() - q.x() * p.y();
  }
  EXPECT_NEAR(area2 / 2, 0.5, 1e-12);
}

}  // namespace
}  // namespace pepper::sim
