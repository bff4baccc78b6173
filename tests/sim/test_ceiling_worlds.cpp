// The shipped worlds with ceiling content (issue 24; docs/mock_robot.md "Ceiling items"): a head
// pitched up at poses on their tours sees enough ceiling landmarks for ceiling mode, and the
// fixtures render where the world file puts them.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/ceiling/canonical_view.hpp"
#include "core/ceiling/landmarks.hpp"
#include "sim/mock_robot.hpp"
#include "sim/renderer.hpp"
#include "sim/world.hpp"
#include "sim/world_generator.hpp"

namespace pepper::sim {
namespace {

constexpr double kPitchRad = -0.7;  // robot.ceiling_head_pitch_rad's default
constexpr int kWidthPx = 320, kHeightPx = 240;
constexpr double kPxPerM = 120.0;  // the ceiling teach's canonical scale (docs/method/ceiling.md)

World shipped(const std::string& name) {
  return load_world(std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds" / name);
}

Eigen::Isometry3d T_world_cam_at(const Pose2D& base, double pitch_rad) {
  Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();
  T_world_base.translation() = Eigen::Vector3d(base.x_m, base.y_m, 0.0);
  T_world_base.linear() =
      Eigen::AngleAxisd(base.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T_world_base * CameraMount{}.T_base_cam(0.0, pitch_rad);
}

ViewState view_at(const Pose2D& base) {
  ViewState view;
  view.T_world_cam = T_world_cam_at(base, kPitchRad);
  view.intrinsics = core::CameraIntrinsics::pepper_top_vga().scaled_to(kWidthPx, kHeightPx);
  return view;
}

// Distance along the heading from `base` to the first wall (its centre line), metres.
double wall_ahead_m(const World& world, const Pose2D& base) {
  const Eigen::Vector2d o(base.x_m, base.y_m), d(std::cos(base.yaw_rad), std::sin(base.yaw_rad));
  double best = 1e9;
  for (const WallObstacle& w : world.walls) {
    const Eigen::Vector2d e = w.b_m - w.a_m;
    const double den = d.x() * e.y() - d.y() * e.x();
    if (std::abs(den) < 1e-12) continue;
    const Eigen::Vector2d ao = w.a_m - o;
    const double t = (ao.x() * e.y() - ao.y() * e.x()) / den;  // along the ray
    const double s = (ao.x() * d.y() - ao.y() * d.x()) / den;  // along the wall, 0..1
    if (t > 0 && s >= 0 && s <= 1) best = std::min(best, t);
  }
  return best;
}

// Poses every `step_m` along the taught polyline, heading along its piece, that have at least
// `free_m` of room ahead: nearer a wall the camera sees the wall, not the ceiling, whatever is
// on the ceiling (the canonical view is cut 3.5 m ahead).
std::vector<Pose2D> tour_poses(const World& world, double step_m, double free_m) {
  const auto& w = world.scenario.waypoints_m;
  std::vector<Pose2D> out;
  double next = 0.0, start = 0.0;
  for (size_t i = 1; i < w.size(); ++i) {
    const Eigen::Vector2d d = w[i] - w[i - 1];
    const double len = d.norm();
    for (; next <= start + len; next += step_m) {
      const Eigen::Vector2d p = w[i - 1] + d * (next - start) / len;
      const Pose2D pose{p.x(), p.y(), std::atan2(d.y(), d.x())};
      if (wall_ahead_m(world, pose) >= free_m) out.push_back(pose);
    }
    start += len;
  }
  return out;
}

// ORB landmarks on the canonical view (the ceiling teach's: 120 px/m, cut 3.5 m ahead) of the
// camera image at `base` that lie on the ceiling or on what hangs from it: the rendered depth at
// the landmark's camera pixel is at least 70 % of the ceiling plane's there (a sign or a beam
// 0.35 m under a ceiling 1.5 m above the camera is at 77 %; a wall in front of the ceiling is
// much nearer). A wall seen at the top of the image warps into the canonical view too.
int ceiling_landmarks(const World& world, Renderer& renderer, const Pose2D& base) {
  const ViewState view = view_at(base);
  const cv::Mat image = renderer.render(world, view);
  const cv::Mat depth = renderer.depth_m();
  core::ceiling::CeilingCamera camera;
  camera.intrinsics = view.intrinsics;
  camera.head_pitch_rad = kPitchRad;
  camera.ceiling_above_cam_m = world.ceiling_height_m - view.T_world_cam.translation().z();
  const core::ceiling::CanonicalView canonical(camera,
                                               core::ceiling::fit_frame(camera, kPxPerM, 3.5));
  cv::Mat seen;
  const cv::Mat warped = canonical.warp(image, &seen);
  const auto landmarks = core::ceiling::extract_landmarks(warped, seen);
  const Eigen::Vector3d cam_world = view.T_world_cam.translation();
  const auto& k = view.intrinsics;
  int on_ceiling = 0;
  for (const cv::KeyPoint& kp : landmarks.keypoints) {
    const auto px = canonical.to_image(kp.pt);
    if (!px) continue;
    const int u = static_cast<int>(std::lround(px->x)), v = static_cast<int>(std::lround(px->y));
    if (u < 0 || v < 0 || u >= k.width_px || v >= k.height_px) continue;
    // The ceiling plane's depth along this pixel's ray.
    const Eigen::Vector3d ray_cam((px->x - k.cx_px) / k.fx_px, (px->y - k.cy_px) / k.fy_px, 1.0);
    const Eigen::Vector3d ray_world = view.T_world_cam.linear() * ray_cam;
    if (ray_world.z() <= 1e-9) continue;
    const double ceiling_depth = (world.ceiling_height_m - cam_world.z()) / ray_world.z();
    if (depth.at<float>(v, u) >= 0.7 * ceiling_depth) ++on_ceiling;
  }
  return on_ceiling;
}

void expect_ceiling_landmarks_along_the_tour(const World& world, const std::string& name,
                                             int min_landmarks) {
  SCOPED_TRACE(name);
  Renderer renderer;  // the simulator's defaults: noise, vignetting, optics blur
  const auto poses = tour_poses(world, 1.0, 3.0);
  ASSERT_GE(poses.size(), 5u);
  int least = 1 << 30;
  double sum = 0.0;
  for (const Pose2D& p : poses) {
    const int n = ceiling_landmarks(world, renderer, p);
    std::cout << name << " (" << p.x_m << ", " << p.y_m << ", "
              << p.yaw_rad * 180.0 / M_PI << " deg): " << n << " ceiling landmarks\n";
    EXPECT_GE(n, min_landmarks) << "at (" << p.x_m << ", " << p.y_m << ")";
    least = std::min(least, n);
    sum += n;
  }
  std::cout << name << ": " << poses.size() << " poses, fewest " << least << ", mean "
            << sum / static_cast<double>(poses.size()) << " ceiling landmarks\n";
  EXPECT_TRUE(world.has_ceiling);
  EXPECT_FALSE(world.ceiling_items.empty());
}

// Bounds: the fewest measured over the poses (printed; docs/mock_robot.md "Ceiling items"),
// less a third: robotics_room 78 (mean 204 over 13 poses), room_corridor_room 140 (mean 268
// over 17). ORB keeps at most 400 per view.
TEST(CeilingWorlds, RoboticsRoomHeadUpSeesCeilingLandmarksAlongTheTour) {
  expect_ceiling_landmarks_along_the_tour(shipped("robotics_room.yaml"), "robotics_room", 50);
}

TEST(CeilingWorlds, RoomCorridorRoomHeadUpSeesCeilingLandmarksAlongTheTour) {
  expect_ceiling_landmarks_along_the_tour(shipped("room_corridor_room.yaml"),
                                          "room_corridor_room", 90);
}

// Generated worlds (`world generate`, its textures at their usual 256 px): one of each kind.
// Bound: the fewest measured over the three (printed: 270 room, 159 corridor, 185 building;
// means 346, 287, 288), less a third.
TEST(CeilingWorlds, GeneratedWorldsHeadUpSeeCeilingLandmarksAlongTheTour) {
  for (const auto& [seed, kind] : {std::pair{1, WorldKind::kRoom}, std::pair{2, WorldKind::kCorridor},
                                   std::pair{3, WorldKind::kBuilding}}) {
    WorldGeneratorOptions o;
    o.seed = static_cast<uint64_t>(seed);
    o.kind = kind;
    o.texture_dir = "textures";  // loaded with worlds/ as the base folder
    const GeneratedWorld g = generate_world(o);
    const std::string name = "gen_" + std::string(to_string(kind)) + "_" + std::to_string(seed);
    const World world =
        parse_world(g.yaml, name + ".yaml", std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds");
    expect_ceiling_landmarks_along_the_tour(world, name, 100);
  }
}

TEST(CeilingWorlds, RoomCorridorRoomVariantsShareTheirCeiling) {
  const World a = shipped("room_corridor_room.yaml");
  const World b = shipped("room_corridor_room_no_board.yaml");
  ASSERT_EQ(a.ceiling_items.size(), b.ceiling_items.size());
  for (size_t i = 0; i < a.ceiling_items.size(); ++i) {
    EXPECT_EQ(a.ceiling_items[i].kind, b.ceiling_items[i].kind);
    EXPECT_EQ(a.ceiling_items[i].center_m, b.ceiling_items[i].center_m);
  }
}

// Where a fixture is, the renderer draws it: a point of the beam's underside projects (pinhole,
// camera x right, y down, z forward) to a pixel whose rendered depth is that point's depth, not the
// ceiling's behind it; the missing tile (dark plenum) is dark at its projected centre and the
// ceiling just beyond its four edges is not.
TEST(CeilingWorlds, FixturesRenderWhereTheWorldFilePutsThem) {
  const World world = shipped("robotics_room.yaml");
  const CeilingItem* beam = nullptr;
  const CeilingItem* hole = nullptr;
  for (const CeilingItem& c : world.ceiling_items) {
    if (c.kind == CeilingItemKind::kBeam) beam = &c;
    if (c.kind == CeilingItemKind::kTile && (c.center_m - Eigen::Vector2d(5.7, 4.5)).norm() < 1e-9)
      hole = &c;
  }
  ASSERT_NE(beam, nullptr);
  ASSERT_NE(hole, nullptr);
  RenderOptions clean;
  clean.noise_sigma_grey = 0.0;
  clean.vignetting = 0.0;
  clean.optics_blur = false;
  Renderer renderer(clean);

  // The beam (x = 4.5, underside at 2.45 m) 1.8 m ahead of a robot facing +x.
  {
    const Pose2D base{beam->center_m.x() - 1.8, 3.0, 0.0};
    const ViewState view = view_at(base);
    renderer.render(world, view);
    const cv::Mat depth = renderer.depth_m();
    const auto& k = view.intrinsics;
    int checked = 0;
    for (double dy : {-0.4, 0.0, 0.4}) {
      const Eigen::Vector3d p_world(beam->center_m.x(), base.y_m + dy, beam->z_bottom_m);
      const Eigen::Vector3d p = view.T_world_cam.inverse() * p_world;
      ASSERT_GT(p.z(), 0.0);
      const double u = k.fx_px * p.x() / p.z() + k.cx_px, v = k.fy_px * p.y() / p.z() + k.cy_px;
      ASSERT_TRUE(u >= 0 && u < kWidthPx && v >= 0 && v < kHeightPx) << u << ", " << v;
      const float z = depth.at<float>(static_cast<int>(std::lround(v)), static_cast<int>(std::lround(u)));
      // The beam is 0.3 m wide: the pixel's neighbourhood is on its underside, within 2 %.
      EXPECT_NEAR(z, p.z(), 0.02 * p.z()) << "dy " << dy;
      ++checked;
    }
    EXPECT_EQ(checked, 3);
  }
  // The missing tile 1.6 m ahead of a robot facing +y.
  {
    const Pose2D base{hole->center_m.x(), hole->center_m.y() - 1.6, M_PI / 2};
    const ViewState view = view_at(base);
    const cv::Mat image = renderer.render(world, view);
    const auto& k = view.intrinsics;
    auto grey_at = [&](const Eigen::Vector2d& xy) {
      const Eigen::Vector3d p = view.T_world_cam.inverse() *
                                Eigen::Vector3d(xy.x(), xy.y(), hole->z_bottom_m);
      const double u = k.fx_px * p.x() / p.z() + k.cx_px, v = k.fy_px * p.y() / p.z() + k.cy_px;
      EXPECT_TRUE(p.z() > 0 && u >= 0 && u < kWidthPx && v >= 0 && v < kHeightPx) << u << ", " << v;
      return static_cast<int>(image.at<uint8_t>(static_cast<int>(std::lround(v)),
                                                static_cast<int>(std::lround(u))));
    };
    const int inside = grey_at(hole->center_m);
    EXPECT_LT(inside, 80);  // plenum noise mean 45 (x 0.85 for a ceiling-high horizontal quad)
    const double out = 0.5 * hole->size_m.x() + 0.1;
    for (const Eigen::Vector2d& d : {Eigen::Vector2d(out, 0), Eigen::Vector2d(-out, 0),
                                     Eigen::Vector2d(0, out), Eigen::Vector2d(0, -out)})
      EXPECT_GT(grey_at(hole->center_m + d), inside + 60) << "beside the tile, offset " << d.transpose();
  }
}

}  // namespace
}  // namespace pepper::sim
