// Canonical (rho, theta) form of image lines (see line_segment.hpp for the convention).
#include "core/features/line_segment.hpp"

#include <cmath>
#include <stdexcept>

namespace pepper::core::features {

RhoTheta canonical_rho_theta(double rho, double theta_rad) {
  // Wrap theta to (-pi, pi], then fold to (-pi/2, pi/2] by flipping the normal (and rho).
  double t = std::remainder(theta_rad, 2.0 * M_PI);  // [-pi, pi]
  if (t <= -M_PI) t += 2.0 * M_PI;
  double r = rho;
  if (t > M_PI_2) {
    t -= M_PI;
    r = -r;
  } else if (t <= -M_PI_2) {
    t += M_PI;
    r = -r;
  }
  return {r, t};
}

RhoTheta rho_theta_from_points(const cv::Point2d& a_norm, const cv::Point2d& b_norm) {
  const cv::Point2d d = b_norm - a_norm;
  const double len = std::hypot(d.x, d.y);
  if (!(len >= 1e-12)) {
    throw std::invalid_argument("rho_theta_from_points: the two points coincide (or are NaN)");
  }
  const double nx = -d.y / len;
  const double ny = d.x / len;
  return canonical_rho_theta(nx * a_norm.x + ny * a_norm.y, std::atan2(ny, nx));
}

cv::Vec3d homogeneous_line(const RhoTheta& l) {
  return {std::cos(l.theta_rad), std::sin(l.theta_rad), -l.rho};
}

}  // namespace pepper::core::features
