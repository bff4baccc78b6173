// What the sessions give the teach UI besides the safety behaviour: the feature overlay in the
// page's frame-header format (rounded pixels, one group of lines and one of points) and the
// taught path kept next to a map taught on the mock robot (top view of a later replay).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/memory/visual_memory.hpp"
#include "session/taught_path.hpp"
#include "session/teach_session.hpp"
#include "session/telemetry_json.hpp"

namespace pepper::app {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  auto p = fs::temp_directory_path() / ("pepper_ui_data_test_" + name);
  fs::remove_all(p);
  return p;
}

TEST(OverlayJson, RoundsPixelsAndLabelsTheGroups) {
  core::features::FeatureOverlay o;
  o.lines.push_back({{10.4f, 20.6f}, {100.5f, -0.4f}});
  o.points_px.emplace_back(3.49f, 7.51f);
  o.points_px.emplace_back(0.0f, 239.0f);
  const nlohmann::json j = overlay_to_json(o, "detected");
  ASSERT_EQ(j.at("lines").size(), 1u);
  const auto& lines = j.at("lines")[0];
  EXPECT_EQ(lines.at("label"), "detected lines");
  EXPECT_EQ(lines.at("segments"), nlohmann::json::parse("[[10,21,101,0]]"));
  const auto& points = j.at("points")[0];
  EXPECT_EQ(points.at("label"), "detected points");
  EXPECT_EQ(points.at("uv"), nlohmann::json::parse("[[3,8],[0,239]]"));
  EXPECT_NE(lines.at("color"), points.at("color"));  // told apart on the page
  // Empty overlays still give both groups, so the legend reads "0" rather than vanishing.
  const nlohmann::json empty = overlay_to_json({}, "matched");
  EXPECT_TRUE(empty.at("lines")[0].at("segments").empty());
  EXPECT_TRUE(empty.at("points")[0].at("uv").empty());
}

// Ceiling mode's caption: the landmarks kept of those matched and the pose in the mosaic; when
// coasting, the odometry distance; before any pose, says so.
TEST(OverlayJson, TheCeilingCaptionSaysWhereTheRobotIsInTheMosaic) {
  nlohmann::json c = {{"fix", true},        {"matches", 80},   {"inliers", 61},
                      {"pose_known", true}, {"coasted_m", 0.0},
                      {"T_mosaic_base", {{"x_m", 1.234}, {"y_m", -0.5}, {"theta_rad", M_PI / 2}}}};
  EXPECT_EQ(ceiling_overlay_caption(c),
            "ceiling: 61 of 80 landmarks, mosaic x 1.23 y -0.50 m, 90 deg");
  c["fix"] = false;
  c["coasted_m"] = 0.31;
  EXPECT_EQ(ceiling_overlay_caption(c),
            "ceiling: coasting on odometry 0.31 m, mosaic x 1.23 y -0.50 m, 90 deg");
  c["T_mosaic_base"] = nullptr;
  c["inliers"] = 3;
  EXPECT_EQ(ceiling_overlay_caption(c), "ceiling: 3 of 80 landmarks, no pose in the mosaic");
}

// Ceiling overlays (teach and replay views) are points only: no lines group in the legend.
TEST(OverlayJson, CeilingOverlaysArePointsOnly) {
  core::features::FeatureOverlay o;
  o.points_px.emplace_back(3.49f, 7.51f);
  const nlohmann::json j = ceiling_overlay_to_json(o);
  EXPECT_FALSE(j.contains("lines"));
  EXPECT_EQ(j.at("points")[0].at("label"), "ceiling landmarks");
  EXPECT_EQ(j.at("points")[0].at("uv"), nlohmann::json::parse("[[3,8]]"));
}

// The teach panel in ceiling mode: this frame's landmarks and the mosaic's, no key image list.
TEST(OverlayJson, TheCeilingTeachStateSaysWhatTheMosaicHas) {
  core::ceiling::MosaicFrameResult step;
  step.localised = true;
  step.inliers = 42;
  step.added = 7;
  const nlohmann::json j = ceiling_teach_state(3.25, step, 812, 5, 1);
  EXPECT_EQ(j.at("distance_m"), 3.25);
  EXPECT_FALSE(j.contains("key_images")) << "relay images are chosen at the end";
  const nlohmann::json& c = j.at("ceiling");
  EXPECT_EQ(c.at("matched"), 42);
  EXPECT_EQ(c.at("added"), 7);
  EXPECT_EQ(c.at("localised"), true);
  EXPECT_EQ(c.at("mosaic_landmarks"), 812);
  EXPECT_EQ(c.at("frames_without_pose"), 5);
  EXPECT_EQ(c.at("loops_closed"), 1);
  step.localised = false;
  EXPECT_EQ(ceiling_teach_state(3.25, step, 812, 6, 1).at("ceiling").at("localised"), false);
}

TEST(TaughtPathFile, RoundTripsAndIsOptional) {
  const fs::path dir = fresh_dir("roundtrip");
  fs::create_directories(dir);
  EXPECT_FALSE(load_taught_path(dir).has_value());
  TaughtPath p{"room", {{0.0, 1.0}, {0.5, 1.25}}, {{0.0, 1.0}}};
  save_taught_path(dir, p);
  const auto back = load_taught_path(dir);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->world, "room");
  ASSERT_EQ(back->path_m.size(), 2u);
  EXPECT_EQ(back->path_m[1], Eigen::Vector2d(0.5, 1.25));
  ASSERT_EQ(back->key_images_m.size(), 1u);
  fs::remove_all(dir);
}

TEST(TaughtPathFile, MalformedFileNamesItself) {
  const fs::path dir = fresh_dir("malformed");
  fs::create_directories(dir);
  std::ofstream(dir / kTaughtPathFile) << R"({"format":"pepper-taught-path","version":1,)"
                                       << R"("world":"w","path_m":[[1]],"key_images_m":[]})";
  try {
    load_taught_path(dir);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(kTaughtPathFile), std::string::npos) << e.what();
  }
  std::ofstream(dir / kTaughtPathFile) << R"({"format":"something-else","version":1})";
  EXPECT_THROW(load_taught_path(dir), std::runtime_error);
  fs::remove_all(dir);
}

TEST(TaughtPathFile, TeachOnTheMockWritesItWithTheMap) {
  RobotConnection robot = open_robot(
      std::string("mock:") + PEPPER_SOURCE_DIR + "/worlds/robotics_room.yaml", {});
  TeachSessionOptions o;
  o.map_dir = fresh_dir("teach_map");
  o.recording_dir = fresh_dir("teach_rec");
  o.camera.width_px = 320;
  o.camera.height_px = 240;
  o.scripted = true;
  o.max_frames = 30;
  SessionLink link(nullptr, nullptr);
  const TeachResult r = run_teach_session(robot, o, link);
  ASSERT_TRUE(r.ok()) << r.outcome << " " << r.error;
  const auto taught = load_taught_path(o.map_dir);
  ASSERT_TRUE(taught.has_value());
  EXPECT_EQ(taught->world, robot.mock->world().name);
  EXPECT_EQ(static_cast<int64_t>(taught->path_m.size()), r.frames_recorded);
  const core::memory::VisualMemory map = core::memory::load_map(o.map_dir);  // still a valid map
  ASSERT_EQ(taught->key_images_m.size(), map.key_images.size());
  EXPECT_EQ(taught->key_images_m.front(), taught->path_m.front());
  EXPECT_EQ(taught->key_images_m.back(), taught->path_m.back());
  EXPECT_GT((taught->path_m.back() - taught->path_m.front()).norm(), 0.1);  // it drove
  fs::remove_all(o.map_dir);
  fs::remove_all(o.recording_dir);
}

}  // namespace
}  // namespace pepper::app
