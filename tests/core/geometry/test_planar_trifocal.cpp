// Three-view line verification under planar motion, on synthetic correspondences with known
// ground truth (tests/support/synthetic_scene.hpp).
#include "core/geometry/planar_trifocal.hpp"

#include <gtest/gtest.h>

#include "support/synthetic_scene.hpp"

namespace pepper::core::geometry {
namespace {

using test::PlanarPose;

// Navigator-like triple (IP, Ia, IN) with the current image Ia as view 0 (the hub): the robot
// drives forward ~0.5 m between key images and turns a little.
const std::array<PlanarPose, 3> kNavigatorPoses{
    PlanarPose{0.03, 0.05, 0.0},    // Ia (hub)
    PlanarPose{-0.05, 0.0, -0.5},   // IP, behind
    PlanarPose{0.12, 0.10, 0.6}};   // IN, ahead
// Teach-like triple (Ic, Ik, Ic-1): Ic-1 close to Ic, Ik further back.
const std::array<PlanarPose, 3> kTeachPoses{
    PlanarPose{0.0, 0.0, 0.0}, PlanarPose{-0.10, -0.05, -0.8}, PlanarPose{-0.01, 0.0, -0.08}};
// A turn: 20 degrees between views.
const std::array<PlanarPose, 3> kTurnPoses{
    PlanarPose{0.35, 0.02, 0.1}, PlanarPose{0.0, 0.0, 0.0}, PlanarPose{-0.2, 0.0, 0.3}};

double focal() { return CameraIntrinsics::pepper_top_vga().fx_px; }

struct Case {
  const char* name;
  const std::array<PlanarPose, 3>* poses;
  double outliers;
  double min_mean_recall;         // measured mean (8 seeds) minus ~0.03
  double max_mean_contamination;  // measured mean plus ~0.01
};

class PlanarTrifocalSynthetic : public ::testing::TestWithParam<Case> {};

// Pixel noise 0.5 px, random-segment outliers in one random view, 120 triplets, 8 seeds.
// Without a prior (the fallback when the point branch gives no usable E) the target
// (>= 95 % recall, <= 2 % outliers) is not reached on recall: the estimated motion sits in a
// shallow yaw / lateral-translation valley (docs/perception.md). The bounds below are the measured
// behaviour with a margin; test_seeded_trifocal.cpp has the estimator with the point prior.
TEST_P(PlanarTrifocalSynthetic, RecoversMostInliersRejectsMostOutliers) {
  const Case c = GetParam();
  double recall = 0.0, contamination = 0.0;
  constexpr int kSeeds = 8;
  for (uint64_t seed = 1; seed <= kSeeds; ++seed) {
    test::SceneOptions so;
    so.outlier_fraction = c.outliers;
    so.pixel_noise_px = 0.5;
    test::SyntheticScene scene(CameraIntrinsics::pepper_top_vga(), so, seed);
    const auto data = scene.lines(*c.poses);
    ASSERT_EQ(static_cast<int>(data.triplets.size()), so.num_lines);
    const auto r = verify_line_triplets(data.triplets, focal());
    ASSERT_TRUE(r.found) << c.name << " seed " << seed;
    const auto s = test::score(r.inliers, data.is_inlier);
    recall += s.recall / kSeeds;
    contamination += s.contamination / kSeeds;
    // The segment check on the 3D line keeps the outliers low even when the model is poor (one
    // turn_50 scene ends on a wrong model: recall 0.14, no outlier); worst measured: 2.0 %.
    EXPECT_LE(s.contamination, 0.05) << c.name << " seed " << seed;
    EXPECT_LE(r.iterations, PlanarTrifocalOptions{}.max_iterations);
  }
  EXPECT_GE(recall, c.min_mean_recall) << c.name;
  EXPECT_LE(contamination, c.max_mean_contamination) << c.name;
}

INSTANTIATE_TEST_SUITE_P(
    Motions, PlanarTrifocalSynthetic,
    // Measured means (8 seeds): navigator 0.920/0.001 and 0.940/0.003, turn 0.938/0.002 and
    // 0.839/0.009, teach 0.937/0.005 (docs/perception.md).
    ::testing::Values(Case{"navigator_30", &kNavigatorPoses, 0.3, 0.89, 0.015},
                      Case{"navigator_50", &kNavigatorPoses, 0.5, 0.91, 0.015},
                      Case{"turn_30", &kTurnPoses, 0.3, 0.90, 0.015},
                      Case{"turn_50", &kTurnPoses, 0.5, 0.80, 0.02},
                      Case{"teach_30", &kTeachPoses, 0.3, 0.90, 0.015}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(PlanarTrifocal, NoiselessDataGivesExactMotionDespiteOutliers) {
  test::SceneOptions so;
  so.outlier_fraction = 0.3;
  so.pixel_noise_px = 0.0;
  test::SyntheticScene scene(CameraIntrinsics::pepper_top_vga(), so, 11);
  const auto data = scene.lines(kNavigatorPoses);
  const auto r = verify_line_triplets(data.triplets, focal());
  ASSERT_TRUE(r.found);
  const auto gt = test::relative_motion(kNavigatorPoses);
  EXPECT_NEAR(r.motion.yaw_rad[1], gt.yaw_rad[1], 1e-3);
  EXPECT_NEAR(r.motion.yaw_rad[2], gt.yaw_rad[2], 1e-3);
  // Translation with its sign: the line constraints leave it free, the cheirality of the
  // verified lines fixes it.
  for (int i = 1; i < 3; ++i) {
    EXPECT_NEAR(r.motion.t_xz[i][0], gt.t_xz[i][0], 1e-3);
    EXPECT_NEAR(r.motion.t_xz[i][1], gt.t_xz[i][1], 1e-3);
  }
  const auto s = test::score(r.inliers, data.is_inlier);
  EXPECT_GE(s.recall, 0.99);
}

TEST(PlanarTrifocal, GroundTruthModelHasSmallResidualForNoiselessInliers) {
  test::SceneOptions so;
  so.outlier_fraction = 0.0;
  so.pixel_noise_px = 0.0;
  test::SyntheticScene scene(CameraIntrinsics::pepper_top_vga(), so, 7);
  const auto data = scene.lines(kNavigatorPoses);
  const auto gt = test::relative_motion(kNavigatorPoses);
  for (const auto& t : data.triplets) {
    EXPECT_LT(line_triplet_residual_px(t, gt, focal()), 1e-6);
  }
}

TEST(PlanarTrifocal, TooFewTripletsIsNotFoundNotAnError) {
  std::vector<LineTriplet> two(2);
  const auto r = verify_line_triplets(two, focal());
  EXPECT_FALSE(r.found);
  EXPECT_TRUE(r.inliers.empty());
  EXPECT_FALSE(verify_line_triplets({}, focal()).found);
}

TEST(PlanarTrifocal, BadArgumentsThrow) {
  EXPECT_THROW(verify_line_triplets({}, 0.0), std::invalid_argument);
  PlanarTrifocalOptions o;
  o.confidence = 1.5;
  EXPECT_THROW(verify_line_triplets({}, focal(), o), std::invalid_argument);
  ASSERT_EQ(o.validate().size(), 1u);
  EXPECT_NE(o.validate()[0].find("confidence"), std::string::npos);
}

TEST(PlanarTrifocal, DeterministicForASeed) {
  test::SceneOptions so;
  test::SyntheticScene a(CameraIntrinsics::pepper_top_vga(), so, 3), b(CameraIntrinsics::pepper_top_vga(), so, 3);
  const auto ra = verify_line_triplets(a.lines(kNavigatorPoses).triplets, focal());
  const auto rb = verify_line_triplets(b.lines(kNavigatorPoses).triplets, focal());
  EXPECT_EQ(ra.inliers, rb.inliers);
  EXPECT_EQ(ra.iterations, rb.iterations);
}

}  // namespace
}  // namespace pepper::core::geometry
