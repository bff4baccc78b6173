#include "core/control/visual_features.hpp"

#include <cmath>
#include <limits>

namespace pepper::core::control {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

double line_feature_X(std::span<const LineRhoTheta> lines) {
  if (lines.empty()) return kNaN;
  double sum = 0.0;
  for (const LineRhoTheta& l : lines) sum += l.rho * std::cos(l.theta_rad);
  return sum / static_cast<double>(lines.size());
}

double line_jacobian_dX_domega(const LineRhoTheta& line) {
  const double c = std::cos(line.theta_rad);
  return c * c + line.rho * line.rho * std::cos(2.0 * line.theta_rad);
}

double line_jacobian_dX_domega(std::span<const LineRhoTheta> lines) {
  if (lines.empty()) return kNaN;
  double sum = 0.0;
  for (const LineRhoTheta& l : lines) sum += line_jacobian_dX_domega(l);
  return sum / static_cast<double>(lines.size());
}

double point_feature_x(std::span<const cv::Point2d> points_norm) {
  if (points_norm.empty()) return kNaN;
  double sum = 0.0;
  for (const cv::Point2d& p : points_norm) sum += p.x;
  return sum / static_cast<double>(points_norm.size());
}

double point_jacobian_dx_domega(std::span<const cv::Point2d> points_norm) {
  if (points_norm.empty()) return kNaN;
  double sum = 0.0;
  for (const cv::Point2d& p : points_norm) sum += p.x * p.x;
  return 1.0 + sum / static_cast<double>(points_norm.size());
}

// Derivation (docs/method/control.md): points of the line are (x, y) = rho n + s n_perp with
// 1/Z = mu0 + mu1 s from the plane; requiring d/dt(x cos theta + y sin theta - rho) = 0 for all s
// gives rho' and theta', hence X' = J_L omega + K (mu0 cos theta + mu1 rho sin theta),
// K = delta omega cos theta + v rho.
double line_X_rate_full(const LineRhoTheta& line, const PlaneCam& plane_cam, double omega_rad_s,
                        double v_m_s, double delta_m) {
  const double ct = std::cos(line.theta_rad);
  const double st = std::sin(line.theta_rad);
  const double rho = line.rho;
  const double mu0 =
      -(plane_cam.a * rho * ct + plane_cam.b * rho * st + plane_cam.c) / plane_cam.d_m;
  const double mu1 = (plane_cam.a * st - plane_cam.b * ct) / plane_cam.d_m;
  const double k = delta_m * omega_rad_s * ct + v_m_s * rho;
  return line_jacobian_dX_domega(line) * omega_rad_s + k * (mu0 * ct + mu1 * rho * st);
}

double point_x_rate_full(const cv::Point2d& point_norm, double depth_m, double omega_rad_s,
                         double v_m_s, double delta_m) {
  const double x = point_norm.x;
  return (1.0 + x * x) * omega_rad_s + (delta_m * omega_rad_s + x * v_m_s) / depth_m;
}

}  // namespace pepper::core::control
