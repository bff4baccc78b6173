// The robot's position relative to a key image from matched floor lines: random planar poses
// seen by Pepper's pitched camera over a corridor's floor edges and floor tile edges, with
// endpoint noise, mismatched pairs and the lines of a moved object; a corridor's parallel edges
// must fix the lateral position only; nothing usable is "no fix".
#include "core/geometry/floor_lines.hpp"

#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "core/camera/intrinsics.hpp"

namespace pepper::core::geometry {
namespace {

using Pairs = std::vector<std::pair<NormSegment, NormSegment>>;

struct Pose {
  double x_m, y_m, yaw_rad;  // view b in view a's floor frame
};

// A floor point (forward, left) of view a seen from a view at `b` (a's floor frame): its
// normalised image point, nullopt when behind or outside the VGA image.
std::optional<cv::Point2d> project(const Eigen::Vector2d& p_a, const Pose& b,
                                   const FloorCamera& cam) {
  const double c = std::cos(b.yaw_rad), s = std::sin(b.yaw_rad);
  const double dx = p_a.x() - b.x_m, dy = p_a.y() - b.y_m;
  const double fwd = c * dx + s * dy, left = -s * dx + c * dy;
  // Level frame (x right, y down, z forward) -> camera: x_cam = R_x(pitch) x_level.
  const double xl = -left, yl = cam.height_m, zl = fwd;
  const double cp = std::cos(cam.pitch_rad), sp = std::sin(cam.pitch_rad);
  const double xc = xl, yc = cp * yl - sp * zl, zc = sp * yl + cp * zl;
  if (zc < 0.3) return std::nullopt;
  const cv::Point2d n(xc / zc, yc / zc);
  const CameraIntrinsics k = CameraIntrinsics::pepper_top_vga();
  const cv::Point2d px = k.denormalize(n);
  if (px.x < 0 || px.y < 0 || px.x >= k.width_px || px.y >= k.height_px) return std::nullopt;
  return n;
}

// The visible part of the floor segment A-B in view `b`, with noise.
std::optional<NormSegment> see(const Eigen::Vector2d& A, const Eigen::Vector2d& B, const Pose& b,
                               const FloorCamera& cam, double noise_norm, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, noise_norm);
  std::vector<cv::Point2d> visible;
  for (int i = 0; i <= 40; ++i) {
    if (const auto n = project(A + (B - A) * (i / 40.0), b, cam)) visible.push_back(*n);
  }
  if (visible.size() < 4) return std::nullopt;
  NormSegment s{visible.front(), visible.back()};
  s.p0 += cv::Point2d(noise(rng), noise(rng));
  s.p1 += cv::Point2d(noise(rng), noise(rng));
  return s;
}

struct Segment2 {
  Eigen::Vector2d a, b;
};

Pairs observe(const std::vector<Segment2>& in_a, const std::vector<Segment2>& in_b,
              const Pose& b, const FloorCamera& cam, double noise_px, uint64_t seed) {
  std::mt19937_64 rng(seed);
  const double noise = noise_px / CameraIntrinsics::pepper_top_vga().fx_px;
  Pairs out;
  for (size_t i = 0; i < in_a.size(); ++i) {
    const auto sa = see(in_a[i].a, in_a[i].b, Pose{0, 0, 0}, cam, noise, rng);
    const auto sb = see(in_b[i].a, in_b[i].b, b, cam, noise, rng);
    if (sa && sb) out.push_back({*sa, *sb});
  }
  return out;
}

// A corridor 2.2 m wide: its two floor edges from 0.5 to 7 m ahead of view a.
std::vector<Segment2> corridor_edges() {
  return {{{0.5, 1.1}, {7.0, 1.1}}, {{0.5, -1.1}, {7.0, -1.1}}};
}
// Floor tile edges across the corridor at 3 to 4.5 m (with the head level, Pepper's top camera
// sees the floor from about 2.9 m ahead).
std::vector<Segment2> tile_edges() {
  return {{{3.0, 1.0}, {3.0, -1.0}},
          {{3.5, 1.0}, {3.5, -1.0}},
          {{4.0, 1.0}, {4.0, -1.0}},
          {{4.5, 1.0}, {4.5, -1.0}}};
}

FloorCamera pepper_camera() { return {pepper_top_camera(0.0).height_m, 0.0}; }

FloorPrior prior_at(const Pose& truth, double sigma_m, const Eigen::Vector2d& offset_m) {
  FloorPrior p;
  p.t_m = Eigen::Vector2d(truth.x_m, truth.y_m) + offset_m;
  p.cov_m2 = Eigen::Matrix2d::Identity() * sigma_m * sigma_m;
  p.yaw_rad = truth.yaw_rad;
  return p;
}

TEST(FloorLines, PepperTopCameraFollowsTheUrdf) {
  const CameraOnBase zero = pepper_top_camera(0.0);
  EXPECT_NEAR(zero.height_m, 1.153, 1e-9);
  EXPECT_NEAR(zero.forward_m, 0.048, 1e-9);
  // Looking down 0.3 rad turns the 0.18 m lever from the pitch axis to the camera forward.
  const double lever = std::hypot(0.08601, 0.16284);
  const double angle0 = std::atan2(0.16284, 0.08601);
  const CameraOnBase down = pepper_top_camera(0.3);
  EXPECT_NEAR(down.height_m, 1.153 - 0.16284 + lever * std::sin(angle0 - 0.3), 1e-9);
  EXPECT_NEAR(down.forward_m, 0.048 - 0.08601 + lever * std::cos(angle0 - 0.3), 1e-9);
}

TEST(FloorLines, FloorPointIsBelowTheHorizonOnly) {
  const FloorCamera cam{1.0, 0.0};
  const auto p = floor_point({0.1, 0.25}, cam, 10.0);  // 0.25 down: 4 m ahead, 0.4 m right
  ASSERT_TRUE(p);
  EXPECT_NEAR(p->x(), 4.0, 1e-12);
  EXPECT_NEAR(p->y(), -0.4, 1e-12);
  EXPECT_FALSE(floor_point({0.0, -0.1}, cam, 10.0));   // above the horizon
  EXPECT_FALSE(floor_point({0.0, 0.05}, cam, 10.0));   // 20 m ahead: beyond the range
  // Pitched down 0.1 rad, the horizon moves up: a ray 0.05 above the image centre meets the floor.
  EXPECT_TRUE(floor_point({0.0, -0.05}, FloorCamera{1.0, 0.1}, 100.0));
}

// Random poses within a replay's reach of a key image (0.5 m along, 0.3 m across, 0.15 rad):
// with the corridor edges and the tile edges, from a prior 0.25 m off in both coordinates, the
// fix is the lateral position within 2 cm and the along one within its own sigma.
TEST(FloorLines, CorridorAndTileEdgesFixBothCoordinates) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Segment2> lines = corridor_edges();
  for (const Segment2& s : tile_edges()) lines.push_back(s);
  int along_fixed = 0;  // trials whose tile edges fixed the along position (sigma < 15 cm)
  for (int trial = 0; trial < 50; ++trial) {
    const Pose b{0.5 * u(rng), 0.3 * u(rng), 0.15 * u(rng)};
    const Pairs pairs = observe(lines, lines, b, pepper_camera(), 0.5, 100 + trial);
    const auto fix = estimate_floor_position(pairs, pepper_camera(),
                                             prior_at(b, 0.3, {0.25, -0.25}));
    ASSERT_TRUE(fix) << trial;
    // Across the corridor the edges pin it; along, the tile edges 3 to 4.5 m ahead are
    // weaker (a pitch error moves a line r^2 / h per radian): within 3 posterior sigmas.
    EXPECT_NEAR(fix->t_m.y(), b.y_m, 0.03) << trial;
    const double sigma_x = std::sqrt(fix->cov_m2(0, 0));
    along_fixed += sigma_x < 0.15 ? 1 : 0;
    EXPECT_NEAR(fix->t_m.x(), b.x_m, 3.0 * sigma_x + 0.01) << trial;
    EXPECT_GE(fix->inliers, 3) << trial;
  }
  EXPECT_GE(along_fixed, 45);  // measured: 48 of 50 (the others keep the prior's 0.3 m)
}

// Parallel edges only: the lateral coordinate is fixed, the along one stays at the prior's.
TEST(FloorLines, ParallelEdgesFixTheLateralPositionOnly) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    const Pose b{0.5 * u(rng), 0.3 * u(rng), 0.1 * u(rng)};
    const Pairs pairs = observe(corridor_edges(), corridor_edges(), b, pepper_camera(), 0.5,
                                200 + trial);
    const FloorPrior prior = prior_at(b, 0.3, {0.2, 0.2});
    const auto fix = estimate_floor_position(pairs, pepper_camera(), prior);
    ASSERT_TRUE(fix) << trial;
    // Across the edges (rotated by the yaw from a's y axis: the edges are a's x direction).
    EXPECT_NEAR(fix->t_m.y(), b.y_m, 0.03) << trial;
    EXPECT_NEAR(fix->t_m.x(), prior.t_m.x(), 0.05) << trial;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(fix->info_1_m2);
    EXPECT_LT(eig.eigenvalues()(0), 1e-3 * eig.eigenvalues()(1)) << trial;
  }
}

// max_angle_to_forward_rad: the tile edges across the view are left out, so the along position
// stays the prior's while the lateral one is fixed as before.
TEST(FloorLines, LinesAcrossTheViewCanBeLeftOut) {
  std::vector<Segment2> lines = corridor_edges();
  for (const Segment2& s : tile_edges()) lines.push_back(s);
  const Pose b{0.2, -0.15, 0.05};
  const Pairs pairs = observe(lines, lines, b, pepper_camera(), 0.5, 17);
  const FloorPrior prior = prior_at(b, 0.3, {0.25, 0.25});
  FloorLineOptions along_only;
  along_only.max_angle_to_forward_rad = 0.5;
  const auto all = estimate_floor_position(pairs, pepper_camera(), prior);
  const auto lateral = estimate_floor_position(pairs, pepper_camera(), prior, along_only);
  ASSERT_TRUE(all && lateral);
  EXPECT_LT(std::abs(all->t_m.x() - b.x_m), 0.1);  // the tile edges moved it
  EXPECT_NEAR(lateral->t_m.x(), prior.t_m.x(), 0.005);  // the edges' noise tilts: < 1 mm
  EXPECT_NEAR(lateral->t_m.y(), b.y_m, 0.03);
  EXPECT_EQ(lateral->usable, 2);
  along_only.max_angle_to_forward_rad = 2.0;
  EXPECT_THROW(estimate_floor_position(pairs, pepper_camera(), prior, along_only),
               std::invalid_argument);
}

// Outliers: the tile edges paired with the wrong edge (each 0.25 to 0.75 m off, each by its
// own amount) and a moved crate whose side edge moved 0.35 m sideways; the fix keeps to the
// true position (the crate's front edge moved along itself: it is still right).
TEST(FloorLines, MismatchesAndAMovedObjectAreOutvoted) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Segment2> a_lines = corridor_edges();
  for (const Segment2& s : tile_edges()) a_lines.push_back(s);
  std::vector<Segment2> b_lines = a_lines;
  a_lines.push_back({{3.0, 0.2}, {3.0, 0.6}});
  a_lines.push_back({{3.0, 0.6}, {3.6, 0.6}});
  b_lines.push_back({{3.0, -0.15}, {3.0, 0.25}});
  b_lines.push_back({{3.0, 0.25}, {3.6, 0.25}});
  for (int trial = 0; trial < 30; ++trial) {
    const Pose b{0.3 * u(rng), 0.2 * u(rng), 0.1 * u(rng)};
    std::vector<Segment2> wrong_a = tile_edges(), wrong_b = tile_edges();
    for (size_t i = 0; i < wrong_b.size(); ++i) {
      const double shift = (0.25 + 0.125 * static_cast<double>(i)) * (i % 2 ? -1.0 : 1.0);
      wrong_b[i].a.x() += shift;
      wrong_b[i].b.x() += shift;
    }
    Pairs pairs = observe(a_lines, b_lines, b, pepper_camera(), 0.5, 300 + trial);
    const Pairs wrong = observe(wrong_a, wrong_b, b, pepper_camera(), 0.5, 400 + trial);
    pairs.insert(pairs.end(), wrong.begin(), wrong.end());
    const auto fix = estimate_floor_position(pairs, pepper_camera(), prior_at(b, 0.3, {0.1, 0.1}));
    ASSERT_TRUE(fix) << trial;
    EXPECT_NEAR(fix->t_m.y(), b.y_m, 0.03) << trial;
    EXPECT_NEAR(fix->t_m.x(), b.x_m, 3.0 * std::sqrt(fix->cov_m2(0, 0)) + 0.01) << trial;
  }
}

TEST(FloorLines, NothingUsableGivesNoFix) {
  const Pose b{0.1, 0.05, 0.02};
  FloorPrior prior = prior_at(b, 0.3, {0, 0});
  EXPECT_FALSE(estimate_floor_position({}, pepper_camera(), prior));
  // Lines above the horizon (a ceiling's edges) are not floor lines.
  const NormSegment up{{-0.3, -0.2}, {-0.1, -0.1}};
  EXPECT_FALSE(estimate_floor_position({{up, up}, {up, up}}, pepper_camera(), prior));
  // One line is below min_inliers (2).
  const Pairs one = observe({corridor_edges().front()}, {corridor_edges().front()}, b,
                            pepper_camera(), 0.0, 1);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_FALSE(estimate_floor_position(one, pepper_camera(), prior));
  // A vertical line (a door frame, or its reflection in a shiny floor) is not a floor line,
  // though it lies below the horizon: it would back-project through the camera itself.
  const NormSegment post{{0.1, 0.14}, {0.1, 0.33}};
  EXPECT_FALSE(floor_line_equation(post, post, 0.0, pepper_camera(), {}));
  // Degenerate segments (both ends equal) are skipped, never a crash.
  const NormSegment dot{{0.1, 0.2}, {0.1, 0.2}};
  EXPECT_FALSE(estimate_floor_position({{dot, dot}, {dot, dot}}, pepper_camera(), prior));
}

TEST(FloorLines, BadInputsAreRefusedByName) {
  FloorLineOptions o;
  o.min_inliers = 0;
  EXPECT_THROW(estimate_floor_position({}, pepper_camera(), FloorPrior{}, o),
               std::invalid_argument);
  EXPECT_THROW(estimate_floor_position({}, FloorCamera{0.0, 0.0}, FloorPrior{}),
               std::invalid_argument);
  o = FloorLineOptions{};
  o.max_range_m = -1.0;
  ASSERT_FALSE(o.validate().empty());
  EXPECT_NE(o.validate().front().find("max_range_m"), std::string::npos);
}

}  // namespace
}  // namespace pepper::core::geometry
