// KLT priors (match_two_view's `prior`, FrameMatcher::set_klt_prior): tracking a key image's
// corners from their verified positions in the previous frame must verify the same points as
// tracking from scratch, and bad priors must fall back to tracking from scratch. And the retry
// schedule of the corners KLT did not track (`skip`, klt_corners_to_skip).
#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "core/features/image_features.hpp"
#include "core/features/matching.hpp"
#include "core/navigator/test_world.hpp"

namespace pepper::core::features {
namespace {

// A key image, the previous frame 20 cm and 3 deg of turn further and the current frame 4 cm and
// 2 deg after that (~20 px of image motion at VGA), rendered in the shared box room.
struct Sequence {
  ImageFeatures key, previous, current;
};
constexpr sim::Pose2D kKeyPose{-3.0, -2.0, 0.00}, kPreviousPose{-2.80, -1.99, 0.05},
    kCurrentPose{-2.76, -1.98, 0.09};

// Where the room point seen at pixel p from base pose a appears from pose b (the renderer's
// geometry: default 8 x 8 x 3 m room, camera 5 cm ahead of the base axis, 1.15 m high);
// none when it is behind b or outside b's image.
std::optional<cv::Point2f> true_position(const cv::Point2f& p, const sim::Pose2D& a,
                                         const sim::Pose2D& b) {
  constexpr double kHalfX = 4.0, kHalfY = 4.0, kRoomH = 3.0, kDelta = 0.05, kCamH = 1.15;
  const CameraIntrinsics k = CameraIntrinsics::pepper_top_vga();
  double c = std::cos(a.yaw_rad), s = std::sin(a.yaw_rad);
  const double ox = a.x_m + kDelta * c, oy = a.y_m + kDelta * s;
  const double xn = (p.x - k.cx_px) / k.fx_px, yn = (p.y - k.cy_px) / k.fy_px;
  // Ray in the world: camera z forward = base x, camera x right = -base y, camera y down = -z.
  const double dx = c + s * xn, dy = s - c * xn, dz = -yn;
  double t = 1e30;
  const auto hit = [&](double num, double den) {
    if (std::abs(den) > 1e-12 && num / den > 0) t = std::min(t, num / den);
  };
  hit((dx > 0 ? kHalfX : -kHalfX) - ox, dx);
  hit((dy > 0 ? kHalfY : -kHalfY) - oy, dy);
  hit((dz > 0 ? kRoomH : 0.0) - kCamH, dz);
  const double px = ox + t * dx, py = oy + t * dy, pz = kCamH + t * dz;
  c = std::cos(b.yaw_rad);
  s = std::sin(b.yaw_rad);
  const double qx = px - (b.x_m + kDelta * c), qy = py - (b.y_m + kDelta * s), qz = pz - kCamH;
  const double fwd = c * qx + s * qy, left = -s * qx + c * qy;
  if (fwd < 0.05) return std::nullopt;
  const cv::Point2f q(static_cast<float>(k.cx_px + k.fx_px * (-left / fwd)),
                      static_cast<float>(k.cy_px + k.fy_px * (-qz / fwd)));
  if (q.x < 0 || q.y < 0 || q.x > k.width_px - 1 || q.y > k.height_px - 1) return std::nullopt;
  return q;
}

const Sequence& sequence() {
  static const Sequence s = [] {
    const CameraIntrinsics k = CameraIntrinsics::pepper_top_vga();
    const test::BoxWorld& world = test::shared_world();
    const FeatureExtractor ex(k);
    Sequence r;
    r.key = ex.extract(world.render(kKeyPose, k));
    r.previous = ex.extract(world.render(kPreviousPose, k), kPartsCurrentFrame);
    r.current = ex.extract(world.render(kCurrentPose, k), kPartsCurrentFrame);
    return r;
  }();
  return s;
}

std::set<int> corner_ids(const TwoViewMatches& m) {
  std::set<int> ids;
  for (const auto& p : m.points) ids.insert(p.idx_a);
  return ids;
}

TEST(KltPrior, PriorFromThePreviousFrameVerifiesTheSamePoints) {
  const Sequence& s = sequence();
  const TwoViewMatches prior = match_two_view(s.key, s.previous);
  ASSERT_GE(prior.n_points(), 50);
  const TwoViewMatches scratch = match_two_view(s.key, s.current);
  const TwoViewMatches seeded = match_two_view(s.key, s.current, {}, prior.points);
  ASSERT_GE(scratch.n_points(), 50);
  // Same verified corners within a few percent (RANSAC draws differ) ...
  const std::set<int> a = corner_ids(scratch), b = corner_ids(seeded);
  int common = 0;
  for (const int i : a) common += b.count(i) > 0 ? 1 : 0;
  EXPECT_GE(common, 0.9 * static_cast<double>(a.size()));
  EXPECT_GE(static_cast<double>(b.size()), 0.95 * static_cast<double>(a.size()));
  // ... as accurately (ground truth from the room's geometry).
  const auto wrong = [&](const TwoViewMatches& m) {
    int n = 0;
    for (const auto& p : m.points) {
      const std::optional<cv::Point2f> t = true_position(p.a_px, kKeyPose, kCurrentPose);
      n += !t || std::hypot(t->x - p.b_px.x, t->y - p.b_px.y) > 1.0 ? 1 : 0;
    }
    return n;
  };
  EXPECT_LE(wrong(seeded), wrong(scratch) + 2);
  EXPECT_EQ(seeded.line_candidates, scratch.line_candidates);  // lines do not use the prior
}

TEST(KltPrior, CommonOffsetOfThePriorIsMeasuredByTheProbes) {
  // Every prior 30 px off (more than a window): the probes, tracked with all pyramid levels,
  // measure the offset and the other corners start from the corrected position.
  const Sequence& s = sequence();
  std::vector<PointMatch> prior = match_two_view(s.key, s.previous).points;
  for (auto& p : prior) p.b_px += cv::Point2f(30.0f, -8.0f);
  const TwoViewMatches scratch = match_two_view(s.key, s.current);
  const TwoViewMatches seeded = match_two_view(s.key, s.current, {}, prior);
  EXPECT_GE(static_cast<double>(seeded.n_points()), 0.95 * scratch.n_points());
}

TEST(KltPrior, FailedPriorTracksFallBackToTrackingFromScratch) {
  // Priors outside the image (and invalid corner indices) all fail: every corner is then
  // tracked from scratch, which gives exactly the result without prior.
  const Sequence& s = sequence();
  std::vector<PointMatch> prior = match_two_view(s.key, s.previous).points;
  ASSERT_FALSE(prior.empty());
  for (auto& p : prior) p.b_px = cv::Point2f(-500.0f, -500.0f);
  PointMatch bad;
  bad.idx_a = static_cast<int>(s.key.corners_px.size()) + 3;
  prior.push_back(bad);
  bad.idx_a = -1;
  prior.push_back(bad);
  const TwoViewMatches scratch = match_two_view(s.key, s.current);
  const TwoViewMatches seeded = match_two_view(s.key, s.current, {}, prior);
  ASSERT_EQ(seeded.n_points(), scratch.n_points());
  for (int i = 0; i < seeded.n_points(); ++i) {
    EXPECT_EQ(seeded.points[i].idx_a, scratch.points[i].idx_a);
    EXPECT_EQ(seeded.points[i].b_px, scratch.points[i].b_px);
  }
}

TEST(KltPrior, DisabledPriorIsIgnoredAndFrameMatcherUsesIt) {
  const Sequence& s = sequence();
  const std::vector<PointMatch> prior = match_two_view(s.key, s.previous).points;
  MatcherOptions off;
  off.klt.prior_max_level = -1;
  const TwoViewMatches scratch = match_two_view(s.key, s.current, off);
  const TwoViewMatches ignored = match_two_view(s.key, s.current, off, prior);
  EXPECT_EQ(corner_ids(ignored), corner_ids(scratch));

  const TwoViewMatches seeded = match_two_view(s.key, s.current, {}, prior);
  FrameMatcher fm(s.current);
  fm.set_klt_prior(4, prior);
  EXPECT_EQ(fm.computed_two_view(4), nullptr);
  const TwoViewMatches& cached = fm.two_view(4, s.key);
  EXPECT_EQ(fm.computed_two_view(4), &cached);
  EXPECT_EQ(corner_ids(cached), corner_ids(seeded));
}

// Corners KLT did not track are retried from scratch on one frame in retry_untracked_frames
// (klt_corners_to_skip), staggered so that each frame retries a share of them.
TEST(KltRetry, EachUntrackedCornerIsRetriedOnOneFrameInN) {
  std::vector<int> untracked;
  for (int c = 0; c < 40; ++c) untracked.push_back(3 * c + 1);
  std::vector<int> retried(untracked.size(), 0);
  for (int64_t frame = 17; frame < 17 + 4; ++frame) {
    const std::vector<int> skip = klt_corners_to_skip(untracked, frame, 4);
    EXPECT_TRUE(std::is_sorted(skip.begin(), skip.end()));
    EXPECT_NEAR(static_cast<double>(untracked.size() - skip.size()), untracked.size() / 4.0, 1.0)
        << "frame " << frame << " retries about a quarter";
    for (size_t i = 0; i < untracked.size(); ++i) {
      retried[i] += std::binary_search(skip.begin(), skip.end(), untracked[i]) ? 0 : 1;
    }
  }
  for (size_t i = 0; i < untracked.size(); ++i) {
    EXPECT_EQ(retried[i], 1) << "corner " << untracked[i] << " retried once in 4 frames";
  }
  EXPECT_TRUE(klt_corners_to_skip(untracked, 17, 1).empty()) << "1: every frame retries all";
  EXPECT_TRUE(klt_corners_to_skip({}, 17, 4).empty());
}

// match_two_view's `skip`: those corners are not tracked from scratch (never verified, listed as
// untracked); the others track exactly as without it, and corners with a prior still track.
TEST(KltRetry, SkippedCornersAreLeftUntrackedAndTheOthersTrackAsBefore) {
  const Sequence& s = sequence();
  const TwoViewMatches all = match_two_view(s.key, s.current);
  ASSERT_GE(all.n_points(), 50);
  EXPECT_TRUE(std::is_sorted(all.klt_untracked.begin(), all.klt_untracked.end()));
  for (const auto& p : all.points) {
    EXPECT_FALSE(std::binary_search(all.klt_untracked.begin(), all.klt_untracked.end(), p.idx_a));
  }
  std::vector<int> skip;  // every third corner
  for (int c = 0; c < static_cast<int>(s.key.corners_px.size()); c += 3) skip.push_back(c);
  const TwoViewMatches some = match_two_view(s.key, s.current, {}, {}, nullptr, skip);
  ASSERT_GE(some.n_points(), 30);
  for (const int c : skip) {
    EXPECT_TRUE(std::binary_search(some.klt_untracked.begin(), some.klt_untracked.end(), c)) << c;
  }
  int common = 0;
  for (const auto& p : some.points) {
    EXPECT_NE(p.idx_a % 3, 0) << "corner " << p.idx_a << " was to be skipped";
    for (const auto& q : all.points) {
      if (q.idx_a != p.idx_a) continue;
      EXPECT_EQ(p.b_px, q.b_px) << "corner " << p.idx_a << " tracked as without skip";
      ++common;
    }
  }
  EXPECT_GE(common, static_cast<int>(0.9 * some.n_points()));
  // A prior wins over the skip: a corner seeded from the previous frame is tracked from there.
  const TwoViewMatches prior = match_two_view(s.key, s.previous);
  std::vector<int> skip_all(s.key.corners_px.size());
  for (size_t c = 0; c < skip_all.size(); ++c) skip_all[c] = static_cast<int>(c);
  const TwoViewMatches seeded = match_two_view(s.key, s.current, {}, prior.points, nullptr, skip_all);
  EXPECT_GE(static_cast<double>(seeded.n_points()), 0.9 * prior.n_points());
  // FrameMatcher passes a key image's skip list with its prior.
  FrameMatcher fm(s.current);
  fm.set_klt_prior(4, {}, skip);
  const TwoViewMatches& cached = fm.two_view(4, s.key);
  EXPECT_EQ(corner_ids(cached), corner_ids(some));
}

TEST(KltPrior, InvalidPriorOptionsAreRejected) {
  MatcherOptions o;
  o.klt.prior_window_px = 10;
  EXPECT_FALSE(o.validate().empty());
  o.klt.prior_window_px = 11;
  o.klt.prior_max_level = 7;
  EXPECT_FALSE(o.validate().empty());
  o.klt.prior_max_level = 0;
  EXPECT_TRUE(o.validate().empty());
  o.klt.retry_untracked_frames = 0;
  EXPECT_FALSE(o.validate().empty());
}

}  // namespace
}  // namespace pepper::core::features
