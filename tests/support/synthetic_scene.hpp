#pragma once
// Synthetic scenes with known ground truth for perception tests: 3D line segments and points in a
// room seen by a camera moving on the floor plane (horizontal optical axis, fixed height, Pepper
// VGA intrinsics), projected with pixel noise and a chosen fraction of outlier correspondences.
//
// World frame of this helper (not the project's `world`): camera-like axes, x right, y DOWN,
// z forward at yaw 0; the camera centre is at height `camera_height_m` above the floor, i.e. the
// floor is the plane y = +camera_height_m and the camera centres have y = 0.
// A pose is (yaw_rad, cx_m, cz_m): X_cam = R_y(yaw) (X_world - C), C = (cx_m, 0, cz_m), with
// R_y(a) = [[cos a, 0, sin a], [0, 1, 0], [-sin a, 0, cos a]] (as geometry/planar_trifocal.hpp).
// Deterministic: everything is drawn from std::mt19937_64(seed).

#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <opencv2/core/matx.hpp>
#include <opencv2/core/types.hpp>

#include "core/camera/intrinsics.hpp"
#include "core/geometry/planar_trifocal.hpp"

namespace pepper::test {

struct PlanarPose {
  double yaw_rad = 0.0;
  double cx_m = 0.0;
  double cz_m = 0.0;
};

inline cv::Matx33d rot_y(double a) {
  const double c = std::cos(a), s = std::sin(a);
  return {c, 0, s, 0, 1, 0, -s, 0, c};
}

inline cv::Vec3d to_cam(const PlanarPose& p, const cv::Vec3d& X_world) {
  return rot_y(p.yaw_rad) * (X_world - cv::Vec3d(p.cx_m, 0.0, p.cz_m));
}

/// Ground-truth motion of views 1, 2 relative to view 0 (planar_trifocal.hpp convention), with
/// translations scaled to |t1|^2 + |t2|^2 = 1 (the estimator's normalisation, sign free).
inline core::geometry::PlanarMotion3 relative_motion(const std::array<PlanarPose, 3>& poses) {
  core::geometry::PlanarMotion3 m;
  const cv::Vec3d c0(poses[0].cx_m, 0, poses[0].cz_m);
  double norm2 = 0.0;
  for (int i = 1; i < 3; ++i) {
    m.yaw_rad[static_cast<size_t>(i)] = poses[static_cast<size_t>(i)].yaw_rad - poses[0].yaw_rad;
    const cv::Vec3d ci(poses[static_cast<size_t>(i)].cx_m, 0, poses[static_cast<size_t>(i)].cz_m);
    const cv::Vec3d t = rot_y(poses[static_cast<size_t>(i)].yaw_rad) * (c0 - ci);
    m.t_xz[static_cast<size_t>(i)] = cv::Vec2d(t[0], t[2]);
    norm2 += t[0] * t[0] + t[2] * t[2];
  }
  const double n = std::sqrt(norm2);
  if (n > 0) {
    for (int i = 1; i < 3; ++i) m.t_xz[static_cast<size_t>(i)] /= n;
  }
  return m;
}

struct SceneOptions {
  double camera_height_m = 1.15;
  double pixel_noise_px = 0.5;     ///< std-dev of the Gaussian noise on every image coordinate
  double outlier_fraction = 0.4;   ///< fraction of correspondences made wrong in one view
  int num_lines = 120;             ///< visible line triplets wanted
  int num_points = 200;            ///< visible point pairs wanted
  double min_depth_m = 1.0;
  double max_depth_m = 8.0;
  double min_segment_px = 30.0;    ///< visible segments shorter than this are redrawn
  double min_visible_depth_m = 1.0;  ///< every observed 3D point is at least this far in front
};

struct SyntheticLines {
  std::vector<core::geometry::LineTriplet> triplets;
  std::vector<bool> is_inlier;
};

struct SyntheticPoints {
  std::vector<cv::Point2d> a_norm;
  std::vector<cv::Point2d> b_norm;
  std::vector<bool> is_inlier;
};

class SyntheticScene {
 public:
  SyntheticScene(core::CameraIntrinsics k, SceneOptions o, uint64_t seed)
      : k_(k), o_(o), rng_(seed) {}

  /// Random 3D segment in front of the reference pose: vertical (35%), horizontal (45%: wall,
  /// floor or ceiling edges, any heading) or any direction (20%).
  std::array<cv::Vec3d, 2> random_segment(const PlanarPose& ref) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double depth = o_.min_depth_m + (o_.max_depth_m - o_.min_depth_m) * u(rng_);
    const double lateral = (u(rng_) - 0.5) * 1.6 * depth;
    const double y = -1.5 + (o_.camera_height_m + 1.5) * u(rng_);  // ceiling 2.65 m .. floor
    const cv::Vec3d centre_cam(lateral, y, depth);
    const cv::Vec3d centre = rot_y(ref.yaw_rad).t() * centre_cam + cv::Vec3d(ref.cx_m, 0, ref.cz_m);
    cv::Vec3d dir;
    const double kind = u(rng_);
    if (kind < 0.35) {
      dir = {0, 1, 0};
    } else if (kind < 0.8) {
      const double h = 2.0 * M_PI * u(rng_);
      dir = {std::cos(h), 0, std::sin(h)};
    } else {
      dir = cv::normalize(cv::Vec3d(u(rng_) - 0.5, u(rng_) - 0.5, u(rng_) - 0.5));
    }
    const double half = 0.3 + 1.2 * u(rng_);
    return {centre - half * dir, centre + half * dir};
  }

  /// Projects X (world) into pose p: pixel, false if behind or outside the image.
  bool project(const PlanarPose& p, const cv::Vec3d& X, cv::Point2d& px) const {
    const cv::Vec3d c = to_cam(p, X);
    if (c[2] < o_.min_visible_depth_m) return false;
    px = k_.denormalize({c[0] / c[2], c[1] / c[2]});
    return px.x >= 0 && px.y >= 0 && px.x <= k_.width_px - 1 && px.y <= k_.height_px - 1;
  }

  cv::Point2d noisy_norm(const cv::Point2d& px) {
    std::normal_distribution<double> n(0.0, o_.pixel_noise_px);
    return k_.normalize({px.x + n(rng_), px.y + n(rng_)});
  }

  cv::Point2d random_px() {
    std::uniform_real_distribution<double> ux(0.0, k_.width_px - 1.0), uy(0.0, k_.height_px - 1.0);
    return {ux(rng_), uy(rng_)};
  }

  /// Line triplets seen from three poses; each view sees its own random sub-segment (detected
  /// extents differ between views). Outliers: one random view's segment replaced by a random one.
  SyntheticLines lines(const std::array<PlanarPose, 3>& poses) {
    SyntheticLines out;
    std::uniform_real_distribution<double> u(0.0, 1.0);
    int guard = 0;
    while (static_cast<int>(out.triplets.size()) < o_.num_lines && guard++ < 200000) {
      const auto seg = random_segment(poses[0]);
      core::geometry::LineTriplet t;
      bool ok = true;
      for (size_t v = 0; v < 3 && ok; ++v) {
        const double s0 = 0.25 * u(rng_), s1 = 1.0 - 0.25 * u(rng_);
        cv::Point2d a, b;
        ok = project(poses[v], seg[0] + s0 * (seg[1] - seg[0]), a) &&
             project(poses[v], seg[0] + s1 * (seg[1] - seg[0]), b) &&
             cv::norm(a - b) >= o_.min_segment_px;
        if (ok) t.view[v] = {noisy_norm(a), noisy_norm(b)};
      }
      if (!ok) continue;
      const bool outlier = u(rng_) < o_.outlier_fraction;
      if (outlier) {
        const size_t v = static_cast<size_t>(std::min(2.0, std::floor(3.0 * u(rng_))));
        cv::Point2d a = random_px(), b = random_px();
        while (cv::norm(a - b) < o_.min_segment_px) b = random_px();
        t.view[v] = {k_.normalize(a), k_.normalize(b)};
      }
      out.triplets.push_back(t);
      out.is_inlier.push_back(!outlier);
    }
    return out;
  }

  /// Point pairs seen from two poses, outliers replaced by a random point in view b.
  SyntheticPoints points(const PlanarPose& a, const PlanarPose& b) {
    SyntheticPoints out;
    std::uniform_real_distribution<double> u(0.0, 1.0);
    int guard = 0;
    while (static_cast<int>(out.a_norm.size()) < o_.num_points && guard++ < 200000) {
      const double depth = o_.min_depth_m + (o_.max_depth_m - o_.min_depth_m) * u(rng_);
      const cv::Vec3d cam((u(rng_) - 0.5) * 1.4 * depth, -1.5 + (o_.camera_height_m + 1.5) * u(rng_), depth);
      const cv::Vec3d X = rot_y(a.yaw_rad).t() * cam + cv::Vec3d(a.cx_m, 0, a.cz_m);
      cv::Point2d pa, pb;
      if (!project(a, X, pa) || !project(b, X, pb)) continue;
      const bool outlier = u(rng_) < o_.outlier_fraction;
      out.a_norm.push_back(noisy_norm(pa));
      out.b_norm.push_back(outlier ? k_.normalize(random_px()) : noisy_norm(pb));
      out.is_inlier.push_back(!outlier);
    }
    return out;
  }

 private:
  core::CameraIntrinsics k_;
  SceneOptions o_;
  std::mt19937_64 rng_;
};

/// Recall (verified true inliers / all true inliers) and contamination (verified outliers /
/// verified) of a verified index set.
struct VerificationScore {
  double recall = 0.0;
  double contamination = 0.0;
  int verified = 0;
};

inline VerificationScore score(const std::vector<int>& verified, const std::vector<bool>& is_inlier) {
  VerificationScore s;
  int true_total = 0, true_found = 0, false_found = 0;
  for (bool b : is_inlier) true_total += b ? 1 : 0;
  for (int i : verified) (is_inlier[static_cast<size_t>(i)] ? true_found : false_found)++;
  s.verified = static_cast<int>(verified.size());
  s.recall = true_total > 0 ? static_cast<double>(true_found) / true_total : 1.0;
  s.contamination = s.verified > 0 ? static_cast<double>(false_found) / s.verified : 0.0;
  return s;
}

}  // namespace pepper::test
