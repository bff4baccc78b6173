// The core's visual-servoing closed forms against ViSP's (issue 31), through visp_adapter:
//   point feature  x and J_P            against vpFeaturePoint::interaction()
//   line feature   X = rho cos(theta), J_L and the full rate  against vpFeatureLine::interaction()
//   the IBVS law (ibvs_law.hpp)         against vpServo (eye-in-hand, robot Jacobian, current L)
// on random features and motions (fixed seeds).
//
// Conventions met here (docs/method/control.md, "Against ViSP"): ViSP's line is the project's,
// x cos(theta) + y sin(theta) = rho in normalised coordinates, same plane A X + B Y + C Z + D = 0
// (ViSP's lambda_rho = -mu0, lambda_theta = mu1 of control.md). The project keeps theta in
// (-pi/2, pi/2] with rho of any sign; ViSP's rows hold for any representative, and the project's
// X = rho cos(theta) and its rate are the same for (rho, theta) and (-rho, theta + pi), which the
// test checks. The base's yaw rate omega moves the camera by the twist
// (-delta omega, 0, v, 0, -omega, 0) (docs/conventions.md): that twist, per unit omega, is the
// robot Jacobian handed to vpServo; the project's law neglects depth (J_v = 0), i.e. only the
// wy column, (0, 0, 0, 0, -1, 0).
//
// Tolerance: both sides evaluate the same closed forms in double precision on O(1) values, so they
// differ by rounding only (1e-15 .. 1e-13); kTol = 1e-10 is far above that and far below what a
// convention error would give (a wrong sign or a missing rho^2 term moves J_L by > 1e-3 over
// these samples; the last test shows the depth terms alone move the rate by more than that).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include "core/control/ibvs_law.hpp"
#include "core/control/visual_features.hpp"
#include "visp_adapter/servo.hpp"
#include "visp_adapter/visual_features.hpp"

namespace pepper::core::control {
namespace {

constexpr double kTol = 1e-10;
constexpr int kSamples = 2000;
constexpr double kPi = std::numbers::pi;

using Twist = Eigen::Matrix<double, 6, 1>;

// Camera twist of the base moving forward at v_m_s and turning at omega_rad_s, camera delta_m ahead
// of the rotation axis (docs/conventions.md, "Signs").
Twist base_twist_cam(double omega_rad_s, double v_m_s, double delta_m) {
  Twist t;
  t << -delta_m * omega_rad_s, 0.0, v_m_s, 0.0, -omega_rad_s, 0.0;
  return t;
}

// d(rho cos theta) = cos(theta) d rho - rho sin(theta) d theta: the row that maps ViSP's (rho, theta)
// rows to the project's line feature X.
Eigen::Matrix<double, 1, 6> x_row_of_line(const LineRhoTheta& l, const visp_adapter::PlaneCam& p) {
  const visp_adapter::InteractionMatrix L = visp_adapter::line_interaction(l.rho, l.theta_rad, p);
  return std::cos(l.theta_rad) * L.row(0) - l.rho * std::sin(l.theta_rad) * L.row(1);
}

struct Sampler {
  std::mt19937 rng;
  explicit Sampler(unsigned seed) : rng(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
  // Normalised coordinates up to the corners of a wide image (Pepper's QVGA is about +-0.54 x +-0.4).
  cv::Point2d point() { return {uniform(-0.7, 0.7), uniform(-0.5, 0.5)}; }
  LineRhoTheta line() {
    double theta = uniform(-kPi / 2, kPi / 2);
    if (theta == -kPi / 2) theta = kPi / 2;  // canonical (-pi/2, pi/2]
    return {uniform(-0.8, 0.8), theta};
  }
  // A plane at a distance of 0.5 .. 8 m from the optical centre, any orientation.
  PlaneCam plane() {
    Eigen::Vector3d n(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    n.normalize();
    return {n.x(), n.y(), n.z(), uniform(0.5, 8.0) * (uniform(0, 1) < 0.5 ? -1.0 : 1.0)};
  }
};

visp_adapter::PlaneCam to_adapter(const PlaneCam& p) { return {p.a, p.b, p.c, p.d_m}; }

TEST(VisualFeaturesAgainstViSP, PointJacobianAndFullRateAreVpFeaturePoints) {
  Sampler s(31);
  for (int i = 0; i < kSamples; ++i) {
    const cv::Point2d p = s.point();
    const double depth_m = s.uniform(0.3, 12.0);
    const double omega = s.uniform(-0.6, 0.6), v = s.uniform(0.0, 0.35), delta = s.uniform(0.0, 0.2);
    const visp_adapter::InteractionMatrix L = visp_adapter::point_interaction(p.x, p.y, depth_m);
    // J_P of one point: dx/domega with depth neglected is minus ViSP's wy column.
    const cv::Point2d one[] = {p};
    ASSERT_NEAR(point_jacobian_dx_domega(one), -L(0, 4), kTol) << "x=" << p.x << " y=" << p.y;
    ASSERT_NEAR(point_x_rate_full(p, depth_m, omega, v, delta),
                L.row(0).dot(base_twist_cam(omega, v, delta)), kTol)
        << "x=" << p.x << " Z=" << depth_m << " omega=" << omega << " v=" << v << " delta=" << delta;
  }
}

TEST(VisualFeaturesAgainstViSP, PointModalityIsTheMeanOfViSPRows) {
  Sampler s(32);
  for (int i = 0; i < 200; ++i) {
    std::vector<cv::Point2d> pts(1 + i % 40);
    double visp_sum = 0.0;
    for (auto& p : pts) {
      p = s.point();
      visp_sum += -visp_adapter::point_interaction(p.x, p.y, s.uniform(0.3, 12.0))(0, 4);
    }
    ASSERT_NEAR(point_jacobian_dx_domega(pts), visp_sum / static_cast<double>(pts.size()), kTol);
  }
}

TEST(VisualFeaturesAgainstViSP, LineJacobianAndFullRateAreVpFeatureLines) {
  Sampler s(33);
  for (int i = 0; i < kSamples; ++i) {
    const LineRhoTheta l = s.line();
    const PlaneCam plane = s.plane();
    const double omega = s.uniform(-0.6, 0.6), v = s.uniform(0.0, 0.35), delta = s.uniform(0.0, 0.2);
    const Eigen::Matrix<double, 1, 6> x_row = x_row_of_line(l, to_adapter(plane));
    ASSERT_NEAR(line_jacobian_dX_domega(l), -x_row(4), kTol)
        << "rho=" << l.rho << " theta=" << l.theta_rad;
    ASSERT_NEAR(line_X_rate_full(l, plane, omega, v, delta),
                x_row.dot(base_twist_cam(omega, v, delta)), kTol)
        << "rho=" << l.rho << " theta=" << l.theta_rad << " plane=(" << plane.a << ", " << plane.b
        << ", " << plane.c << ", " << plane.d_m << ") omega=" << omega << " v=" << v;
    // The other representative of the same line, (-rho, theta + pi), outside the project's
    // canonical range: ViSP's rows give the same X rate, so the range is no convention to map.
    const LineRhoTheta flipped{-l.rho, l.theta_rad + kPi};
    ASSERT_NEAR(x_row_of_line(flipped, to_adapter(plane)).dot(base_twist_cam(omega, v, delta)),
                x_row.dot(base_twist_cam(omega, v, delta)), kTol);
  }
}

TEST(VisualFeaturesAgainstViSP, DepthTermsMatterSoTheComparisonCanFail) {
  // The full rates include ViSP's translation columns: had the project dropped them, or got the
  // plane's sign wrong (mu0 = -lambda_rho), the comparison above would be off by more than this.
  Sampler s(34);
  double largest_depth_term = 0.0;
  for (int i = 0; i < 200; ++i) {
    const LineRhoTheta l = s.line();
    const Eigen::Matrix<double, 1, 6> x_row = x_row_of_line(l, to_adapter(s.plane()));
    const Twist twist = base_twist_cam(0.3, 0.3, 0.18);
    largest_depth_term = std::max(largest_depth_term, std::abs(x_row.head<3>().dot(twist.head<3>())));
  }
  EXPECT_GT(largest_depth_term, 1e-3);
}

// One modality's inputs: features of Ia matched to IN and to INN (same count, as the navigator
// pairs them), and the project's error/Jacobian for them.
struct LinesSample {
  std::vector<LineRhoTheta> a_n, n, a_nn, nn;
};
struct PointsSample {
  std::vector<cv::Point2d> a_n, n, a_nn, nn;
};

TEST(IbvsLawAgainstViSP, OmegaIsVpServoOnTheTwoModalityTask) {
  Sampler s(35);
  const visp_adapter::PlaneCam any_plane{0.0, 0.0, 1.0, -3.0};  // wy column does not depend on it
  int commanded = 0;
  for (int i = 0; i < 500; ++i) {
    LinesSample ls;
    PointsSample ps;
    for (int k = 0, nl = 1 + i % 12; k < nl; ++k) {
      ls.a_n.push_back(s.line());
      ls.n.push_back(s.line());
      ls.a_nn.push_back(s.line());
      ls.nn.push_back(s.line());
    }
    for (int k = 0, np = 1 + i % 30; k < np; ++k) {
      ps.a_n.push_back(s.point());
      ps.n.push_back(s.point());
      ps.a_nn.push_back(s.point());
      ps.nn.push_back(s.point());
    }
    const bool last_segment = i % 5 == 0;  // no INN: its error is IN's (ibvs_law.hpp)
    IbvsOptions opt;
    opt.mode = i % 3 == 0 ? FeatureMode::kLinesAndPoints
                          : (i % 3 == 1 ? FeatureMode::kLinesOnly : FeatureMode::kPointsOnly);
    opt.g1 = s.uniform(0.0, 1.0);
    opt.g2 = s.uniform(0.05, 1.0);
    opt.lambda = s.uniform(0.2, 2.0);

    // The project's law, as the navigator feeds it (the Jacobian at Ia's features matched to IN).
    IbvsInput in;
    ModalityError lines{line_feature_X(ls.a_n) - line_feature_X(ls.n), std::nullopt,
                        line_jacobian_dX_domega(ls.a_n)};
    ModalityError points{point_feature_x(ps.a_n) - point_feature_x(ps.n), std::nullopt,
                         point_jacobian_dx_domega(ps.a_n)};
    if (!last_segment) {
      lines.err_next_next = line_feature_X(ls.a_nn) - line_feature_X(ls.nn);
      points.err_next_next = point_feature_x(ps.a_nn) - point_feature_x(ps.nn);
    }
    in.lines = lines;
    in.points = points;
    const IbvsResult ours = compute_ibvs_omega(in, opt);

    // ViSP: one task row per modality, its interaction row the mean of ViSP's rows of Ia's
    // features (the modality's feature is a mean), its error g1 e_N + g2 e_NN; one robot dof, the
    // yaw rate, moving the camera by (0, 0, 0, 0, -1, 0) per rad/s (depth neglected as in the law).
    std::vector<Eigen::Matrix<double, 1, 6>> rows;
    std::vector<double> errors;
    auto weighted = [&](const ModalityError& m) {
      return opt.g1 * m.err_next + opt.g2 * m.err_next_next.value_or(m.err_next);
    };
    if (opt.mode != FeatureMode::kPointsOnly) {
      Eigen::Matrix<double, 1, 6> row = Eigen::Matrix<double, 1, 6>::Zero();
      for (const LineRhoTheta& l : ls.a_n) row += x_row_of_line(l, any_plane);
      rows.push_back(row / static_cast<double>(ls.a_n.size()));
      errors.push_back(weighted(lines));
    }
    if (opt.mode != FeatureMode::kLinesOnly) {
      Eigen::Matrix<double, 1, 6> row = Eigen::Matrix<double, 1, 6>::Zero();
      for (const cv::Point2d& p : ps.a_n) row += visp_adapter::point_interaction(p.x, p.y, 2.0).row(0);
      rows.push_back(row / static_cast<double>(ps.a_n.size()));
      errors.push_back(weighted(points));
    }
    visp_adapter::ServoTask task;
    task.interaction.resize(static_cast<Eigen::Index>(rows.size()), 6);
    task.error.resize(static_cast<Eigen::Index>(rows.size()));
    for (size_t r = 0; r < rows.size(); ++r) {
      task.interaction.row(static_cast<Eigen::Index>(r)) = rows[r];
      task.error(static_cast<Eigen::Index>(r)) = errors[r];
    }
    task.robot_jacobian_cam = Eigen::MatrixXd::Zero(6, 1);
    task.robot_jacobian_cam(4, 0) = -1.0;
    task.lambda = opt.lambda;
    const double visp_omega = visp_adapter::servo_velocity(task)(0);

    // The project refuses J_L^2 + J_P^2 < 1e-9 (no yaw information); ViSP's pseudo-inverse then
    // returns ~0. Elsewhere both must give the same command.
    if (!ours.omega_rad_s) {
      EXPECT_LT(task.interaction.col(4).squaredNorm(), 1e-9) << "sample " << i;
      continue;
    }
    ++commanded;
    ASSERT_NEAR(*ours.omega_rad_s, visp_omega, kTol * std::max(1.0, std::abs(visp_omega)))
        << "sample " << i << " mode " << to_string(opt.mode) << " g1=" << opt.g1 << " g2=" << opt.g2
        << " lambda=" << opt.lambda << " last_segment=" << last_segment;
  }
  EXPECT_GT(commanded, 450);  // the comparison ran on (almost) every sample
}

}  // namespace
}  // namespace pepper::core::control
