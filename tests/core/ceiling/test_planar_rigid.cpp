// Planar rigid transforms: composition and inverse, the closed-form fit, and RANSAC with outliers.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "core/ceiling/planar_rigid.hpp"

namespace pepper::core::ceiling {
namespace {

TEST(PlanarRigid, ComposeInverseAndApplyAgree) {
  const PlanarPose T_a_b{0.7, -1.2, 2.5};
  const PlanarPose T_b_c{-0.3, 0.4, 1.9};
  const cv::Point2d p_c(0.25, -0.6);
  const cv::Point2d direct = T_a_b.apply(T_b_c.apply(p_c));
  const cv::Point2d composed = (T_a_b * T_b_c).apply(p_c);
  EXPECT_NEAR(direct.x, composed.x, 1e-12);
  EXPECT_NEAR(direct.y, composed.y, 1e-12);
  // 2.5 + 1.9 wraps past pi.
  EXPECT_NEAR((T_a_b * T_b_c).theta_rad, 4.4 - 2 * M_PI, 1e-12);
  const cv::Point2d back = T_a_b.inverse().apply(T_a_b.apply(p_c));
  EXPECT_NEAR(back.x, p_c.x, 1e-12);
  EXPECT_NEAR(back.y, p_c.y, 1e-12);
  // A quarter turn left maps x onto y (counter-clockwise).
  const cv::Point2d q = PlanarPose{0, 0, M_PI / 2}.apply({1, 0});
  EXPECT_NEAR(q.x, 0.0, 1e-12);
  EXPECT_NEAR(q.y, 1.0, 1e-12);
  EXPECT_NEAR(wrap_angle_rad(-M_PI), M_PI, 1e-12);
  EXPECT_NEAR(wrap_angle_rad(7.0), 7.0 - 2 * M_PI, 1e-12);
}

TEST(PlanarRigid, FitRecoversAKnownTransformFromNoisyPoints) {
  const PlanarPose truth{1.5, -0.4, -0.8};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  std::normal_distribution<double> noise(0.0, 0.002);
  std::vector<cv::Point2d> src, dst;
  for (int i = 0; i < 200; ++i) {
    const cv::Point2d p(u(rng), u(rng));
    src.push_back(p);
    dst.push_back(truth.apply(p) + cv::Point2d(noise(rng), noise(rng)));
  }
  const PlanarPose fit = fit_rigid(src, dst);
  EXPECT_NEAR(fit.x_m, truth.x_m, 1e-3);
  EXPECT_NEAR(fit.y_m, truth.y_m, 1e-3);
  EXPECT_NEAR(fit.theta_rad, truth.theta_rad, 1e-3);
  EXPECT_THROW(fit_rigid({src[0]}, {dst[0]}), std::invalid_argument);
  EXPECT_THROW(fit_rigid(src, {dst[0], dst[1]}), std::invalid_argument);
}

TEST(PlanarRigid, RansacIgnoresHalfTheMatchesBeingWrong) {
  const PlanarPose truth{-0.6, 2.1, 2.9};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::normal_distribution<double> noise(0.0, 0.005);
  std::vector<cv::Point2d> src, dst;
  std::vector<bool> good;
  for (int i = 0; i < 120; ++i) {
    const cv::Point2d p(u(rng), u(rng));
    src.push_back(p);
    const bool ok = i % 2 == 0;  // every other match is a wrong landmark somewhere else
    dst.push_back(ok ? truth.apply(p) + cv::Point2d(noise(rng), noise(rng))
                     : cv::Point2d(u(rng), u(rng)) * 3.0);
    good.push_back(ok);
  }
  const RigidFit fit = ransac_rigid(src, dst);
  ASSERT_TRUE(fit.found);
  EXPECT_NEAR(fit.T_dst_src.x_m, truth.x_m, 0.005);
  EXPECT_NEAR(fit.T_dst_src.y_m, truth.y_m, 0.005);
  EXPECT_NEAR(fit.T_dst_src.theta_rad, truth.theta_rad, 0.005);
  EXPECT_GE(fit.inliers, 58);
  EXPECT_LE(fit.inliers, 64);  // a wrong match may fall inside 3 cm by chance, not many
  EXPECT_LT(fit.rms_m, 0.012);
  for (size_t i = 0; i < good.size(); ++i)
    if (good[i]) {
      EXPECT_EQ(fit.inlier[i], 1) << i;
    }
  // Same input, same answer (seeded sampler).
  const RigidFit again = ransac_rigid(src, dst);
  EXPECT_EQ(again.T_dst_src.x_m, fit.T_dst_src.x_m);
}

TEST(PlanarRigid, RansacFailsAsAValueAndRefusesBadOptions) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<cv::Point2d> src, dst;
  for (int i = 0; i < 40; ++i) {  // unrelated point sets
    src.emplace_back(u(rng), u(rng));
    dst.emplace_back(u(rng) * 5, u(rng) * 5);
  }
  RigidRansacOptions o;
  o.min_inliers = 10;
  EXPECT_FALSE(ransac_rigid(src, dst, o).found);
  EXPECT_FALSE(ransac_rigid({}, {}, o).found);
  o.inlier_threshold_m = 0.0;
  EXPECT_THROW(ransac_rigid(src, dst, o), std::invalid_argument);
  o = {};
  o.min_inliers = 1;
  EXPECT_THROW(ransac_rigid(src, dst, o), std::invalid_argument);
  o = {};
  o.iterations = 0;
  EXPECT_THROW(ransac_rigid(src, dst, o), std::invalid_argument);
  EXPECT_THROW(ransac_rigid(src, {dst[0]}), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::ceiling
