// The navigator's interaction-matrix work per frame, the project's closed forms against ViSP's
// through visp_adapter (issue 31): what one frame needs is J_L = d(mean rho cos theta)/d omega over
// the lines matched with IN and J_P = d(mean x)/d omega over the matched points
// (core/control/visual_features.hpp; the navigator calls these in core/src/navigator/navigator.cpp),
// then the IBVS law (ibvs_law.hpp). ViSP's way: vpFeatureLine / vpFeaturePoint::interaction() for
// each feature, contracted to the same derivative (d X = cos(theta) d rho - rho sin(theta) d theta,
// twist per omega (0, 0, 0, 0, -1, 0)), and vpServo for the law. The counts follow the navigator's
// typical frame (tens of lines, up to a couple of hundred points: docs/perception.md).
// Both give the same numbers to 1e-10 (tests/core/control/test_visual_features_visp.cpp).
//
// Run (one line): taskset -c 0 build/bench/bench_visp --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include <opencv2/core/types.hpp>

#include "core/control/ibvs_law.hpp"
#include "core/control/visual_features.hpp"
#include "visp_adapter/servo.hpp"
#include "visp_adapter/visual_features.hpp"

namespace {

using namespace pepper;
using core::control::LineRhoTheta;

std::vector<LineRhoTheta> random_lines(int n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> rho(-0.8, 0.8), theta(-1.5, 1.5);
  std::vector<LineRhoTheta> out(static_cast<size_t>(n));
  for (auto& l : out) l = {rho(rng), theta(rng)};
  return out;
}

std::vector<cv::Point2d> random_points(int n) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> x(-0.6, 0.6), y(-0.45, 0.45);
  std::vector<cv::Point2d> out(static_cast<size_t>(n));
  for (auto& p : out) p = {x(rng), y(rng)};
  return out;
}

// ViSP's J_L: each line's (rho, theta) rows, the wy column, contracted to X = rho cos(theta). The
// plane does not enter the wy column; ViSP needs one all the same.
double visp_line_jacobian(const std::vector<LineRhoTheta>& lines) {
  const visp_adapter::PlaneCam plane{0.0, 0.0, 1.0, -3.0};
  double sum = 0.0;
  for (const LineRhoTheta& l : lines) {
    const visp_adapter::InteractionMatrix L = visp_adapter::line_interaction(l.rho, l.theta_rad, plane);
    sum -= std::cos(l.theta_rad) * L(0, 4) - l.rho * std::sin(l.theta_rad) * L(1, 4);
  }
  return sum / static_cast<double>(lines.size());
}

double visp_point_jacobian(const std::vector<cv::Point2d>& points) {
  double sum = 0.0;
  for (const cv::Point2d& p : points) sum -= visp_adapter::point_interaction(p.x, p.y, 2.0)(0, 4);
  return sum / static_cast<double>(points.size());
}

void BM_LineJacobianOurs(benchmark::State& state) {
  const auto lines = random_lines(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(core::control::line_jacobian_dX_domega(lines));
}
BENCHMARK(BM_LineJacobianOurs)->Arg(20)->Arg(60);

void BM_LineJacobianViSP(benchmark::State& state) {
  const auto lines = random_lines(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(visp_line_jacobian(lines));
}
BENCHMARK(BM_LineJacobianViSP)->Arg(20)->Arg(60);

void BM_PointJacobianOurs(benchmark::State& state) {
  const auto points = random_points(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(core::control::point_jacobian_dx_domega(points));
}
BENCHMARK(BM_PointJacobianOurs)->Arg(50)->Arg(200);

void BM_PointJacobianViSP(benchmark::State& state) {
  const auto points = random_points(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(visp_point_jacobian(points));
}
BENCHMARK(BM_PointJacobianViSP)->Arg(50)->Arg(200);

// The law itself on the two modality rows (lines and points, IN and INN errors).
void BM_IbvsLawOurs(benchmark::State& state) {
  core::control::IbvsInput in;
  in.lines = core::control::ModalityError{0.012, -0.004, 0.93};
  in.points = core::control::ModalityError{-0.02, 0.01, 1.08};
  const core::control::IbvsOptions opt;
  for (auto _ : state) benchmark::DoNotOptimize(core::control::compute_ibvs_omega(in, opt));
}
BENCHMARK(BM_IbvsLawOurs);

void BM_IbvsLawViSP(benchmark::State& state) {
  visp_adapter::ServoTask task;
  task.interaction = Eigen::MatrixXd::Zero(2, 6);
  task.interaction(0, 4) = -0.93;
  task.interaction(1, 4) = -1.08;
  task.error = Eigen::Vector2d(0.7 * 0.012 + 0.3 * -0.004, 0.7 * -0.02 + 0.3 * 0.01);
  task.robot_jacobian_cam = Eigen::MatrixXd::Zero(6, 1);
  task.robot_jacobian_cam(4, 0) = -1.0;
  for (auto _ : state) benchmark::DoNotOptimize(visp_adapter::servo_velocity(task));
}
BENCHMARK(BM_IbvsLawViSP);

}  // namespace

BENCHMARK_MAIN();
