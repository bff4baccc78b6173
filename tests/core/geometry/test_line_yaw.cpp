// Relative yaw from matched horizontal lines: the yaw of random planar motions seen by a pitched
// camera, with endpoint noise, vertical lines (no yaw information) and mismatched pairs; the
// translation must not matter; too little or contradicting evidence is "no estimate".
#include "core/geometry/line_yaw.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "core/camera/intrinsics.hpp"

namespace pepper::core::geometry {
namespace {

using Pairs = std::vector<std::pair<NormSegment, NormSegment>>;

// Level frame (x right, y down, z forward) -> pitched camera: x_cam = R_x(pitch) x_level.
cv::Vec3d to_cam(const cv::Vec3d& X_level, double pitch_rad) {
  const double c = std::cos(pitch_rad), s = std::sin(pitch_rad);
  return {X_level[0], c * X_level[1] - s * X_level[2], s * X_level[1] + c * X_level[2]};
}

// View b at X_b = R_y(yaw) X_a + t (level frames), as in line_yaw.hpp.
cv::Vec3d a_to_b(const cv::Vec3d& X, double yaw_rad, const cv::Vec3d& t) {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  return cv::Vec3d(c * X[0] + s * X[2], X[1], -s * X[0] + c * X[2]) + t;
}

struct Scene {
  Pairs pairs;
  int horizontal = 0;
};

// A room's horizontal lines (skirting 1.1 m below the camera, lintels and tile edges above,
// walls ahead and to both sides, 1.5 to 6 m away) and vertical lines (door frames), projected
// into views a and b; endpoints clipped to the image, noise in pixels; `mismatches` pairs get a
// random other segment in b.
Scene make_scene(double yaw_rad, const cv::Vec3d& t, double pitch_rad, int n_horizontal,
                 int n_vertical, int mismatches, double noise_px, uint64_t seed) {
  const CameraIntrinsics k = CameraIntrinsics::pepper_top_vga();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, noise_px / k.fx_px);
  auto project = [&](const cv::Vec3d& X_level, cv::Point2d& out) {
    const cv::Vec3d c = to_cam(X_level, pitch_rad);
    if (c[2] < 0.3) return false;
    out = {c[0] / c[2], c[1] / c[2]};
    const cv::Point2d px = k.denormalize(out);
    return px.x >= 0 && px.y >= 0 && px.x < k.width_px && px.y < k.height_px;
  };
  auto segment = [&](const cv::Vec3d& A, const cv::Vec3d& B, NormSegment& sa, NormSegment& sb) {
    // Several points along the 3D segment; the projected segment is the first and last visible.
    std::vector<cv::Point2d> va, vb;
    for (int i = 0; i <= 20; ++i) {
      const cv::Vec3d X = A + (B - A) * (i / 20.0);
      cv::Point2d pa, pb;
      if (project(X, pa) && project(a_to_b(X, yaw_rad, t), pb)) {
        va.push_back(pa);
        vb.push_back(pb);
      }
    }
    if (va.size() < 4) return false;
    auto jitter = [&](cv::Point2d p) { return cv::Point2d(p.x + noise(rng), p.y + noise(rng)); };
    sa = {jitter(va.front()), jitter(va.back())};
    sb = {jitter(vb.front()), jitter(vb.back())};
    return true;
  };
  Scene s;
  int guard = 0;
  while (s.horizontal < n_horizontal && guard++ < 20000) {
    // A horizontal line on a wall at a random bearing, height and distance.
    const double bearing = (u(rng) - 0.5) * 2.4;
    const double dist = 1.5 + 4.5 * u(rng);
    const double height = u(rng) < 0.5 ? 1.1 : -0.4 - 1.4 * u(rng);  // y down: floor at +1.1
    const double wall_angle = bearing + std::numbers::pi / 2 + (u(rng) - 0.5) * 1.2;
    const cv::Vec3d C(dist * std::sin(bearing), height, dist * std::cos(bearing));
    const cv::Vec3d dir(std::sin(wall_angle), 0.0, std::cos(wall_angle));
    const double half = 0.3 + 1.2 * u(rng);
    NormSegment sa, sb;
    if (segment(C - dir * half, C + dir * half, sa, sb)) {
      s.pairs.push_back({sa, sb});
      ++s.horizontal;
    }
  }
  int vertical = 0;
  guard = 0;
  while (vertical < n_vertical && guard++ < 20000) {
    const double bearing = (u(rng) - 0.5) * 1.6;
    const double dist = 1.5 + 4.5 * u(rng);
    const cv::Vec3d C(dist * std::sin(bearing), 0.0, dist * std::cos(bearing));
    NormSegment sa, sb;
    if (segment(C + cv::Vec3d(0, -0.9, 0), C + cv::Vec3d(0, 1.0, 0), sa, sb)) {
      s.pairs.push_back({sa, sb});
      ++vertical;
    }
  }
  const size_t real = s.pairs.size();
  for (int m = 0; m < mismatches && real > 1; ++m) {
    const size_t i = static_cast<size_t>(u(rng) * real), j = static_cast<size_t>(u(rng) * real);
    if (i == j) continue;
    s.pairs.push_back({s.pairs[i].first, s.pairs[j].second});
  }
  return s;
}

TEST(LineYaw, RecoversTheYawOfRandomPlanarMotionsWhateverTheTranslation) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> errors;
  for (int trial = 0; trial < 40; ++trial) {
    const double yaw = 0.5 * u(rng);
    const cv::Vec3d t(0.6 * u(rng), 0.0, 0.8 * u(rng));
    const double pitch = trial % 2 ? 0.1 : 0.0;
    const Scene s = make_scene(yaw, t, pitch, 6, 4, 0, 0.5, 100 + trial);
    const auto est = estimate_line_yaw(s.pairs, pitch);
    ASSERT_TRUE(est) << "trial " << trial;
    errors.push_back(std::abs(est->yaw_rad - yaw));
    EXPECT_GE(est->inliers, 5) << "trial " << trial;
    EXPECT_EQ(est->usable, 6) << "trial " << trial << ": vertical lines are not usable";
  }
  // 0.5 px of endpoint noise at VGA on 6 lines: median within 0.5 degree; at worst 2.5 degrees
  // (walls seen nearly face-on turn their lines' image slope by about half the yaw, so the
  // yaw's error is about twice the slope's: ~1 degree of slope noise on a short segment).
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.0087);
  EXPECT_LT(errors.back(), 0.044);
}

TEST(LineYaw, MismatchesBecomeOutliers) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int beaten = 0;
  double worst = 0.0;
  for (int trial = 0; trial < 40; ++trial) {
    const double yaw = 0.4 * u(rng);
    const cv::Vec3d t(0.5 * u(rng), 0.0, 0.5 * u(rng));
    const Scene s = make_scene(yaw, t, 0.0, 8, 2, 4, 0.5, 300 + trial);
    const auto est = estimate_line_yaw(s.pairs, 0.0);
    ASSERT_TRUE(est) << "trial " << trial;
    if (std::abs(est->yaw_rad - yaw) > 0.044) ++beaten;  // the clean scenes' worst, above
    worst = std::max(worst, std::abs(est->yaw_rad - yaw));
  }
  // 8 true horizontal lines against 4 mismatches: the consensus holds. A mismatch that happens to
  // fall within the inlier threshold of the true yaw pulls the refinement a little (1 of 40
  // scenes beyond the clean scenes' worst when this was written), never to a wrong yaw.
  EXPECT_LE(beaten, 2);
  EXPECT_LT(worst, 0.087);
}

// A moved shelf: its boards' lines (24) are turned by 0.25 rad since teaching and outnumber the
// room's (8). The consensus follows the shelf; with odometry's prediction of the yaw (a little off
// the truth) only the room's proposals compete; a prediction far from both finds nothing. (Turned
// by 0.12 rad, the two sets' gates overlap at the sway's 0.006 rad and the estimate is a mixture
// with or without the prior, 0.084 rad from the room's yaw: the navigator's 3-sigma gate on the
// heading refuses that one.)
TEST(LineYaw, APriorTellsTheRoomFromATurnedShelf) {
  const double yaw = 0.15, turned = 0.25;
  const cv::Vec3d t(0.1, 0.0, 0.4);
  const Scene room = make_scene(yaw, t, 0.0, 8, 0, 0, 0.3, 21);
  const Scene shelf = make_scene(yaw + turned, t, 0.0, 24, 0, 0, 0.3, 22);
  Pairs pairs = room.pairs;
  pairs.insert(pairs.end(), shelf.pairs.begin(), shelf.pairs.end());
  const auto plain = estimate_line_yaw(pairs, 0.0);
  ASSERT_TRUE(plain);
  EXPECT_NEAR(plain->yaw_rad, yaw + turned, 0.02);

  const YawPrior near{yaw + 0.02, 0.02};
  const auto with_prior = estimate_line_yaw(pairs, 0.0, {}, &near);
  ASSERT_TRUE(with_prior);
  EXPECT_NEAR(with_prior->yaw_rad, yaw, 0.01);
  EXPECT_GE(with_prior->inliers, 6);
  EXPECT_LE(with_prior->inliers, 10);

  const YawPrior far{yaw - 0.3, 0.02};
  EXPECT_FALSE(estimate_line_yaw(pairs, 0.0, {}, &far));
  const YawPrior bad{yaw, 0.0};
  EXPECT_THROW(estimate_line_yaw(pairs, 0.0, {}, &bad), std::invalid_argument);
}

TEST(LineYaw, VerticalLinesAloneGiveNoEstimate) {
  const Scene s = make_scene(0.2, cv::Vec3d(0.1, 0, 0.4), 0.0, 0, 8, 0, 0.5, 5);
  ASSERT_GE(s.pairs.size(), 8u);
  EXPECT_FALSE(estimate_line_yaw(s.pairs, 0.0));
}

TEST(LineYaw, OneLineIsNotEnoughByDefault) {
  const Scene s = make_scene(0.2, cv::Vec3d(0.1, 0, 0.4), 0.0, 1, 0, 0, 0.0, 5);
  ASSERT_EQ(s.pairs.size(), 1u);
  EXPECT_FALSE(estimate_line_yaw(s.pairs, 0.0));
  LineYawOptions one;
  one.min_inliers = 1;
  one.max_sigma_rad = 1.0;  // one line's sigma is large; noise-free here
  const auto est = estimate_line_yaw(s.pairs, 0.0, one);
  ASSERT_TRUE(est);
  EXPECT_NEAR(est->yaw_rad, 0.2, 1e-6);  // noise-free: exact
}

TEST(LineYaw, ResidualIsZeroAtTheTrueYawAndGrowsAway) {
  const Scene s = make_scene(-0.3, cv::Vec3d(0.2, 0, -0.3), 0.05, 3, 0, 0, 0.0, 9);
  for (const auto& [a, b] : s.pairs) {
    EXPECT_LT(line_yaw_residual_rad(a, b, -0.3, 0.05), 1e-9);
    EXPECT_GT(line_yaw_residual_rad(a, b, -0.2, 0.05), 1e-3);
  }
}

TEST(LineYaw, InvalidInputsThrow) {
  LineYawOptions bad;
  bad.min_leverage = 1.5;
  EXPECT_THROW(estimate_line_yaw({}, 0.0, bad), std::invalid_argument);
  EXPECT_THROW(estimate_line_yaw({}, std::nan("")), std::invalid_argument);
  EXPECT_FALSE(estimate_line_yaw({}, 0.0));
}

}  // namespace
}  // namespace pepper::core::geometry
