// The canonical ceiling view (core/ceiling) on the simulator's renders: two views of a textured
// ceiling from base poses a known translation apart, with the head pitched up, are related by the
// pure translation px_per_m x (the base's move) in the canonical image (phase correlation).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "core/ceiling/canonical_view.hpp"
#include "core/ceiling/landmarks.hpp"
#include "sim/mock_robot.hpp"
#include "sim/renderer.hpp"
#include "sim/world.hpp"

namespace pepper::sim {
namespace {

// A 20 m x 20 m hall: with the head fully up the walls stay below the bottom image row (they are
// 10 m away; the bottom row looks ~19 deg up), so the camera sees only the ceiling.
std::string hall_yaml(const std::string& ceiling_texture) {
  return R"(
textures:
  paint: {type: noise, mean: 180, contrast: 10}
  plaster: {type: noise, mean: 150, contrast: 70, feature_px: 12, octaves: 4, seed: 7, size_px: 512}
  tiles: {type: tiles, mean: 170, contrast: 60, cells: 8, seed: 3, size_px: 512}
floor: {texture: paint}
ceiling: {height_m: 2.6, texture: )" +
         ceiling_texture + R"(, tile_m: [4.8, 4.8]}
walls:
  - points: [[-10, -10], [10, -10], [10, 10], [-10, 10]]
    closed: true
    texture: paint
)";
}

RenderOptions clean_options() {
  RenderOptions o;
  o.noise_sigma_grey = 0.0;
  o.vignetting = 0.0;  // fixed in the camera image, it would not move with the ceiling
  o.motion_blur_exposure_s = 0.0;
  return o;
}

struct CeilingShot {
  cv::Mat canonical;
  cv::Mat seen;
};

// Renders the camera of a base at (x, y, yaw) with the head at `pitch_rad` and warps it.
CeilingShot shoot(const World& world, Renderer& renderer, const Pose2D& base, double pitch_rad,
                  const core::ceiling::CanonicalFrame& frame) {
  const CameraMount mount;
  Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();
  T_world_base.translation() = Eigen::Vector3d(base.x_m, base.y_m, 0.0);
  T_world_base.linear() =
      Eigen::AngleAxisd(base.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  ViewState view;
  view.T_world_cam = T_world_base * mount.T_base_cam(0.0, pitch_rad);
  view.intrinsics = core::CameraIntrinsics::pepper_top_vga().scaled_to(320, 240);
  const cv::Mat image = renderer.render(world, view);

  core::ceiling::CeilingCamera camera;
  camera.intrinsics = view.intrinsics;
  camera.head_pitch_rad = pitch_rad;
  camera.ceiling_above_cam_m = world.ceiling_height_m - view.T_world_cam.translation().z();
  const core::ceiling::CanonicalView canonical(camera, frame);
  CeilingShot shot;
  shot.canonical = canonical.warp(image, &shot.seen);
  return shot;
}

// Shift (du, dv) of b's content relative to a's, by phase correlation with a Hann window.
cv::Point2d content_shift(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat fa, fb, window;
  a.convertTo(fa, CV_64F);
  b.convertTo(fb, CV_64F);
  cv::createHanningWindow(window, a.size(), CV_64F);
  return cv::phaseCorrelate(fa, fb, window);
}

// A frame inside the camera's ceiling footprint at pitch -0.7068: 1.2 m wide, 1.8 m deep.
core::ceiling::CanonicalFrame inner_frame() {
  core::ceiling::CanonicalFrame frame;
  frame.px_per_m = 80.0;
  frame.width_px = 96;
  frame.height_px = 144;
  frame.center_forward_m = 2.1;
  return frame;
}

void expect_translation(const std::string& texture, const Pose2D& a, double forward_m,
                        double left_m) {
  SCOPED_TRACE(texture);
  const World world = parse_world(hall_yaml(texture), "ceiling_hall.yaml",
                                  std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds");
  Renderer renderer(clean_options());
  const double pitch = -0.7068;  // NAOqi's HeadPitch limit: fully up
  const auto frame = inner_frame();
  Pose2D b = a;
  b.x_m += forward_m * std::cos(a.yaw_rad) - left_m * std::sin(a.yaw_rad);
  b.y_m += forward_m * std::sin(a.yaw_rad) + left_m * std::cos(a.yaw_rad);
  const CeilingShot shot_a = shoot(world, renderer, a, pitch, frame);
  const CeilingShot shot_b = shoot(world, renderer, b, pitch, frame);
  // The premise: the whole frame is seen, and it shows texture (not a flat field).
  ASSERT_EQ(cv::countNonZero(shot_a.seen), frame.width_px * frame.height_px);
  cv::Scalar mean, stddev;
  cv::meanStdDev(shot_a.canonical, mean, stddev);
  ASSERT_GT(stddev[0], 8.0);
  // Moving forward by d moves the ceiling content down the canonical image by px_per_m d;
  // moving left moves it to the image's left (image right is the robot's left, seen from below).
  const cv::Point2d expected(-frame.px_per_m * left_m, frame.px_per_m * forward_m);
  const cv::Point2d shift = content_shift(shot_a.canonical, shot_b.canonical);
  EXPECT_NEAR(shift.x, expected.x, 1.5) << "measured " << shift << " expected " << expected;
  EXPECT_NEAR(shift.y, expected.y, 1.5) << "measured " << shift << " expected " << expected;
}

TEST(CeilingView, RendersOfATranslatedBaseDifferByThatTranslationInTheCanonicalView) {
  expect_translation("plaster", {0.3, -0.2, 0.0}, 0.15, 0.0);
  expect_translation("plaster", {0.3, -0.2, 0.0}, 0.0, 0.10);
  // Heading not along a world axis: the canonical axes follow the base, not the world.
  expect_translation("plaster", {-1.0, 0.7, 0.6}, 0.12, -0.08);
  // A tile grid (0.6 m tiles of random greys with grout lines), moved less than half a tile.
  expect_translation("tiles", {0.1, 0.25, -0.3}, 0.2, 0.1);
}

TEST(CeilingView, TileGroutLinesAreStraightAndEvenlySpacedInTheCanonicalView) {
  // Base heading along world x: the grout lines of 0.6 m tiles run along the canonical axes, so
  // the darkest rows of the canonical image are 0.6 m x 80 px/m = 48 px apart.
  const World world = parse_world(hall_yaml("tiles"), "ceiling_hall.yaml",
                                  std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds");
  Renderer renderer(clean_options());
  const auto frame = inner_frame();
  const CeilingShot shot = shoot(world, renderer, {0.0, 0.0, 0.0}, -0.7068, frame);
  cv::Mat row_mean;
  cv::reduce(shot.canonical, row_mean, 1, cv::REDUCE_AVG, CV_64F);
  // Local minima of the row profile well below the median grey are grout rows.
  std::vector<int> grout_rows;
  cv::Mat sorted;
  cv::sort(row_mean.reshape(1, 1), sorted, cv::SORT_ASCENDING);
  const double median = sorted.at<double>(0, sorted.cols / 2);
  for (int v = 1; v + 1 < row_mean.rows; ++v) {
    const double m = row_mean.at<double>(v);
    if (m < median - 15.0 && m <= row_mean.at<double>(v - 1) && m <= row_mean.at<double>(v + 1))
      grout_rows.push_back(v);
  }
  ASSERT_GE(grout_rows.size(), 2u) << "no grout lines found";
  for (size_t i = 1; i < grout_rows.size(); ++i)
    EXPECT_NEAR(grout_rows[i] - grout_rows[i - 1], 0.6 * frame.px_per_m, 2.0) << i;
}

// Landmarks (ORB on the canonical view) tracked between two renders give the base's motion: a
// translation as the same pure image translation, a turn on the spot as a rotation by -yaw (a
// left turn turns the content counter-clockwise on the screen, i.e. negative in image axes).
TEST(CeilingViewLandmarks, TrackingBetweenRendersRecoversTheBasesMotion) {
  for (const std::string texture : {"plaster", "tiles"}) {
    SCOPED_TRACE(texture);
    const World world = parse_world(hall_yaml(texture), "ceiling_hall.yaml",
                                    std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds");
    Renderer renderer(clean_options());
    const double pitch = -0.7068;
    core::ceiling::CeilingCamera camera;
    camera.intrinsics = core::CameraIntrinsics::pepper_top_vga().scaled_to(320, 240);
    camera.head_pitch_rad = pitch;
    camera.ceiling_above_cam_m = 1.45;  // only to size the frame
    const auto frame = core::ceiling::fit_frame(camera, 80.0, 3.5);
    const Pose2D a{0.4, -0.3, 0.2};
    const CeilingShot shot_a = shoot(world, renderer, a, pitch, frame);
    const auto la = core::ceiling::extract_landmarks(shot_a.canonical, shot_a.seen);
    ASSERT_GT(la.keypoints.size(), 50u);
    for (const auto& k : la.keypoints) {  // only where the camera sees the ceiling
      ASSERT_EQ(shot_a.seen.at<uint8_t>(cv::Point(k.pt)), 255);
    }

    // 0.12 m forward and 0.06 m to the left.
    Pose2D b = a;
    b.x_m += 0.12 * std::cos(a.yaw_rad) - 0.06 * std::sin(a.yaw_rad);
    b.y_m += 0.12 * std::sin(a.yaw_rad) + 0.06 * std::cos(a.yaw_rad);
    const CeilingShot shot_b = shoot(world, renderer, b, pitch, frame);
    const auto moved = core::ceiling::track_landmarks(
        la, core::ceiling::extract_landmarks(shot_b.canonical, shot_b.seen));
    ASSERT_TRUE(moved.found) << moved.matches << " matches, " << moved.inliers << " inliers";
    EXPECT_GE(moved.inliers, 30);
    EXPECT_NEAR(moved.scale, 1.0, 0.01);
    EXPECT_NEAR(moved.angle_rad, 0.0, 0.005);
    EXPECT_NEAR(moved.A_b_a(0, 2), -80.0 * 0.06, 1.0);
    EXPECT_NEAR(moved.A_b_a(1, 2), 80.0 * 0.12, 1.0);

    // A left turn on the spot by 0.12 rad.
    Pose2D c = a;
    c.yaw_rad += 0.12;
    const CeilingShot shot_c = shoot(world, renderer, c, pitch, frame);
    const auto turned = core::ceiling::track_landmarks(
        la, core::ceiling::extract_landmarks(shot_c.canonical, shot_c.seen));
    ASSERT_TRUE(turned.found) << turned.matches << " matches, " << turned.inliers << " inliers";
    EXPECT_NEAR(turned.scale, 1.0, 0.01);
    EXPECT_NEAR(turned.angle_rad, -0.12, 0.005);
  }
}

}  // namespace
}  // namespace pepper::sim
