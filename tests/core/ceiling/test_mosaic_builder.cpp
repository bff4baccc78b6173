// MosaicBuilder and MosaicLocaliser on synthetic observations (no rendering): ceiling points
// with random ORB-like descriptors seen from known poses, so that chaining, the keep rule and
// the robust fits can be checked exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <optional>
#include <random>
#include <stdexcept>

#include "core/ceiling/mosaic_builder.hpp"
#include "core/ceiling/mosaic_localiser.hpp"
#include "synthetic_ceiling.hpp"

namespace pepper::core::ceiling {
namespace {

using Ceiling = test_support::SyntheticCeiling;

// A ceiling over x in [0, 6], y in [-1, 1].
Ceiling make_ceiling(uint32_t seed) {
  return test_support::make_synthetic_ceiling(seed, 0.0, 60, -1.0, 20);
}

// What a base at T_world_base sees, plus `junk` points with random descriptors (a person, a
// moved lamp).
CeilingObservation see(const Ceiling& c, const PlanarPose& T_world_base, int junk,
                       std::mt19937& rng) {
  return test_support::see_synthetic(c, T_world_base, rng, junk);
}

TEST(MosaicBuilder, ChainsExactPosesAndKeepsOnlyLandmarksSeenConsistently) {
  const Ceiling c = make_ceiling(4);
  std::mt19937 rng(9);
  MosaicBuilder builder;
  const PlanarPose T_world_start{0.2, 0.0, 0.0};
  std::vector<PlanarPose> truth;
  for (int k = 0; k < 200; ++k) {  // 4 m forward with a gentle left turn, 2 cm per frame
    const double s = 0.02 * k;
    truth.push_back({0.2 + s, 0.15 * std::sin(s / 1.5), 0.1 * std::cos(s / 1.5) - 0.1});
    builder.add_frame(see(c, truth.back(), /*junk=*/15, rng));
  }
  const auto& frames = builder.frames();
  ASSERT_EQ(frames.size(), 200u);
  for (size_t k = 0; k < frames.size(); ++k) {
    ASSERT_TRUE(frames[k].localised) << k;
    const PlanarPose expected = T_world_start.inverse() * truth[k];
    EXPECT_NEAR(frames[k].T_mosaic_base.x_m, expected.x_m, 1e-9) << k;
    EXPECT_NEAR(frames[k].T_mosaic_base.y_m, expected.y_m, 1e-9) << k;
    EXPECT_NEAR(frames[k].T_mosaic_base.theta_rad, expected.theta_rad, 1e-9) << k;
  }
  // Every kept landmark is a ceiling point at its exact place: the junk (random descriptors at
  // random places in each frame) is never confirmed.
  const Mosaic m = builder.mosaic();
  EXPECT_TRUE(m.validate().empty());
  ASSERT_GT(m.landmarks.size(), 500u);
  for (const MosaicLandmark& l : m.landmarks) {
    const cv::Point2d w = T_world_start.apply(l.position_m);
    double nearest = 1e9;
    for (const cv::Point2d& p : c.points_world) nearest = std::min(nearest, cv::norm(p - w));
    EXPECT_LT(nearest, 1e-9) << "landmark " << l.id << " at " << w.x << ", " << w.y;
    EXPECT_GE(l.observations, 3);
  }
  // Relay sightings refer to kept landmarks only.
  const auto kept = builder.kept_sightings();
  ASSERT_EQ(kept.size(), 200u);
  EXPECT_GT(kept[100].size(), 20u);
}

TEST(MosaicBuilder, AFrameWithoutConsensusIsReportedAndTheNextOneRecovers) {
  const Ceiling c = make_ceiling(5);
  std::mt19937 rng(2);
  MosaicBuilder builder;
  for (int k = 0; k < 10; ++k) builder.add_frame(see(c, {0.2 + 0.02 * k, 0.0, 0.0}, 0, rng));
  // A frame of pure junk: no pose, nothing added.
  const size_t before = builder.mosaic().landmarks.size() + builder.candidates();
  const MosaicFrameResult lost = builder.add_frame(see(c, {50.0, 50.0, 0.0}, 40, rng));
  EXPECT_FALSE(lost.localised);
  EXPECT_EQ(lost.added, 0);
  EXPECT_LE(builder.mosaic().landmarks.size() + builder.candidates(), before);
  const MosaicFrameResult back = builder.add_frame(see(c, {0.42, 0.0, 0.0}, 0, rng));
  ASSERT_TRUE(back.localised);
  EXPECT_NEAR(back.T_mosaic_base.x_m, 0.22, 1e-9);
}

TEST(MosaicBuilder, RefusesBadOptionsAndMalformedObservations) {
  MosaicBuilderOptions o;
  o.search_radius_m = 0.0;
  EXPECT_THROW(MosaicBuilder{o}, std::invalid_argument);
  o = {};
  o.max_hamming = 0;
  EXPECT_THROW(MosaicBuilder{o}, std::invalid_argument);
  o = {};
  o.min_observations = 0;
  EXPECT_THROW(MosaicBuilder{o}, std::invalid_argument);
  o = {};
  o.landmark_step_m = -1.0;
  EXPECT_THROW(MosaicBuilder{o}, std::invalid_argument);
  o = {};
  o.ransac.min_inliers = 1;
  EXPECT_THROW(MosaicBuilder{o}, std::invalid_argument);
  MosaicBuilder builder;
  CeilingObservation bad;
  bad.p_base_m.emplace_back(1.0, 0.0);  // no descriptor, no orientation
  EXPECT_THROW(builder.add_frame(bad), std::invalid_argument);
}

TEST(MosaicLocaliser, FindsThePoseWithoutAPriorDespiteHalfTheViewBeingJunk) {
  const Ceiling c = make_ceiling(6);
  std::mt19937 rng(3);
  MosaicBuilder builder;
  for (int k = 0; k < 200; ++k) builder.add_frame(see(c, {0.2 + 0.02 * k, 0.0, 0.0}, 0, rng));
  const MosaicLocaliser loc(builder.mosaic());
  const PlanarPose T_world_mosaic{0.2, 0.0, 0.0};
  for (const PlanarPose& world :
       {PlanarPose{1.5, 0.1, 0.3}, PlanarPose{3.0, -0.2, -0.25}, PlanarPose{2.2, 0.0, 3.0}}) {
    const CeilingObservation o = see(c, world, /*junk=*/40, rng);
    for (const auto& prior :
         {std::optional<PlanarPose>{}, std::optional<PlanarPose>{T_world_mosaic.inverse() * world *
                                                                 PlanarPose{0.1, -0.05, 0.05}}}) {
      const MosaicFix fix = loc.localise(o, prior);
      ASSERT_TRUE(fix.found) << fix.matches << " matches";
      const PlanarPose expected = T_world_mosaic.inverse() * world;
      EXPECT_NEAR(fix.T_mosaic_base.x_m, expected.x_m, 1e-9);
      EXPECT_NEAR(fix.T_mosaic_base.y_m, expected.y_m, 1e-9);
      EXPECT_NEAR(wrap_angle_rad(fix.T_mosaic_base.theta_rad - expected.theta_rad), 0.0, 1e-9);
    }
  }
  // Only junk: no fix.
  CeilingObservation junk = see(c, {100.0, 0.0, 0.0}, 60, rng);
  EXPECT_FALSE(loc.localise(junk).found);
  EXPECT_THROW(MosaicLocaliser(Mosaic{}), std::invalid_argument);
  CeilingObservation wrong_descriptors = see(c, {1.5, 0.1, 0.3}, 0, rng);
  wrong_descriptors.descriptors.convertTo(wrong_descriptors.descriptors, CV_32F);
  EXPECT_THROW(loc.localise(wrong_descriptors), std::invalid_argument);
  LocaliserOptions bad;
  bad.min_inlier_ratio = 2.0;
  EXPECT_THROW(MosaicLocaliser(builder.mosaic(), bad), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::ceiling
