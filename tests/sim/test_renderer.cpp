// Renderer: projection accuracy, near-plane clipping cases, determinism, sizes, exposure, blur.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/camera/distortion.hpp"
#include "sim/mock_robot.hpp"
#include "sim/renderer.hpp"
#include "sim/world.hpp"

namespace pepper::sim {
namespace {

// Camera frame (x right, y down, z forward) looking along world +x from (0, 0, h).
Eigen::Isometry3d camera_looking_along_x(double height_m) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  Eigen::Matrix3d R;
  // clang-format off
  R << 0, 0, 1,
      -1, 0, 0,
       0,-1, 0;
  // clang-format on
  T.linear() = R;
  T.translation() = Eigen::Vector3d(0, 0, height_m);
  return T;
}

Texture uniform_texture(const std::string& name, int grey) {
  return Texture(name, cv::Mat(16, 16, CV_8UC1, cv::Scalar(grey)), true);
}

// A vertical quad facing -x at x = x_m, spanning y in [y0, y1] and z in [z0, z1].
Quad wall_x(double x_m, double y0, double y1, double z0, double z1, int texture) {
  Quad q;
  q.origin_m = {x_m, y1, z1};
  q.axis_u = {0, -1, 0};
  q.axis_v = {0, 0, -1};
  q.size_u_m = y1 - y0;
  q.size_v_m = z1 - z0;
  q.texture = texture;
  q.tile_u_m = q.size_u_m;
  q.tile_v_m = q.size_v_m;
  return q;
}

RenderOptions clean_options() {
  RenderOptions o;
  o.noise_sigma_grey = 0.0;
  o.optics_blur = false;
  o.vignetting = 0.0;
  o.motion_blur_exposure_s = 0.0;
  return o;
}

// The world's key-light shading of a wall facing -x: 0.72 + 0.28 |cos(key)| (renderer.cpp).
double wall_shade(const World& w) { return 0.72 + 0.28 * std::abs(std::cos(w.key_light_rad)); }

World square_world(const Eigen::Vector3d& centre, double side_m) {
  World w;
  w.textures.push_back(uniform_texture("grey", 60));
  w.textures.push_back(uniform_texture("white", 250));
  w.quads.push_back(wall_x(6.0, -10, 10, -5, 5, 0));
  w.quads.push_back(wall_x(centre.x(), centre.y() - side_m / 2, centre.y() + side_m / 2,
                           centre.z() - side_m / 2, centre.z() + side_m / 2, 1));
  return w;
}

cv::Point2d bright_centroid(const cv::Mat& img, int threshold) {
  cv::Mat mask = img > threshold;
  const cv::Moments m = cv::moments(mask, true);
  return {m.m10 / m.m00, m.m01 / m.m00};
}

TEST(Renderer, SquareCentroidLandsOnProjectedPixel) {
  const double h = 1.2;
  const Eigen::Isometry3d T_world_cam = camera_looking_along_x(h);
  for (const auto& size : {cv::Size(640, 480), cv::Size(320, 240), cv::Size(1280, 960)}) {
    for (const Eigen::Vector3d& p :
         {Eigen::Vector3d(4.0, 0.3, 1.5), Eigen::Vector3d(3.0, -0.7, 0.9),
          Eigen::Vector3d(5.0, 1.1, 1.0)}) {
      const World w = square_world(p, 0.12);
      Renderer r(clean_options());
      ViewState view;
      view.T_world_cam = T_world_cam;
      view.intrinsics = core::CameraIntrinsics::pepper_top_vga().scaled_to(size.width, size.height);
      const cv::Mat img = r.render(w, view);
      ASSERT_EQ(img.size(), size);
      const Eigen::Vector3d pc = T_world_cam.inverse() * p;
      const double u = view.intrinsics.fx_px * pc.x() / pc.z() + view.intrinsics.cx_px;
      const double v = view.intrinsics.fy_px * pc.y() / pc.z() + view.intrinsics.cy_px;
      const cv::Point2d c = bright_centroid(img, 150);
      // Within a pixel (the brief); the square covers >= 12 px across, so the centroid of the
      // pixels whose centres fall inside is within a fraction of a pixel of the projection.
      EXPECT_NEAR(c.x, u, 1.0) << size << " point " << p.transpose();
      EXPECT_NEAR(c.y, v, 1.0) << size << " point " << p.transpose();
      // Left of the image is +y in the world: a point at y > 0 projects left of cx.
      if (p.y() > 0) {
        EXPECT_LT(c.x, view.intrinsics.cx_px);
      }
    }
  }
}

// Intrinsics with ViSP's distortion model render through the lens (issue 31): a square near the
// image corner lands where ViSP's meter -> pixel conversion (kud) puts it, several pixels from
// its pinhole projection; at the centre nothing moves.
TEST(Renderer, DistortionModelMovesPointsWhereViSPsModelPutsThem) {
  const double h = 1.2;
  const Eigen::Isometry3d T_world_cam = camera_looking_along_x(h);
  core::CameraIntrinsics k = core::CameraIntrinsics::pepper_top_vga();
  k.model = core::ProjectionModel::kWithDistortion;
  k.kud = 0.03;  // Pepper's top camera (PEPPER.md)
  k.kdu = -0.029;
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(3.0, 1.5, 2.2), Eigen::Vector3d(3.0, -1.4, 0.25),
                                   Eigen::Vector3d(4.0, 0.0, h)}) {
    const World w = square_world(p, 0.12);
    Renderer r(clean_options());
    ViewState view;
    view.T_world_cam = T_world_cam;
    view.intrinsics = k;
    const cv::Mat img = r.render(w, view);
    const Eigen::Vector3d pc = T_world_cam.inverse() * p;
    const cv::Point2d n{pc.x() / pc.z(), pc.y() / pc.z()};
    const cv::Point2d lens = core::camera::norm_to_pixel(k, n);
    const cv::Point2d pinhole = k.denormalize(n);
    const cv::Point2d c = bright_centroid(img, 150);
    EXPECT_NEAR(c.x, lens.x, 1.0) << "point " << p.transpose();
    EXPECT_NEAR(c.y, lens.y, 1.0) << "point " << p.transpose();
    if (std::hypot(n.x, n.y) > 0.5) {
      EXPECT_GT(std::hypot(c.x - pinhole.x, c.y - pinhole.y), 2.5) << "point " << p.transpose();
    }
  }
}

TEST(Renderer, SquareValueIsTextureTimesShading) {
  const World w = square_world({4.0, 0.0, 1.2}, 0.3);
  Renderer r(clean_options());
  ViewState view;
  view.T_world_cam = camera_looking_along_x(1.2);
  const cv::Mat img = r.render(w, view);
  const double k = wall_shade(w);
  EXPECT_NEAR(img.at<uint8_t>(238, 319), 250 * k, 1.0);  // the square (at the principal point)
  EXPECT_NEAR(img.at<uint8_t>(20, 20), 60 * k, 1.0);     // the grey wall behind it
}

// Wall on the left along the optical axis, extending behind the camera; floor below.
World corridor_world() {
  World w;
  w.textures.push_back(uniform_texture("wall", 200));
  w.textures.push_back(uniform_texture("floor", 80));
  Quad wall;
  wall.origin_m = {-5, 0.25, 2.5};
  wall.axis_u = {1, 0, 0};
  wall.axis_v = {0, 0, -1};
  wall.size_u_m = 15;
  wall.size_v_m = 2.5;
  wall.texture = 0;
  w.quads.push_back(wall);
  Quad floor;
  floor.origin_m = {-5, 5, 0};
  floor.axis_u = {1, 0, 0};
  floor.axis_v = {0, -1, 0};
  floor.size_u_m = 15;
  floor.size_v_m = 10;
  floor.texture = 1;
  floor.is_floor = true;
  w.quads.push_back(floor);
  return w;
}

TEST(Renderer, WallBesideAndBehindCameraIsClipped) {
  const World w = corridor_world();
  Renderer r(clean_options());
  ViewState view;
  view.T_world_cam = camera_looking_along_x(1.15);
  const cv::Mat img = r.render(w, view);
  // The wall 0.25 m to the left fills the left edge from top to bottom (it extends behind the
  // camera, so without near-plane clipping it would wrap around or crash).
  const double wall_grey = 200 * (0.72 + 0.28 * std::abs(std::sin(w.key_light_rad)));
  for (int row : {5, 120, 240, 360}) EXPECT_NEAR(img.at<uint8_t>(row, 2), wall_grey, 1.5) << row;
  // Floor at the bottom right, nothing seen at the top right (background).
  EXPECT_NEAR(img.at<uint8_t>(470, 600), 80, 1.0);
  EXPECT_NEAR(img.at<uint8_t>(10, 630), clean_options().background_grey, 1.0);
  EXPECT_GT(r.last_stats().pixels_shaded, 640 * 480 / 3);
  const cv::Mat depth = r.depth_m();
  EXPECT_LT(depth.at<float>(240, 0), 0.6f);  // wall at 0.25 m seen at ~28 deg off axis
}

TEST(Renderer, CameraFacingAwayFromWallSeesOnlyFloor) {
  World w = corridor_world();
  w.quads[0].origin_m = {-1.0, 5, 2.5};  // wall at x = -1, facing the camera's back
  w.quads[0].axis_u = {0, -1, 0};
  w.quads[0].size_u_m = 10;
  Renderer r(clean_options());
  ViewState view;
  view.T_world_cam = camera_looking_along_x(1.15);
  const cv::Mat img = r.render(w, view);
  EXPECT_NEAR(img.at<uint8_t>(470, 320), 80, 1.0);
  EXPECT_NEAR(img.at<uint8_t>(100, 320), clean_options().background_grey, 1.0);
}

TEST(Renderer, WallThroughCameraCentreIsSkippedWithoutError) {
  World w = corridor_world();
  w.quads[0].origin_m.y() = 0.0;  // the wall's plane contains the optical centre (y = 0)
  Renderer r(clean_options());
  ViewState view;
  view.T_world_cam = camera_looking_along_x(1.15);
  cv::Mat img;
  ASSERT_NO_THROW(r.render(w, view, img));
  EXPECT_NEAR(img.at<uint8_t>(470, 600), 80, 1.0);
  EXPECT_NEAR(img.at<uint8_t>(470, 40), 80, 1.0);  // floor on both sides: the wall is edge-on
}

TEST(Renderer, CameraInsideAWallPlaneAtEveryHeadingRendersSanely) {
  const auto world = std::make_shared<const World>(
      load_world(std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds/robotics_room.yaml"));
  Renderer r;
  for (double yaw_deg = 0; yaw_deg < 360; yaw_deg += 45) {
    // Base 10 cm from the south wall (y = 0): the camera is 5 to 15 cm from it, the wall passes
    // beside and behind the camera, or through its image plane, depending on the heading.
    Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();
    T_world_base.translation() = Eigen::Vector3d(4.0, 0.1, 0.0);
    T_world_base.linear() =
        Eigen::AngleAxisd(yaw_deg * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    ViewState view;
    view.T_world_cam = T_world_base * CameraMount{}.T_base_cam(0, 0);
    cv::Mat img;
    ASSERT_NO_THROW(r.render(*world, view, img));
    const double mean = cv::mean(img)[0];
    EXPECT_GT(mean, 20.0) << yaw_deg;
    EXPECT_LT(mean, 250.0) << yaw_deg;
  }
}

TEST(Renderer, IdenticalSeedsGiveIdenticalImages) {
  const World w = corridor_world();
  RenderOptions o;
  o.noise_sigma_grey = 3.0;
  o.noise_seed = 7;
  Renderer a(o), b(o);
  ViewState view;
  view.T_world_cam = camera_looking_along_x(1.15);
  view.frame_index = 3;
  const cv::Mat ia = a.render(w, view), ib = b.render(w, view);
  EXPECT_EQ(cv::norm(ia, ib, cv::NORM_INF), 0.0);
  o.noise_seed = 8;
  Renderer c(o);
  EXPECT_GT(cv::norm(ia, c.render(w, view), cv::NORM_L1), 0.0);
  view.frame_index = 4;  // another frame, other noise
  EXPECT_GT(cv::norm(ia, a.render(w, view), cv::NORM_L1), 0.0);
}

TEST(Renderer, DifferentSizesGiveConsistentImages) {
  const auto world =
      load_world(std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds/room_corridor_room.yaml");
  Renderer r(clean_options());
  ViewState view;
  Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();
  T_world_base.translation() = Eigen::Vector3d(7.0, 3.5, 0.0);
  T_world_base.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  view.T_world_cam = T_world_base * CameraMount{}.T_base_cam(0, 0);
  view.intrinsics = core::CameraIntrinsics::pepper_top_vga().scaled_to(640, 480);
  const cv::Mat vga = r.render(world, view);
  for (const auto& size :
       {cv::Size(160, 120), cv::Size(320, 240), cv::Size(333, 222), cv::Size(1280, 960)}) {
    view.intrinsics = core::CameraIntrinsics::pepper_top_vga().scaled_to(size.width, size.height);
    const cv::Mat img = r.render(world, view);
    ASSERT_EQ(img.size(), size);
    cv::Mat small_vga, small_img;
    cv::resize(vga, small_vga, cv::Size(64, 48), 0, 0, cv::INTER_AREA);
    cv::resize(img, small_img, cv::Size(64, 48), 0, 0, cv::INTER_AREA);
    // Same view at another resolution: the 64x48 thumbnails agree to a few grey levels.
    EXPECT_LT(cv::norm(small_vga, small_img, cv::NORM_L1) / (64 * 48), 6.0) << size;
  }
}

TEST(Renderer, LowerLightGivesDarkerImage) {
  const World w = corridor_world();
  Renderer r(clean_options());
  ViewState view;
  view.T_world_cam = camera_looking_along_x(1.15);
  const double bright = cv::mean(r.render(w, view))[0];
  view.light.ambient = 0.5;
  const double dark = cv::mean(r.render(w, view))[0];
  EXPECT_LT(dark, 0.75 * bright);
}

TEST(Renderer, RotationBlursHorizontally) {
  const auto world =
      load_world(std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds/robotics_room.yaml");
  RenderOptions o = clean_options();
  o.motion_blur_exposure_s = 0.03;
  Renderer r(o);
  ViewState view;
  Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();
  T_world_base.translation() = Eigen::Vector3d(2.0, 1.8, 0.0);
  view.T_world_cam = T_world_base * CameraMount{}.T_base_cam(0, 0);
  auto gradient_energy = [](const cv::Mat& img) {
    cv::Mat gx;
    cv::Sobel(img, gx, CV_32F, 1, 0);
    return cv::norm(gx, cv::NORM_L2);  // energy: a blur spreads edges
  };
  const double still = gradient_energy(r.render(world, view));
  view.yaw_rate_cam_rad_s = 1.0;  // 0.03 s * 1 rad/s * 596 px = 18 px of blur
  const double turning = gradient_energy(r.render(world, view));
  EXPECT_LT(turning, 0.6 * still);
}

TEST(Renderer, RejectsInvalidOptionsAndIntrinsics) {
  RenderOptions o;
  o.near_m = 0.0;
  EXPECT_THROW(Renderer{o}, std::invalid_argument);
  Renderer r;
  ViewState view;
  view.intrinsics.fx_px = -1;
  cv::Mat img;
  EXPECT_THROW(r.render(corridor_world(), view, img), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::sim
