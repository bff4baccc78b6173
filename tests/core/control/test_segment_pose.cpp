// Segment reconstruction and planar resection (core/control/segment_pose.hpp) on synthetic 3D
// points seen from known planar poses: exact recovery without noise, bounded errors with pixel
// noise, outliers rejected, and one scale for IP and the current camera whatever the scale of
// the two-view translation given for IP.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/control/segment_pose.hpp"

namespace pepper::core::control {
namespace {

constexpr double kFocalPx = 300.0;  // about Pepper's top camera at QVGA

// Points on textured walls of a room seen from IN (camera frame, m): y in [-1.0, 1.1] (the floor
// is ~1.1 m below the camera), ahead 2..9 m, to the sides up to 3.5 m.
std::vector<cv::Vec3d> room_points(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-3.5, 3.5), uy(-1.0, 1.1), uz(2.0, 9.0);
  std::vector<cv::Vec3d> X;
  for (int i = 0; i < n; ++i) X.emplace_back(ux(rng), uy(rng), uz(rng));
  return X;
}

cv::Point2d project(const PlanarPose& cam_in_next, const cv::Vec3d& X_next) {
  const cv::Vec3d Xc = to_camera(cam_in_next, X_next);
  return {Xc[0] / Xc[2], Xc[1] / Xc[2]};
}

std::vector<cv::Point2d> observe(const PlanarPose& pose, const std::vector<cv::Vec3d>& X,
                                 double noise_px, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_px / kFocalPx);
  std::vector<cv::Point2d> x;
  for (const cv::Vec3d& p : X) {
    const cv::Point2d q = project(pose, p);
    x.emplace_back(q.x + noise(rng), q.y + noise(rng));
  }
  return x;
}

// to_camera, planar_pose_from_camera (T_a_b) and planar_pose_from_motion (X_C = R_y X_R + t)
// describe one pose three ways; inverse() swaps the roles of the two cameras.
TEST(SegmentPose, PoseConventionsAgree) {
  const PlanarPose pose{-0.7, 0.25, 0.3};
  // to_camera is affine: X_C = R X_R + t.
  const cv::Vec3d t = to_camera(pose, {0, 0, 0});
  cv::Matx33d R;
  for (int j = 0; j < 3; ++j) {
    cv::Vec3d e(0, 0, 0);
    e[j] = 1.0;
    const cv::Vec3d col = to_camera(pose, e) - t;
    for (int i = 0; i < 3; ++i) R(i, j) = col[i];
  }
  const double c = std::cos(0.3), s = std::sin(0.3);
  EXPECT_LT(cv::norm(R - cv::Matx33d(c, 0, s, 0, 1, 0, -s, 0, c)), 1e-12);  // R_y(yaw)
  EXPECT_NEAR(t[1], 0.0, 1e-15);
  const PlanarPose from_camera = planar_pose_from_camera(R.t(), -(R.t() * t));
  const PlanarPose from_motion = planar_pose_from_motion(0.3, t[0], t[2]);
  for (const PlanarPose& back : {from_camera, from_motion}) {
    EXPECT_NEAR(back.x_m, pose.x_m, 1e-12);
    EXPECT_NEAR(back.y_m, pose.y_m, 1e-12);
    EXPECT_NEAR(back.yaw_rad, pose.yaw_rad, 1e-12);
  }
  // R seen from C: R's origin maps to C's frame at to_camera(pose, 0), i.e. ahead = t_z.
  const PlanarPose r_in_c = inverse(pose);
  EXPECT_NEAR(r_in_c.x_m, t[2], 1e-12);
  EXPECT_NEAR(r_in_c.y_m, -t[0], 1e-12);
  EXPECT_NEAR(r_in_c.yaw_rad, -0.3, 1e-12);
  const PlanarPose twice = inverse(r_in_c);
  EXPECT_NEAR(twice.x_m, pose.x_m, 1e-12);
  EXPECT_NEAR(twice.y_m, pose.y_m, 1e-12);
  // A point straight ahead of a camera turned left lies to its right (x > 0) after the turn.
  const cv::Vec3d ahead = to_camera({0.0, 0.0, 0.2}, {0.0, 0.0, 5.0});
  EXPECT_GT(ahead[0], 0.0);
}

TEST(SegmentPose, ResectionRecoversPlanarPoses) {
  const SegmentPoseOptions o;
  const std::vector<cv::Vec3d> X = room_points(80, 1);
  for (const PlanarPose truth : {PlanarPose{-1.0, 0.0, 0.0}, PlanarPose{-0.6, 0.15, 0.2},
                                 PlanarPose{-0.2, -0.3, -0.35}, PlanarPose{0.1, 0.05, 0.05}}) {
    const auto exact = planar_resection(X, observe(truth, X, 0.0, 2), kFocalPx, o);
    ASSERT_TRUE(exact);
    EXPECT_EQ(exact->inliers, 80);
    EXPECT_NEAR(exact->pose.x_m, truth.x_m, 1e-9);
    EXPECT_NEAR(exact->pose.y_m, truth.y_m, 1e-9);
    EXPECT_NEAR(exact->pose.yaw_rad, truth.yaw_rad, 1e-9);
    // Half a pixel of noise: a few millimetres and milliradians (here, 80 points 2-9 m away).
    const auto noisy = planar_resection(X, observe(truth, X, 0.5, 3), kFocalPx, o);
    ASSERT_TRUE(noisy);
    EXPECT_GE(noisy->inliers, 75);
    EXPECT_LT(noisy->rms_px, 1.0);
    EXPECT_NEAR(noisy->pose.x_m, truth.x_m, 0.05);
    EXPECT_NEAR(noisy->pose.y_m, truth.y_m, 0.02);
    EXPECT_NEAR(noisy->pose.yaw_rad, truth.yaw_rad, 0.005);
  }
}

TEST(SegmentPose, ResectionRejectsOutliers) {
  const SegmentPoseOptions o;
  const std::vector<cv::Vec3d> X = room_points(100, 4);
  const PlanarPose truth{-0.5, 0.12, -0.15};
  std::vector<cv::Point2d> x = observe(truth, X, 0.3, 5);
  // 30 % of the observations are elsewhere in the image.
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> anywhere(-0.5, 0.5);
  for (int i = 0; i < 30; ++i) x[static_cast<size_t>(i) * 3] = {anywhere(rng), anywhere(rng)};
  const auto fix = planar_resection(X, x, kFocalPx, o);
  ASSERT_TRUE(fix);
  EXPECT_LE(fix->inliers, 72);  // the 70 good ones, maybe an outlier that landed near its point
  EXPECT_GE(fix->inliers, 66);
  EXPECT_NEAR(fix->pose.x_m, truth.x_m, 0.05);
  EXPECT_NEAR(fix->pose.y_m, truth.y_m, 0.02);
  EXPECT_NEAR(fix->pose.yaw_rad, truth.yaw_rad, 0.005);
  // Too few points for min_points: no pose.
  const std::vector<cv::Vec3d> few(X.begin(), X.begin() + (o.min_points - 1));
  const std::vector<cv::Point2d> few_x = observe(truth, few, 0.0, 7);
  EXPECT_FALSE(planar_resection(few, few_x, kFocalPx, o));
}

// A moved object: 70 points on a book shelf ahead-left, moved 0.15 units and turned 7 degrees
// since teaching, outnumber 40 points on the walls. Its consensus is the largest, so without a
// prior the fix follows the shelf; with the odometry's prediction the walls' structure is chosen,
// and a prediction far from every structure refuses them all.
TEST(SegmentPose, ResectionPriorTellsTheRoomFromAMovedObject) {
  const SegmentPoseOptions o;
  const PlanarPose truth{-0.6, -0.05, -0.1};
  const std::vector<cv::Vec3d> walls = room_points(40, 11);
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> ux(-1.2, -0.2), uy(-0.9, 0.6), uz(2.5, 2.7);
  std::vector<cv::Vec3d> shelf_taught;
  for (int i = 0; i < 70; ++i) shelf_taught.emplace_back(ux(rng), uy(rng), uz(rng));
  // The shelf where it stands now: turned by 7 degrees about its middle and moved.
  const double a = 7.0 * M_PI / 180.0, c = std::cos(a), s = std::sin(a);
  const cv::Vec3d mid(-0.7, 0.0, 2.6), shift(0.15, 0.0, 0.1);
  std::vector<cv::Vec3d> X = walls, X_now = walls;
  for (const cv::Vec3d& p : shelf_taught) {
    const cv::Vec3d d = p - mid;
    X.push_back(p);  // the model: where teaching triangulated it
    X_now.push_back(mid + shift + cv::Vec3d(c * d[0] + s * d[2], d[1], -s * d[0] + c * d[2]));
  }
  const std::vector<cv::Point2d> x = observe(truth, X_now, 0.3, 13);
  auto error = [&](const PlanarFix& f) {
    return std::hypot(f.pose.x_m - truth.x_m, f.pose.y_m - truth.y_m);
  };

  const auto plain = planar_resection(X, x, kFocalPx, o);
  ASSERT_TRUE(plain);
  EXPECT_GE(plain->inliers, 60);  // the shelf's
  EXPECT_GT(error(*plain), 0.1);  // so the fix is off by more than the moved shelf's lateral ...

  PosePrior prior;  // odometry a few centimetres and a degree off the truth
  prior.pose = {truth.x_m + 0.04, truth.y_m - 0.02, truth.yaw_rad + 0.015};
  prior.sigma_x = 0.15;
  prior.sigma_y = 0.05;
  prior.sigma_yaw_rad = 0.03;
  const auto with_prior = planar_resection(X, x, kFocalPx, o, &prior);
  ASSERT_TRUE(with_prior);
  EXPECT_TRUE(with_prior->within_prior);
  EXPECT_GE(with_prior->structures, 2);
  EXPECT_GE(with_prior->inliers, 36);  // the walls'
  EXPECT_LE(with_prior->inliers, 45);
  EXPECT_LT(error(*with_prior), 0.03);
  EXPECT_NEAR(with_prior->pose.yaw_rad, truth.yaw_rad, 0.005);
  EXPECT_LE(with_prior->prior_d2, prior.gate_chi2);

  // A prediction far from both structures: nothing is the room; the largest is returned, marked.
  PosePrior far = prior;
  far.pose = {truth.x_m, truth.y_m + 0.6, truth.yaw_rad};
  const auto refused = planar_resection(X, x, kFocalPx, o, &far);
  ASSERT_TRUE(refused);
  EXPECT_FALSE(refused->within_prior);
  EXPECT_GT(refused->prior_d2, far.gate_chi2);
  EXPECT_EQ(refused->inliers, plain->inliers);

  // A loose prior (a fresh localisation) cannot tell them apart: the largest structure wins.
  PosePrior loose = prior;
  loose.sigma_x = loose.sigma_y = 2.0;
  loose.sigma_yaw_rad = 1.0;
  const auto loosely = planar_resection(X, x, kFocalPx, o, &loose);
  ASSERT_TRUE(loosely);
  EXPECT_TRUE(loosely->within_prior);
  EXPECT_EQ(loosely->inliers, plain->inliers);

  PosePrior bad = prior;
  bad.sigma_y = 0.0;
  EXPECT_THROW(planar_resection(X, x, kFocalPx, o, &bad), std::invalid_argument);
}

// IP and the current camera located in one reconstruction: their lateral offsets from the
// segment agree with the metric truth once multiplied by the metric segment length, for any
// scale of the IP translation passed in (two-view translations have none).
TEST(SegmentPose, ModelAndResectionShareOneScale) {
  const SegmentPoseOptions o;
  const std::vector<cv::Vec3d> X = room_points(150, 8);  // metric, IN's camera frame
  const PlanarPose prev{-1.2, 0.08, 0.06};               // IP in IN's frame, m
  const PlanarPose cur{-0.55, 0.14, -0.12};              // current camera, m
  const double segment_m = std::hypot(prev.x_m, prev.y_m);
  const auto truth = deviation_from_segment(prev, cur);
  ASSERT_TRUE(truth);

  for (const double noise_px : {0.0, 0.5}) {
    std::vector<CornerObservation> to_prev, to_cur;
    const std::vector<cv::Point2d> x_next = observe({0, 0, 0}, X, noise_px, 9);
    const std::vector<cv::Point2d> x_prev = observe(prev, X, noise_px, 10);
    const std::vector<cv::Point2d> x_cur = observe(cur, X, noise_px, 11);
    for (int i = 0; i < static_cast<int>(X.size()); ++i) {
      to_prev.push_back({i, x_next[i], x_prev[i]});
      to_cur.push_back({i, x_next[i], x_cur[i]});
    }
    for (const double scale : {1.0 / segment_m, 3.7}) {
      const PlanarPose prev_scaled{prev.x_m * scale, prev.y_m * scale, prev.yaw_rad};
      const auto model = build_segment_model(prev_scaled, to_prev, kFocalPx, o);
      ASSERT_TRUE(model);
      EXPECT_NEAR(std::hypot(model->prev_in_next.x_m, model->prev_in_next.y_m), 1.0, 1e-12);
      EXPECT_GT(model->point_by_corner.size(), 100u);
      const auto fix = locate_in_segment(*model, to_cur, kFocalPx, o);
      ASSERT_TRUE(fix);
      const auto dev = deviation_from_segment(model->prev_in_next, fix->pose);
      ASSERT_TRUE(dev);
      const double tol_m = noise_px == 0.0 ? 1e-9 : 0.02;
      EXPECT_NEAR(dev->lateral_m * segment_m, truth->lateral_m, tol_m) << noise_px;
      EXPECT_NEAR(dev->heading_rad, truth->heading_rad, noise_px == 0.0 ? 1e-9 : 0.01);
      EXPECT_NEAR(fix->pose.x_m * segment_m, cur.x_m, noise_px == 0.0 ? 1e-9 : 0.08);
    }
  }
}

// IP on a taught arc (or straight line) before IN: the chord points along the mean heading.
// The 1-DOF fit recovers IP's yaw and the chord direction from noisy matches with outliers.
TEST(SegmentPose, ArcFitRecoversTheSegment) {
  const SegmentPoseOptions o;
  const std::vector<cv::Vec3d> X = room_points(120, 14);
  for (const double yaw : {0.0, -0.2, 0.35}) {
    const double length_m = 0.6;  // any: the fit returns unit distance
    const PlanarPose prev{-length_m * std::cos(0.5 * yaw), -length_m * std::sin(0.5 * yaw), yaw};
    const std::vector<cv::Point2d> x_next = observe({0, 0, 0}, X, 0.3, 15);
    std::vector<cv::Point2d> x_prev = observe(prev, X, 0.3, 16);
    for (size_t i = 0; i < x_prev.size(); i += 10) x_prev[i].x += 8.0 / kFocalPx;  // 10 % outliers
    std::vector<CornerObservation> m;
    for (int i = 0; i < static_cast<int>(X.size()); ++i) m.push_back({i, x_next[i], x_prev[i]});
    const auto fit = fit_arc_segment(m, kFocalPx, o);
    ASSERT_TRUE(fit);
    EXPECT_NEAR(fit->yaw_rad, yaw, 0.003) << yaw;
    EXPECT_NEAR(std::hypot(fit->x_m, fit->y_m), 1.0, 1e-12);
    EXPECT_NEAR(std::atan2(-fit->y_m, -fit->x_m), 0.5 * yaw, 0.002) << yaw;
    // The fitted pose reconstructs the segment: most points triangulate.
    const auto model = build_segment_model(*fit, m, kFocalPx, o);
    ASSERT_TRUE(model);
    EXPECT_GT(model->point_by_corner.size(), 60u);
  }
  std::vector<CornerObservation> few(static_cast<size_t>(o.min_points - 1));
  EXPECT_FALSE(fit_arc_segment(few, kFocalPx, o));
}

TEST(SegmentPose, TriangulationNeedsParallaxAndBaseline) {
  const SegmentPoseOptions o;
  const PlanarPose prev{-1.0, 0.0, 0.0};
  std::vector<cv::Vec3d> X = room_points(40, 12);
  X.emplace_back(0.0, 0.0, 6.0);   // on the line of motion: no parallax
  X.emplace_back(0.05, 0.0, 8.0);  // 0.4 deg off it
  std::vector<CornerObservation> m;
  const std::vector<cv::Point2d> x_next = observe({0, 0, 0}, X, 0.0, 0);
  const std::vector<cv::Point2d> x_prev = observe(prev, X, 0.0, 0);
  for (int i = 0; i < static_cast<int>(X.size()); ++i) m.push_back({100 + i, x_next[i], x_prev[i]});
  const auto model = build_segment_model(prev, m, kFocalPx, o);
  ASSERT_TRUE(model);
  EXPECT_FALSE(model->point_by_corner.contains(100 + 40));
  EXPECT_FALSE(model->point_by_corner.contains(100 + 41));
  // Kept points are where they were (noise-free, |IP - IN| = 1 m here).
  for (const auto& [corner, p] : model->point_by_corner) {
    EXPECT_LT(cv::norm(p - X[static_cast<size_t>(corner - 100)]), 1e-9);
  }
  // Pure rotation: no baseline, no model; a wrong match breaks the reprojection check.
  EXPECT_FALSE(build_segment_model({0.0, 0.0, 0.3}, m, kFocalPx, o));
  int kept = 0;
  while (!model->point_by_corner.contains(m[static_cast<size_t>(kept)].corner)) ++kept;
  m[static_cast<size_t>(kept)].other_norm.x += 10.0 / kFocalPx;
  const auto with_outlier = build_segment_model(prev, m, kFocalPx, o);
  ASSERT_TRUE(with_outlier);
  EXPECT_FALSE(with_outlier->point_by_corner.contains(m[static_cast<size_t>(kept)].corner));
  EXPECT_EQ(with_outlier->point_by_corner.size() + 1, model->point_by_corner.size());
}

TEST(SegmentPose, ContractViolationsThrow) {
  SegmentPoseOptions bad;
  bad.max_reprojection_px = 0.0;
  const std::vector<cv::Vec3d> X = room_points(20, 13);
  const std::vector<cv::Point2d> x = observe({}, X, 0.0, 0);
  EXPECT_THROW(planar_resection(X, x, kFocalPx, bad), std::invalid_argument);
  EXPECT_THROW(planar_resection(X, x, 0.0, {}), std::invalid_argument);
  EXPECT_THROW(planar_resection(X, {x.begin(), x.end() - 1}, kFocalPx, {}), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::control
