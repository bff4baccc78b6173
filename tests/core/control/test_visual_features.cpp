// Jacobians of the IBVS features against central differences of a synthetic projection of 3D
// points and lines while the base turns (and moves forward), in the conventions of
// docs/conventions.md: camera x right, y down, z forward; omega > 0 turns left; the camera sits
// delta_m ahead of the rotation axis. This test settles the sign of the rho^2 term of J_L.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <opencv2/core/matx.hpp>
#include <random>
#include <vector>

#include "core/control/visual_features.hpp"
#include "support/numeric_diff.hpp"

namespace pepper::core::control {
namespace {

using test::central_diff;

// Finite differences of smooth projections: ~1e-10 relative accuracy expected (numeric_diff.hpp);
// 1e-7 leaves margin for the conditioning of the line fit through two projected points.
constexpr double kFdRelTol = 1e-7;
constexpr double kFdAbsTol = 1e-8;

cv::Matx33d rot_y(double beta) {
  const double c = std::cos(beta), s = std::sin(beta);
  return {c, 0, s, 0, 1, 0, -s, 0, c};
}

// Camera pose after time t in the camera frame at t = 0: the base turns by omega t about the
// vertical axis through (0, 0, -delta) and that axis moves forward by v t. Returns P in the new
// camera frame.
cv::Vec3d to_moved_cam(const cv::Vec3d& P, double t, double omega, double v, double delta) {
  const cv::Matx33d R = rot_y(-omega * t);  // left turn = rotation about camera -y
  const cv::Vec3d c = cv::Vec3d(0, 0, -delta + v * t) + R * cv::Vec3d(0, 0, delta);
  return R.t() * (P - c);
}

cv::Point2d project(const cv::Vec3d& P) { return {P[0] / P[2], P[1] / P[2]}; }

LineRhoTheta line_through(const cv::Point2d& p1, const cv::Point2d& p2) {
  double nx = -(p2.y - p1.y), ny = p2.x - p1.x;
  const double n = std::hypot(nx, ny);
  nx /= n;
  ny /= n;
  LineRhoTheta l{nx * p1.x + ny * p1.y, std::atan2(ny, nx)};
  // canonical theta in (-pi/2, pi/2] (docs/conventions.md)
  if (l.theta_rad > std::numbers::pi / 2) {
    l.theta_rad -= std::numbers::pi;
    l.rho = -l.rho;
  } else if (l.theta_rad <= -std::numbers::pi / 2) {
    l.theta_rad += std::numbers::pi;
    l.rho = -l.rho;
  }
  return l;
}

struct Line3d {
  cv::Vec3d P1, P2;
  LineRhoTheta image;  // at t = 0
  PlaneCam plane;      // a plane through the line, not through the optical centre
};

// A 3D line projecting to (rho, theta) at t = 0, its two points at depths z1, z2.
Line3d make_line(double rho, double theta, double z1, double z2, const cv::Vec3d& aux_dir) {
  const cv::Point2d foot{rho * std::cos(theta), rho * std::sin(theta)};
  const cv::Point2d dir{-std::sin(theta), std::cos(theta)};
  const cv::Point2d p1 = foot - 0.3 * dir, p2 = foot + 0.4 * dir;
  Line3d L;
  L.P1 = z1 * cv::Vec3d(p1.x, p1.y, 1.0);
  L.P2 = z2 * cv::Vec3d(p2.x, p2.y, 1.0);
  L.image = {rho, theta};
  const cv::Vec3d n = (L.P2 - L.P1).cross(aux_dir);
  L.plane = {n[0], n[1], n[2], -n.dot(L.P1)};
  return L;
}

double X_at(const Line3d& L, double t, double omega, double v, double delta) {
  const LineRhoTheta l = line_through(project(to_moved_cam(L.P1, t, omega, v, delta)),
                                      project(to_moved_cam(L.P2, t, omega, v, delta)));
  return l.rho * std::cos(l.theta_rad);
}

double x_at(const cv::Vec3d& P, double t, double omega, double v, double delta) {
  return project(to_moved_cam(P, t, omega, v, delta)).x;
}

void expect_line_matches(const Line3d& L, double delta) {
  SCOPED_TRACE(::testing::Message()
               << "rho " << L.image.rho << " theta " << L.image.theta_rad << " delta " << delta);
  // Pure base rotation: FD of X w.r.t. the turned angle.
  const double fd_rot = central_diff([&](double a) { return X_at(L, a, 1.0, 0.0, delta); }, 0.0);
  const double full_rot = line_X_rate_full(L.image, L.plane, 1.0, 0.0, delta);
  EXPECT_TRUE(test::near_rel(fd_rot, full_rot, kFdRelTol, kFdAbsTol))
      << fd_rot << " vs " << full_rot;
  if (delta == 0.0) {
    const double J = line_jacobian_dX_domega(L.image);
    EXPECT_TRUE(test::near_rel(fd_rot, J, kFdRelTol, kFdAbsTol)) << fd_rot << " vs J_L " << J;
  }
  // Forward motion only (the J_v term the law neglects).
  const double fd_fwd = central_diff([&](double t) { return X_at(L, t, 0.0, 1.0, delta); }, 0.0);
  const double full_fwd = line_X_rate_full(L.image, L.plane, 0.0, 1.0, delta);
  EXPECT_TRUE(test::near_rel(fd_fwd, full_fwd, kFdRelTol, kFdAbsTol))
      << fd_fwd << " vs " << full_fwd;
}

TEST(VisualFeatures, LineJacobianSignSettledByFiniteDifferences) {
  // METHOD.md's example: rho = -0.252, theta = 0.221. cos^2(0.221) = 0.95195,
  // rho^2 cos(0.442) = 0.063504 * 0.90389 = 0.05740: plus form 1.00935 (METHOD.md prints
  // 1.00966, a rounding slip), minus form 0.89455 (METHOD.md: 0.8946).
  const Line3d L = make_line(-0.252, 0.221, 3.0, 4.5, {0.3, 1.0, 0.2});
  const double fd = central_diff([&](double a) { return X_at(L, a, 1.0, 0.0, 0.0); }, 0.0);
  const double c = std::cos(0.221);
  const double plus = c * c + 0.252 * 0.252 * std::cos(2 * 0.221);
  const double minus = c * c - 0.252 * 0.252 * std::cos(2 * 0.221);
  EXPECT_NEAR(fd, 1.00935, 1e-5);
  EXPECT_NEAR(minus, 0.89455, 1e-5);
  EXPECT_NEAR(fd, plus, 1e-8);
  EXPECT_GT(std::abs(fd - minus), 0.1);
  EXPECT_NEAR(line_jacobian_dX_domega(L.image), plus, 1e-15);
}

TEST(VisualFeatures, LineJacobianHandPickedCases) {
  const cv::Vec3d aux{0.2, 1.0, 0.1};
  for (double delta : {0.0, 0.05}) {
    expect_line_matches(make_line(0.0, 0.0, 2.0, 2.0, aux), delta);  // vertical, centre
    expect_line_matches(make_line(0.3, 0.0, 2.0, 3.0, aux), delta);  // vertical, right
    expect_line_matches(make_line(0.3, std::numbers::pi / 2 - 1e-3, 2.0, 5.0, aux), delta);
    expect_line_matches(make_line(-0.2, -std::numbers::pi / 2 + 1e-3, 4.0, 2.0, aux), delta);
    expect_line_matches(make_line(0.8, 0.6, 3.0, 6.0, aux), delta);  // large rho
    expect_line_matches(make_line(-0.7, -1.0, 1.5, 2.5, aux), delta);
  }
  // Values at hand-picked points: theta = 0 -> 1 + rho^2; theta = pi/4 -> 1/2.
  EXPECT_DOUBLE_EQ(line_jacobian_dX_domega(LineRhoTheta{0.0, 0.0}), 1.0);
  EXPECT_DOUBLE_EQ(line_jacobian_dX_domega(LineRhoTheta{0.5, 0.0}), 1.25);
  EXPECT_NEAR(line_jacobian_dX_domega(LineRhoTheta{0.5, std::numbers::pi / 4}), 0.5, 1e-15);
}

TEST(VisualFeatures, LineJacobianSeededRandomSample) {
  std::mt19937 rng(20170924);
  std::uniform_real_distribution<double> rho_d(-0.6, 0.6), theta_d(-1.55, 1.57), z_d(1.5, 8.0),
      aux_d(-1.0, 1.0);
  for (int i = 0; i < 60; ++i) {
    const Line3d L = make_line(rho_d(rng), theta_d(rng), z_d(rng), z_d(rng),
                               {aux_d(rng), aux_d(rng), aux_d(rng)});
    if (std::abs(L.plane.d_m) < 0.2) continue;  // plane too close to the optical centre
    expect_line_matches(L, 0.0);
    expect_line_matches(L, 0.05);
  }
}

TEST(VisualFeatures, MeanLineJacobianIsDerivativeOfMeanFeature) {
  std::vector<Line3d> lines = {make_line(0.1, 0.2, 2, 3, {0, 1, 0}),
                               make_line(-0.4, 1.2, 3, 3, {1, 0, 1}),
                               make_line(0.25, -0.7, 5, 2, {0, 1, 1})};
  std::vector<LineRhoTheta> image;
  for (const auto& L : lines) image.push_back(L.image);
  auto mean_X = [&](double a) {
    double s = 0;
    for (const auto& L : lines) s += X_at(L, a, 1.0, 0.0, 0.0);
    return s / lines.size();
  };
  EXPECT_NEAR(line_feature_X(image), mean_X(0.0), 1e-12);
  EXPECT_NEAR(central_diff(mean_X, 0.0), line_jacobian_dX_domega(image), 1e-8);
}

TEST(VisualFeatures, PointJacobianAgainstFiniteDifferences) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> xy(-0.6, 0.6), z_d(1.5, 8.0);
  std::vector<cv::Vec3d> pts = {{0, 0, 2}, {0.5, -0.2, 1}, {-3.0, 0.4, 4.0}};
  for (int i = 0; i < 40; ++i) {
    const double z = z_d(rng);
    pts.push_back({xy(rng) * z, xy(rng) * z, z});
  }
  for (const cv::Vec3d& P : pts) {
    const cv::Point2d p = project(P);
    for (double delta : {0.0, 0.05}) {
      const double fd = central_diff([&](double a) { return x_at(P, a, 1.0, 0.0, delta); }, 0.0);
      EXPECT_NEAR(fd, point_x_rate_full(p, P[2], 1.0, 0.0, delta), 1e-8);
      const double J = point_jacobian_dx_domega(std::vector<cv::Point2d>{p});
      if (delta == 0.0) {
        EXPECT_NEAR(fd, J, 1e-8);
      } else {
        // Neglected depth term delta / Z: at most 0.05 / 1 m here.
        EXPECT_NEAR(fd - J, delta / P[2], 1e-8);
      }
      const double fd_fwd =
          central_diff([&](double t) { return x_at(P, t, 0.0, 1.0, delta); }, 0.0);
      EXPECT_NEAR(fd_fwd, point_x_rate_full(p, P[2], 0.0, 1.0, delta), 1e-8);
    }
  }
  const std::vector<cv::Point2d> two = {{0.2, 0.0}, {-0.4, 1.0}};
  EXPECT_DOUBLE_EQ(point_feature_x(two), -0.1);
  EXPECT_DOUBLE_EQ(point_jacobian_dx_domega(two), 1.0 + (0.04 + 0.16) / 2);  // 1.1
}

TEST(VisualFeatures, EmptyInputsGiveNaN) {
  EXPECT_TRUE(std::isnan(line_feature_X({})));
  EXPECT_TRUE(std::isnan(line_jacobian_dX_domega(std::span<const LineRhoTheta>{})));
  EXPECT_TRUE(std::isnan(point_feature_x({})));
  EXPECT_TRUE(std::isnan(point_jacobian_dx_domega({})));
}

}  // namespace
}  // namespace pepper::core::control
