// Three-view line verification seeded by a prior from the point branch (planar_trifocal.hpp):
// synthetic scenes with 3D lines and 3D points. The essential matrices come from the real point
// pipeline (verify_essential on projected noisy points with outliers), then planar_view_prior, then
// verify_line_triplets with that prior, as features::verify_three_view chains them.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <iomanip>
#include <iostream>
#include <vector>

#include <gtest/gtest.h>

#include "core/geometry/essential_ransac.hpp"
#include "core/geometry/planar_trifocal.hpp"
#include "support/synthetic_scene.hpp"

namespace pepper::core::geometry {
namespace {

using test::PlanarPose;

// View 0 is the hub (the current image), views 1 and 2 the key images (verify_three_view's order).
// Navigator (IP, Ia, IN): IP 0.5 m behind, IN 0.6 m ahead, small yaws.
const std::array<PlanarPose, 3> kNavigatorPoses{
    PlanarPose{0.03, 0.05, 0.0}, PlanarPose{-0.05, 0.0, -0.5}, PlanarPose{0.12, 0.10, 0.6}};
// A turn: 20 degrees between views, 0.1-0.3 m apart.
const std::array<PlanarPose, 3> kTurnPoses{PlanarPose{0.35, 0.02, 0.1}, PlanarPose{0.0, 0.0, 0.0},
                                           PlanarPose{-0.2, 0.0, 0.3}};
// Teach (Ic, Ik, Ic-1): Ik 0.8 m behind, Ic-1 8 cm behind Ic.
const std::array<PlanarPose, 3> kTeachPoses{
    PlanarPose{0.0, 0.0, 0.0}, PlanarPose{-0.10, -0.05, -0.8}, PlanarPose{-0.01, 0.0, -0.08}};
// Teach with Ic-1 only 1 cm behind Ic: too little parallax for a prior from that pair.
const std::array<PlanarPose, 3> kTeachClosePoses{
    PlanarPose{0.0, 0.0, 0.0}, PlanarPose{-0.10, -0.05, -0.8}, PlanarPose{-0.005, 0.0, -0.01}};

CameraIntrinsics camera() { return CameraIntrinsics::pepper_top_vga(); }
double focal() { return camera().fx_px; }

// The point branch for key view -> hub: 100 KLT-like pairs (30 % outliers, 0.5 px noise) and
// five-point RANSAC; returns the verified pairs and E.
struct PointBranch {
  EssentialResult essential;
  std::vector<cv::Point2d> key_norm, hub_norm;  // verified pairs
};

PointBranch point_branch(const PlanarPose& key, const PlanarPose& hub, uint64_t seed,
                         bool planar = false) {
  test::SceneOptions so;
  so.num_points = 100;
  so.outlier_fraction = 0.3;
  so.pixel_noise_px = 0.5;
  test::SyntheticScene scene(camera(), so, seed);
  const auto d = scene.points(key, hub);
  PointBranch pb;
  EssentialRansacOptions o;
  o.planar = planar;
  pb.essential = verify_essential(d.a_norm, d.b_norm, focal(), o);
  for (int i : pb.essential.inliers) {
    pb.key_norm.push_back(d.a_norm[static_cast<size_t>(i)]);
    pb.hub_norm.push_back(d.b_norm[static_cast<size_t>(i)]);
  }
  return pb;
}

std::optional<PlanarViewPrior> prior_of(const PointBranch& pb) {
  if (!pb.essential.found) return std::nullopt;
  return planar_view_prior(pb.essential.E_b_a, pb.key_norm, pb.hub_norm, focal());
}

double cpu_ms_since(std::clock_t t0) {
  return 1e3 * static_cast<double>(std::clock() - t0) / CLOCKS_PER_SEC;
}

struct Case {
  const char* name;
  const std::array<PlanarPose, 3>* poses;
  double outliers;
  bool planar = false;  ///< the point branch's essential model (planar 2-point or five-point)
};

// One row of the measured table: `scenes` scenes of 120 line triplets (0.5 px noise, outliers = a random
// segment in one random view) with their point branches; the prior is used when both key images
// give one. CPU: planar_view_prior of both key images + verify_line_triplets (reported, not
// asserted). The unseeded estimator runs on the same scenes for comparison.
struct Row {
  std::vector<test::VerificationScore> scenes;  // with the prior when available
  std::vector<bool> prior_available, from_prior;
  double cpu_ms = 0.0, unseeded_recall = 0.0, unseeded_outliers = 0.0, unseeded_cpu_ms = 0.0;
};

constexpr int kScenes = 10;

Row measure(const Case& c, int scenes = kScenes) {
  Row row;
  const double n_scenes = scenes;
  for (uint64_t s = 1; s <= static_cast<uint64_t>(scenes); ++s) {
    test::SceneOptions so;
    so.outlier_fraction = c.outliers;
    so.pixel_noise_px = 0.5;
    test::SyntheticScene scene(camera(), so, s);
    const auto data = scene.lines(*c.poses);
    const PointBranch p1 = point_branch((*c.poses)[1], (*c.poses)[0], 1000 + s, c.planar);
    const PointBranch p2 = point_branch((*c.poses)[2], (*c.poses)[0], 2000 + s, c.planar);
    const std::clock_t t0 = std::clock();
    const auto s1 = prior_of(p1);
    const auto s2 = prior_of(p2);
    const auto r =
        s1 && s2 ? verify_line_triplets(data.triplets, focal(), {}, PlanarMotionPrior{*s1, *s2})
                 : verify_line_triplets(data.triplets, focal());
    row.cpu_ms += cpu_ms_since(t0) / n_scenes;
    row.scenes.push_back(test::score(r.inliers, data.is_inlier));
    row.prior_available.push_back(s1 && s2);
    row.from_prior.push_back(r.from_prior);
    const std::clock_t t1 = std::clock();
    const auto unseeded = verify_line_triplets(data.triplets, focal());
    row.unseeded_cpu_ms += cpu_ms_since(t1) / n_scenes;
    const auto su = test::score(unseeded.inliers, data.is_inlier);
    row.unseeded_recall += su.recall / n_scenes;
    row.unseeded_outliers += su.contamination / n_scenes;
  }
  double recall = 0.0, recall_min = 1.0, outliers = 0.0, outliers_max = 0.0;
  for (const auto& sc : row.scenes) {
    recall += sc.recall / n_scenes;
    recall_min = std::min(recall_min, sc.recall);
    outliers += sc.contamination / n_scenes;
    outliers_max = std::max(outliers_max, sc.contamination);
  }
  std::cout << std::fixed << std::setprecision(3) << "[ measured ] " << c.name << ": recall mean "
            << recall << " min " << recall_min << ", outliers mean " << outliers << " max "
            << outliers_max << ", CPU " << row.cpu_ms << " ms/call, prior used "
            << std::count(row.from_prior.begin(), row.from_prior.end(), true) << "/" << scenes
            << "; unseeded: recall mean " << row.unseeded_recall << ", outliers mean "
            << row.unseeded_outliers << ", CPU " << row.unseeded_cpu_ms << " ms/call\n";
  return row;
}

// The target: >= 95 % of the true triplets verified, <= 2 % of the verified ones
// outliers, over 40 scenes per motion. Asserted on the mean, with a count of scenes over the 2 %
// bound (at most 1 in 10) and a count of scenes under 90 % recall (at most 1). Per scene, both
// bounds are properties of the seeds: over seeds 1-100 the five-point prior exceeds the 2 % bound
// in 1 (turn, 30 % outliers) and 4 (50 %) scenes, the planar prior in 3 and 7, with means of
// 0.30 / 0.86 % and 0.22 / 0.68 % (docs/method/navigator.md "Speed"); over seeds 1-200 one
// scene of turn_50 falls under 90 % recall with either prior (five-point: seed 53, 0.83; planar:
// seed 9, 0.78; mean recall 0.998 both; `PEPPER_TEST_SCENES=200 build/tests/core_tests
// --gtest_filter='Motions/SeededTrifocal*'`). Both essential models (the point branch's prior) are
// held to it. Prints the measured table of docs/perception.md.
class SeededTrifocalSynthetic : public ::testing::TestWithParam<Case> {};

TEST_P(SeededTrifocalSynthetic, MeetsTheTargetOverScenes) {
  // 40 scenes; PEPPER_TEST_SCENES=N measures over N (the seed counts cited above).
  const char* scenes_env = std::getenv("PEPPER_TEST_SCENES");
  const int kStatScenes = scenes_env != nullptr ? std::max(1, std::atoi(scenes_env)) : 40;
  const Case c = GetParam();
  const Row row = measure(c, kStatScenes);
  double recall = 0.0, outliers = 0.0;
  int over_bound = 0, under_floor = 0, prior_used = 0;
  for (size_t s = 0; s < row.scenes.size(); ++s) {
    recall += row.scenes[s].recall / kStatScenes;
    outliers += row.scenes[s].contamination / kStatScenes;
    over_bound += row.scenes[s].contamination > 0.02 ? 1 : 0;
    prior_used += row.from_prior[s] ? 1 : 0;
    under_floor += row.scenes[s].recall < 0.9 ? 1 : 0;
  }
  std::cout << "[ measured ] " << c.name << ": " << kStatScenes << " scenes, " << under_floor
            << " under 90 % recall, " << over_bound << " over 2 % outliers\n";
  EXPECT_GE(prior_used, kStatScenes * 9 / 10) << c.name;
  EXPECT_GE(recall, 0.95) << c.name;
  EXPECT_LE(outliers, 0.02) << c.name;
  EXPECT_LE(over_bound, kStatScenes / 10) << c.name;
  EXPECT_LE(under_floor, 1) << c.name;
}

INSTANTIATE_TEST_SUITE_P(Motions, SeededTrifocalSynthetic,
                         ::testing::Values(Case{"navigator_30", &kNavigatorPoses, 0.3},
                                           Case{"navigator_50", &kNavigatorPoses, 0.5},
                                           Case{"turn_30", &kTurnPoses, 0.3},
                                           Case{"turn_50", &kTurnPoses, 0.5},
                                           Case{"navigator_30_planar", &kNavigatorPoses, 0.3, true},
                                           Case{"navigator_50_planar", &kNavigatorPoses, 0.5, true},
                                           Case{"turn_30_planar", &kTurnPoses, 0.3, true},
                                           Case{"turn_50_planar", &kTurnPoses, 0.5, true}),
                         [](const auto& info) { return std::string(info.param.name); });

// Teach (Ik, Ic-1, Ic) with Ic-1 close to Ic, where the target is not promised: the planes
// of Ic and Ic-1 nearly coincide for every line, so a wrong Ik segment is consistent with some 3D
// line and only the segment overlap and cheirality on that line can expose it. With Ic-1 1 cm
// away the Ic-1 -> Ic pair often gives no prior (near-pure rotation) and the unseeded estimator
// runs. Asserted on the means only.
class SeededTrifocalTeach : public ::testing::TestWithParam<Case> {};

TEST_P(SeededTrifocalTeach, MeasuredOnAverage) {
  const Case c = GetParam();
  const Row row = measure(c);
  double recall = 0.0, outliers = 0.0;
  for (const auto& sc : row.scenes) {
    recall += sc.recall / kScenes;
    outliers += sc.contamination / kScenes;
  }
  EXPECT_GE(recall, 0.9) << c.name;
  EXPECT_LE(outliers, 0.03) << c.name;
}

INSTANTIATE_TEST_SUITE_P(Teach, SeededTrifocalTeach,
                         ::testing::Values(Case{"teach_30", &kTeachPoses, 0.3},
                                           Case{"teach_50", &kTeachPoses, 0.5},
                                           Case{"teach_1cm_30", &kTeachClosePoses, 0.3},
                                           Case{"teach_1cm_50", &kTeachClosePoses, 0.5}),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(PlanarViewPrior, RecoversYawAndSignedDirectionFromThePointBranch) {
  const auto gt = test::relative_motion(kNavigatorPoses);
  for (uint64_t s = 1; s <= 5; ++s) {
    for (int v = 1; v <= 2; ++v) {
      const auto prior = prior_of(
          point_branch(kNavigatorPoses[static_cast<size_t>(v)], kNavigatorPoses[0], 100 * v + s));
      ASSERT_TRUE(prior) << "view " << v << " scene " << s;
      EXPECT_NEAR(prior->yaw_rad, gt.yaw_rad[static_cast<size_t>(v)], 0.005);
      const cv::Vec2d t =
          gt.t_xz[static_cast<size_t>(v)] / cv::norm(gt.t_xz[static_cast<size_t>(v)]);
      EXPECT_NEAR(cv::norm(prior->t_dir_xz), 1.0, 1e-9);
      EXPECT_GT(prior->t_dir_xz.dot(t), std::cos(0.05))
          << "view " << v << " scene " << s;  // sign too
    }
  }
}

// Exact correspondences of `n` points under X_0 = R X_i + t (E's convention).
struct ExactPairs {
  cv::Matx33d E;
  std::vector<cv::Point2d> xi, x0;
};

ExactPairs exact_pairs(const cv::Matx33d& R, const cv::Vec3d& t, int n) {
  ExactPairs p;
  const cv::Matx33d tx(0, -t[2], t[1], t[2], 0, -t[0], -t[1], t[0], 0);
  p.E = tx * R;
  for (int k = 0; k < n; ++k) {
    const cv::Vec3d Xi(-1.5 + 3.0 * ((k * 37) % 100) / 100.0, -1.0 + 2.0 * ((k * 53) % 100) / 100.0,
                       2.0 + 6.0 * ((k * 71) % 100) / 100.0);
    const cv::Vec3d X0 = R * Xi + t;
    p.xi.emplace_back(Xi[0] / Xi[2], Xi[1] / Xi[2]);
    p.x0.emplace_back(X0[0] / X0[2], X0[1] / X0[2]);
  }
  return p;
}

TEST(PlanarViewPrior, ExactPlanarPairsGiveTheExactSeed) {
  const double yaw_i = 0.1;             // view i's yaw w.r.t. view 0 (trifocal convention)
  const cv::Vec3d t_i(0.2, 0.0, -0.5);  // X_i = R_y(yaw_i) X_0 + t_i
  const cv::Matx33d R = test::rot_y(yaw_i).t();
  const auto p = exact_pairs(R, -(R * t_i), 40);
  const auto prior = planar_view_prior(p.E, p.xi, p.x0, focal());
  ASSERT_TRUE(prior);
  EXPECT_NEAR(prior->yaw_rad, yaw_i, 1e-6);
  const cv::Vec2d dir = cv::Vec2d(t_i[0], t_i[2]) / std::hypot(t_i[0], t_i[2]);
  EXPECT_NEAR(prior->t_dir_xz[0], dir[0], 1e-6);
  EXPECT_NEAR(prior->t_dir_xz[1], dir[1], 1e-6);
}

TEST(PlanarViewPrior, UnreliableGeometryGivesNoSeed) {
  // Too few points.
  const cv::Matx33d R = test::rot_y(0.05);
  const auto few = exact_pairs(R, cv::Vec3d(0.1, 0.0, 0.5), 8);
  EXPECT_FALSE(planar_view_prior(few.E, few.xi, few.x0, focal()));
  // Rotation off the vertical axis (a pitch of 0.2 rad).
  const cv::Matx33d pitch(1, 0, 0, 0, std::cos(0.2), -std::sin(0.2), 0, std::sin(0.2),
                          std::cos(0.2));
  const auto tilted = exact_pairs(pitch * R, cv::Vec3d(0.1, 0.0, 0.5), 40);
  EXPECT_FALSE(planar_view_prior(tilted.E, tilted.xi, tilted.x0, focal()));
  // Translation out of the floor plane.
  const auto vertical = exact_pairs(R, cv::Vec3d(0.1, 0.4, 0.3), 40);
  EXPECT_FALSE(planar_view_prior(vertical.E, vertical.xi, vertical.x0, focal()));
  // Near-pure rotation: 2 mm baseline, points 2-8 m away (parallax well below 1 px).
  const auto rotation = exact_pairs(R, cv::Vec3d(0.0, 0.0, 0.002), 40);
  EXPECT_FALSE(planar_view_prior(rotation.E, rotation.xi, rotation.x0, focal()));
  // The same pairs with a real baseline do give a prior (the checks above are what rejects).
  const auto good = exact_pairs(R, cv::Vec3d(0.1, 0.0, 0.5), 40);
  EXPECT_TRUE(planar_view_prior(good.E, good.xi, good.x0, focal()));
}

TEST(PlanarViewPrior, BadArgumentsThrow) {
  std::vector<cv::Point2d> a(20), b(19);
  EXPECT_THROW(planar_view_prior(cv::Matx33d::eye(), a, b, focal()), std::invalid_argument);
  EXPECT_THROW(planar_view_prior(cv::Matx33d::eye(), a, a, 0.0), std::invalid_argument);
  PlanarTrifocalOptions o;
  o.prior_replace_ratio = 0.5;
  EXPECT_THROW(planar_view_prior(cv::Matx33d::eye(), a, a, focal(), o), std::invalid_argument);
}

// A wrong prior (yaws off by 0.2 rad) explains few triplets: the local optimisation or, failing
// that, the unseeded challengers recover the motion.
TEST(SeededTrifocal, WrongPriorDoesNotSpoilTheResult) {
  const auto gt = test::relative_motion(kNavigatorPoses);
  double recall_sum = 0.0;
  constexpr int kScenes = 5;
  for (uint64_t s = 1; s <= kScenes; ++s) {
    test::SceneOptions so;
    so.outlier_fraction = 0.3;
    test::SyntheticScene scene(camera(), so, s);
    const auto data = scene.lines(kNavigatorPoses);
    PlanarMotionPrior wrong;
    wrong.view1 = {gt.yaw_rad[1] + 0.2, gt.t_xz[1] / cv::norm(gt.t_xz[1])};
    wrong.view2 = {gt.yaw_rad[2] - 0.2, gt.t_xz[2] / cv::norm(gt.t_xz[2])};
    const auto r = verify_line_triplets(data.triplets, focal(), {}, wrong);
    ASSERT_TRUE(r.found) << "scene " << s;
    EXPECT_NEAR(r.motion.yaw_rad[1], gt.yaw_rad[1], 0.1) << "scene " << s;
    EXPECT_NEAR(r.motion.yaw_rad[2], gt.yaw_rad[2], 0.1) << "scene " << s;
    const auto sc = test::score(r.inliers, data.is_inlier);
    EXPECT_LE(sc.contamination, 0.05) << "scene " << s;
    recall_sum += sc.recall / kScenes;
  }
  EXPECT_GE(recall_sum, 0.9);
}

TEST(SeededTrifocal, NoiselessDataGivesTheExactSignedMotion) {
  test::SceneOptions so;
  so.outlier_fraction = 0.3;
  so.pixel_noise_px = 0.0;
  test::SyntheticScene scene(camera(), so, 11);
  const auto data = scene.lines(kNavigatorPoses);
  const auto gt = test::relative_motion(kNavigatorPoses);
  // A prior a little off (as from noisy points): the local optimisation recovers the exact motion.
  PlanarMotionPrior prior;
  const double dy = 0.003;
  prior.view1 = {gt.yaw_rad[1] + dy, gt.t_xz[1] / cv::norm(gt.t_xz[1])};
  prior.view2 = {gt.yaw_rad[2] - dy, gt.t_xz[2] / cv::norm(gt.t_xz[2])};
  const auto r = verify_line_triplets(data.triplets, focal(), {}, prior);
  ASSERT_TRUE(r.found);
  EXPECT_TRUE(r.from_prior);
  for (size_t i = 1; i < 3; ++i) {
    EXPECT_NEAR(r.motion.yaw_rad[i], gt.yaw_rad[i], 1e-4);
    EXPECT_NEAR(r.motion.t_xz[i][0], gt.t_xz[i][0], 1e-3);  // sign included (cheirality)
    EXPECT_NEAR(r.motion.t_xz[i][1], gt.t_xz[i][1], 1e-3);
  }
  const auto sc = test::score(r.inliers, data.is_inlier);
  EXPECT_GE(sc.recall, 0.99);
  EXPECT_EQ(sc.contamination, 0.0);
}

TEST(SeededTrifocal, DeterministicForASeed) {
  test::SceneOptions so;
  test::SyntheticScene a(camera(), so, 3), b(camera(), so, 3);
  const auto gt = test::relative_motion(kNavigatorPoses);
  PlanarMotionPrior prior;
  prior.view1 = {gt.yaw_rad[1], gt.t_xz[1] / cv::norm(gt.t_xz[1])};
  prior.view2 = {gt.yaw_rad[2], gt.t_xz[2] / cv::norm(gt.t_xz[2])};
  const auto ra = verify_line_triplets(a.lines(kNavigatorPoses).triplets, focal(), {}, prior);
  const auto rb = verify_line_triplets(b.lines(kNavigatorPoses).triplets, focal(), {}, prior);
  EXPECT_EQ(ra.inliers, rb.inliers);
  EXPECT_EQ(ra.iterations, rb.iterations);
  EXPECT_EQ(ra.motion.yaw_rad, rb.motion.yaw_rad);
}

}  // namespace
}  // namespace pepper::core::geometry
