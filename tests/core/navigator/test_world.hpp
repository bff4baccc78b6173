#pragma once
// A tiny deterministic renderer for navigation tests and benchmarks: a closed box room
// (walls textured with random grey rectangles and dots, plain floor and ceiling) seen by a
// pinhole camera on a unicycle base. Ray casting per pixel gives exact geometry (no clipping
// issues); bilinear texture lookup avoids aliasing. Conventions: world z up; base x forward,
// y left; camera x right, y down, z forward, optical axis horizontal, `delta_m` ahead of the
// base rotation axis, `height_m` above the floor (docs/conventions.md).
//
// Why not sim's World + Renderer: the same room drawn by sim::Renderer (camera effects and
// mipmaps off, every surface lit 1:1, texel centres aligned) differs from these images by 0.02
// grey levels on average and in 0.03 % of pixels by more than 1, mostly along texture edges
// (cv::remap interpolates at 1/32-pixel fixed point, the renderer in float). That moves the tour's
// fifth key image from frame 78 to 76 and lets VNHV keep its estimate for 5 blank frames
// instead of 2, stopping at +2.2 s where Navigator.VanishingFeaturesHoldThenStopWithReason
// asserted +1.6 s (it now asserts the design bound, +2.2 s). The navigator tests' measured
// bounds belong to this renderer.

#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/camera/intrinsics.hpp"
#include "core/frame.hpp"
#include "core/mapping/teacher.hpp"

namespace pepper::test {

struct Pose2d {
  double x_m = 0.0, y_m = 0.0, yaw_rad = 0.0;  ///< base in the world, yaw CCW from world x
};

class BoxWorld {
 public:
  /// Room [-half_x, half_x] x [-half_y, half_y] x [0, height], textures seeded by `seed`.
  BoxWorld(double half_x_m = 4.0, double half_y_m = 4.0, double room_height_m = 3.0,
           uint64_t seed = 7, double px_per_m = 120.0)
      : hx_(half_x_m), hy_(half_y_m), hz_(room_height_m), ppm_(px_per_m) {
    cv::RNG rng(seed);
    // Atlas: 4 walls side by side, each (wall length x room height) at px_per_m.
    wall_w_px_[0] = wall_w_px_[1] = static_cast<int>(2 * hy_ * ppm_);  // x = +hx, x = -hx
    wall_w_px_[2] = wall_w_px_[3] = static_cast<int>(2 * hx_ * ppm_);  // y = +hy, y = -hy
    const int h_px = static_cast<int>(hz_ * ppm_);
    int total = 0;
    for (int i = 0; i < 4; ++i) {
      wall_x0_px_[i] = total;
      total += wall_w_px_[i];
    }
    atlas_ = cv::Mat(h_px, total, CV_8UC1, cv::Scalar(128));
    for (int i = 0; i < 4; ++i) {
      cv::Mat wall = atlas_(cv::Rect(wall_x0_px_[i], 0, wall_w_px_[i], h_px));
      wall.setTo(cv::Scalar(rng.uniform(90, 170)));
      const int n_rect = static_cast<int>(2 * (i < 2 ? hy_ : hx_) * 9);
      for (int r = 0; r < n_rect; ++r) {
        const int w = rng.uniform(15, 90), h = rng.uniform(15, 110);
        const int x = rng.uniform(0, wall.cols - w), y = rng.uniform(0, h_px - h);
        cv::rectangle(wall, cv::Rect(x, y, w, h), cv::Scalar(rng.uniform(0, 256)), cv::FILLED);
      }
      for (int d = 0; d < n_rect * 3; ++d) {
        cv::circle(wall, {rng.uniform(0, wall.cols), rng.uniform(0, h_px)}, rng.uniform(2, 5),
                   cv::Scalar(rng.uniform(0, 256)), cv::FILLED);
      }
    }
    cv::GaussianBlur(atlas_, atlas_, cv::Size(3, 3), 0.8);
  }

  /// Renders the view of a camera on base pose `base` (floor plane). `blank` walls: uniform grey
  /// everywhere (no features at all).
  cv::Mat render(const Pose2d& base, const core::CameraIntrinsics& k, double delta_m = 0.05,
                 double height_m = 1.15, bool blank = false) const {
    cv::Mat map_x(k.height_px, k.width_px, CV_32F), map_y(k.height_px, k.width_px, CV_32F);
    cv::Mat plain(k.height_px, k.width_px, CV_8UC1, cv::Scalar(0));
    const double c = std::cos(base.yaw_rad), s = std::sin(base.yaw_rad);
    const double ox = base.x_m + delta_m * c, oy = base.y_m + delta_m * s, oz = height_m;
    for (int v = 0; v < k.height_px; ++v) {
      for (int u = 0; u < k.width_px; ++u) {
        const double xn = (u - k.cx_px) / k.fx_px, yn = (v - k.cy_px) / k.fy_px;
        // base frame direction (forward 1, left -xn, up -yn), then world.
        const double bx = 1.0, by = -xn, bz = -yn;
        const double dx = c * bx - s * by, dy = s * bx + c * by, dz = bz;
        double t = 1e30;
        int wall = -1;
        auto hit = [&](double tt, int w) {
          if (tt > 0 && tt < t) {
            t = tt;
            wall = w;
          }
        };
        if (dx > 1e-12) hit((hx_ - ox) / dx, 0);
        if (dx < -1e-12) hit((-hx_ - ox) / dx, 1);
        if (dy > 1e-12) hit((hy_ - oy) / dy, 2);
        if (dy < -1e-12) hit((-hy_ - oy) / dy, 3);
        if (dz < -1e-12) hit(-oz / dz, 4);
        if (dz > 1e-12) hit((hz_ - oz) / dz, 5);
        const double px = ox + t * dx, py = oy + t * dy, pz = oz + t * dz;
        float ax = -1, ay = -1;
        if (wall >= 0 && wall < 4) {
          // Horizontal coordinate along the wall (seen from inside, left to right).
          double along = 0;
          if (wall == 0) along = py + hy_;
          if (wall == 1) along = hy_ - py;
          if (wall == 2) along = hx_ - px;
          if (wall == 3) along = px + hx_;
          ax = static_cast<float>(wall_x0_px_[wall] +
                                  std::clamp(along * ppm_, 0.0, wall_w_px_[wall] - 1.0));
          ay = static_cast<float>(std::clamp((hz_ - pz) * ppm_, 0.0, atlas_.rows - 1.0));
        } else {
          plain.at<uint8_t>(v, u) = wall == 4 ? 70 : 200;  // floor darker than ceiling
        }
        if (blank) ax = ay = -1;
        map_x.at<float>(v, u) = ax;
        map_y.at<float>(v, u) = ay;
      }
    }
    cv::Mat out;
    cv::remap(atlas_, out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
    if (blank) return cv::Mat(k.height_px, k.width_px, CV_8UC1, cv::Scalar(128));
    const cv::Mat mask = map_x < 0;
    plain.copyTo(out, mask);
    return out;
  }

 private:
  double hx_, hy_, hz_, ppm_;
  int wall_w_px_[4]{};
  int wall_x0_px_[4]{};
  cv::Mat atlas_;
};

/// A unicycle path: a straight run along world +x from (x0, y0), a left turn of `turn_rad` on an
/// arc of radius `radius_m`, then another straight run. Samples every `step_m` of travel (arc
/// length), yaw following the path.
inline std::vector<Pose2d> straight_turn_straight(double x0, double y0, double run1_m,
                                                  double turn_rad, double radius_m, double run2_m,
                                                  double step_m) {
  std::vector<Pose2d> out;
  const double arc = std::abs(turn_rad) * radius_m;
  const double total = run1_m + arc + run2_m;
  for (double s = 0; s <= total + 1e-9; s += step_m) {
    Pose2d p;
    if (s <= run1_m) {
      p = {x0 + s, y0, 0.0};
    } else if (s <= run1_m + arc) {
      const double a = (s - run1_m) / radius_m * (turn_rad > 0 ? 1 : -1);
      const double sign = turn_rad > 0 ? 1.0 : -1.0;
      p = {x0 + run1_m + radius_m * std::sin(std::abs(a)), y0 + sign * radius_m * (1 - std::cos(a)),
           a};
    } else {
      const double sign = turn_rad > 0 ? 1.0 : -1.0;
      const double ex = x0 + run1_m + radius_m * std::sin(std::abs(turn_rad));
      const double ey = y0 + sign * radius_m * (1 - std::cos(turn_rad));
      const double d = s - run1_m - arc;
      p = {ex + d * std::cos(turn_rad), ey + d * std::sin(turn_rad), turn_rad};
    }
    out.push_back(p);
  }
  return out;
}

inline std::vector<core::Frame> render_frames(const BoxWorld& world,
                                              const std::vector<Pose2d>& path,
                                              const core::CameraIntrinsics& k, double fps = 5.0) {
  std::vector<core::Frame> frames;
  for (size_t i = 0; i < path.size(); ++i) {
    core::Frame f;
    f.gray = world.render(path[i], k);
    f.t_ns = static_cast<int64_t>(1e9 * static_cast<double>(i) / fps);
    f.index = static_cast<int64_t>(i);
    frames.push_back(f);
  }
  return frames;
}

/// The tour shared by the mapping and navigator tests (built once per test binary): in the
/// default BoxWorld, from (-3, -2) heading +x: 2.5 m straight, 60 deg left turn on a 0.8 m
/// radius, 1.5 m straight; 4.5 cm per frame at 5 Hz (0.225 m/s); QVGA Pepper camera. Taught with
/// the paper's absolute rule (relative = 0) and epsilon = 120: this world's images carry up to
/// ~300 corners + ~100 lines; 120 gives 11 key images, 7 of them in the turn. The frames are
/// 4.5 cm apart (3x the mock robot's), so the navigator tests keep this fixed, hand-checked map.
struct SharedTour {
  core::CameraIntrinsics camera;
  std::vector<Pose2d> path;
  std::vector<core::Frame> frames;
  core::mapping::TeachOptions teach_options;
  std::vector<core::mapping::TeachStep> steps;  ///< of the offline teach
  core::memory::VisualMemory map;               ///< offline teach of `frames`
};

inline const BoxWorld& shared_world() {
  static const BoxWorld world;
  return world;
}

inline const SharedTour& shared_tour() {
  static const SharedTour tour = [] {
    SharedTour t;
    t.camera = core::CameraIntrinsics::pepper_top_vga().scaled_to(320, 240);
    t.path = straight_turn_straight(-3.0, -2.0, 2.5, 1.0472, 0.8, 1.5, 0.045);
    t.frames = render_frames(shared_world(), t.path, t.camera);
    t.teach_options.selector.epsilon = 120;
    t.teach_options.selector.relative = 0.0;
    t.map = core::mapping::teach_offline(t.frames, t.camera, t.teach_options, "{}", &t.steps);
    return t;
  }();
  return tour;
}

}  // namespace pepper::test
