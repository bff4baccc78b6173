// Issue 26, floor lines (docs/method/navigator.md "Lateral position from floor lines"): in a
// white corridor under light x1.4 the walls saturate and the floor-wall edges are most of what
// the view keeps. The corridor's tour is taught on the mock robot at QVGA; then the navigator
// over that map is fed frames rendered 0.2 m to the left of the taught path (exact odometry,
// open loop). Placed at a key image's taught pose by its localisation, the odometry estimate
// must learn the 0.2 m from the floor lines alone.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include <Eigen/Geometry>

#include "core/navigator/navigator.hpp"
#include "evaluation/closed_loop.hpp"
#include "sim/mock_robot.hpp"
#include "sim/renderer.hpp"
#include "sim/world.hpp"
#include "support/temp_dir.hpp"

namespace pepper::app::evaluation {
namespace {

TEST(FloorLinesReplay, TheOdometryEstimateLearnsTheLateralOffsetFromTheFloorEdges) {
  const auto world = std::make_shared<const sim::World>(sim::load_world(
      std::string(PEPPER_SOURCE_DIR) + "/tests/app/evaluation/data/white_corridor_short.yaml"));
  const test::TempDir tmp("floor_lines");
  EvaluationOptions o;
  o.width_px = 320;
  o.height_px = 240;
  o.map_dir = tmp.path() / "map";
  const TeachResult teach = teach_tour(world, o);
  ASSERT_GE(teach.map.key_images.size(), 4u);
  ASSERT_TRUE(teach.map.key_images.front().odom);  // the mock's wheel odometry, in the map

  // The floor lines correct the estimate only on frames without an accepted VNHV fix. With the
  // default planar essential model VNHV fixes 0.20-0.22 m on about 40 of these frames and the
  // floor lines act on 37 (within 3 cm after the first second); with the five-point model VNHV
  // has no fix here and the floor lines alone must learn the offset, which is what this test is
  // about.
  core::navigator::NavigatorOptions nav_options = replay_session_options(o).navigator;
  nav_options.matcher.essential.planar = false;
  core::navigator::Navigator nav(teach.map, nav_options);
  sim::LightingCondition light = world->light("replay");
  light.ambient *= 1.4;
  light.windows *= 1.4;
  light.lamps *= 1.4;
  sim::Renderer renderer;
  const sim::CameraMount mount;
  constexpr double kOffsetM = 0.2;
  int floor_frames = 0, late_frames = 0, late_good = 0;
  for (int i = 0; i < 100; ++i) {
    // Along the taught line y = 0 from x = 1.1 m, 3 cm per frame, 0.2 m to its left.
    const double x_m = 1.1 + 0.03 * i;
    sim::ViewState view;
    Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();
    T_world_base.translation() = Eigen::Vector3d(x_m, kOffsetM, 0.0);
    view.T_world_cam = T_world_base * mount.T_base_cam(0.0, 0.0);
    view.intrinsics = teach.map.camera;
    view.light = light;
    view.frame_index = static_cast<uint64_t>(i);
    core::Frame f;
    f.gray = renderer.render(*world, view);
    f.t_ns = static_cast<int64_t>(i) * 100'000'000;
    f.index = i;
    f.odom = core::OdometryPose{x_m, kOffsetM, 0.0};
    const core::navigator::Telemetry t = nav.step(f).telemetry;
    if (t.floor_lines == 0) continue;
    ++floor_frames;
    EXPECT_GE(t.floor_lines, 2);
    // The taught path is y = 0 up to the teach drive's own few millimetres: after the first
    // second, every floor-line update puts the estimate within 3 cm of the true offset.
    if (i >= 10) {
      ++late_frames;
      late_good += std::abs(t.floor_lateral_after_m - kOffsetM) <= 0.03 ? 1 : 0;
    }
  }
  std::printf("[ measured ] %d of 100 frames with a floor-line update, %d after the first second\n",
              floor_frames, late_frames);
  EXPECT_GE(floor_frames, 40);  // measured 77 (QVGA; 83 before the teach used the planar model)
  ASSERT_GT(late_frames, 0);
  EXPECT_EQ(late_good, late_frames);
}

}  // namespace
}  // namespace pepper::app::evaluation
