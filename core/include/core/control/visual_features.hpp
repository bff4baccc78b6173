#pragma once
// Scalar visual features of the IBVS law and their Jacobians w.r.t. the base yaw rate.
//
// Source: METHOD.md, "Replay: control law". Inputs are in normalised image coordinates
// (x_norm = (u_px - cx_px) / fx_px), lines as x cos(theta) + y sin(theta) = rho (rad, any sign of
// rho); conventions in docs/conventions.md.
//   line feature   X = mean_i(rho_i cos theta_i)       (abscissa of the foot of each line)
//   point feature  x = mean_j(x_j)
// Jacobians (d feature / d omega_rad_s), depth terms neglected (J_v = 0, paper's approximation):
//   J_P = 1 + mean_j(x_j^2)
//   J_L = mean_i(cos^2 theta_i + rho_i^2 cos 2 theta_i)
// The sign of the rho^2 term was settled by the finite-difference test of projected 3D lines under
// base rotations (tests/core/control/test_visual_features.cpp; derivation in
// docs/method/control.md): the paper's printed minus sign is an extraction artefact.
//
// The *_rate_full functions give the exact feature rates for a known 3D structure (plane of the
// line / depth of the point) under the camera twist (-delta*omega, 0, v, 0, -omega, 0); they exist
// to quantify the approximation and to test it, the law itself never needs depth.
//
// All functions are pure and thread-safe. Empty inputs return NaN for means (callers check
// emptiness first; the IBVS law drops a missing modality).

#include <opencv2/core/types.hpp>
#include <span>

namespace pepper::core::control {

/// A line in normalised image coordinates: x cos(theta) + y sin(theta) = rho.
struct LineRhoTheta {
  double rho = 0.0;        ///< signed distance to the principal point, normalised units
  double theta_rad = 0.0;  ///< normal direction, rad
};

/// X = mean(rho cos theta). NaN when empty.
double line_feature_X(std::span<const LineRhoTheta> lines);
/// J_L = mean(cos^2 theta + rho^2 cos 2theta) = dX/domega for a pure base rotation (delta = 0).
double line_jacobian_dX_domega(std::span<const LineRhoTheta> lines);
/// Per-line term of J_L.
double line_jacobian_dX_domega(const LineRhoTheta& line);

/// x = mean(x_norm). NaN when empty.
double point_feature_x(std::span<const cv::Point2d> points_norm);
/// J_P = 1 + mean(x_norm^2) = dx/domega for a pure base rotation (delta = 0).
double point_jacobian_dx_domega(std::span<const cv::Point2d> points_norm);

/// Plane A X + B Y + C Z + D = 0 (camera frame, metres) containing a 3D line, D != 0.
struct PlaneCam {
  double a = 0.0, b = 0.0, c = 0.0, d_m = 1.0;
};

/// Exact d(rho cos theta)/dt of one line under base yaw rate omega_rad_s, forward speed v_m_s, with
/// the camera delta_m ahead of the rotation axis; plane_cam is any plane through the 3D line that
/// does not contain the optical centre.
double line_X_rate_full(const LineRhoTheta& line, const PlaneCam& plane_cam, double omega_rad_s,
                        double v_m_s, double delta_m);

/// Exact dx_norm/dt of one point at depth depth_m (camera z) under the same motion.
double point_x_rate_full(const cv::Point2d& point_norm, double depth_m, double omega_rad_s,
                         double v_m_s, double delta_m);

}  // namespace pepper::core::control
