#pragma once
// Sampson distance of a point correspondence to an essential (or fundamental) matrix: the
// first-order distance of (x_a, x_b) to the variety x_b^T E x_a = 0, in the units of the
// coordinates (normalised image coordinates here). One definition for the essential RANSACs
// (essential_ransac.cpp, planar_essential.cpp).
#include <cmath>
#include <limits>

#include <Eigen/Core>

namespace pepper::core::geometry {

/// The epipolar residual x_b^T E x_a and the squared norm of its gradient in the four image
/// coordinates; the Sampson distance is residual / sqrt(gradient_sq).
struct SampsonTerms {
  double residual = 0.0;
  double gradient_sq = 0.0;
};

inline SampsonTerms sampson_terms(const Eigen::Matrix3d& E, const Eigen::Vector3d& xa,
                                  const Eigen::Vector3d& xb) {
  const Eigen::Vector3d Ea = E * xa, Etb = E.transpose() * xb;
  return {xb.dot(Ea), Ea(0) * Ea(0) + Ea(1) * Ea(1) + Etb(0) * Etb(0) + Etb(1) * Etb(1)};
}

/// Signed Sampson distance; +inf where the gradient vanishes (the point on both epipoles) or is
/// not a number. xa, xb: homogeneous (x, y, 1).
inline double sampson_signed(const Eigen::Matrix3d& E, const Eigen::Vector3d& xa,
                             const Eigen::Vector3d& xb) {
  const SampsonTerms s = sampson_terms(E, xa, xb);
  return s.gradient_sq > 0.0 ? s.residual / std::sqrt(s.gradient_sq)
                             : std::numeric_limits<double>::infinity();
}

/// Squared Sampson distance (residual^2 / gradient_sq, without the square root); +inf as above.
inline double sampson_squared(const Eigen::Matrix3d& E, const Eigen::Vector3d& xa,
                              const Eigen::Vector3d& xb) {
  const SampsonTerms s = sampson_terms(E, xa, xb);
  return s.gradient_sq > 0.0 ? s.residual * s.residual / s.gradient_sq
                             : std::numeric_limits<double>::infinity();
}

}  // namespace pepper::core::geometry
