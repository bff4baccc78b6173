#pragma once
// ViSP's interaction matrices of the point and line features (vpFeaturePoint, vpFeatureLine),
// behind types that are not ViSP's: callers compile as C++20, ViSP 3.5 only as C++17
// (visp_adapter/CMakeLists.txt). Used to check the core's own closed forms against the reference
// implementation of the method's lab (tests/core/control/test_visual_features_visp.cpp) and to
// measure what calling ViSP would cost in the navigator's hot path (bench/micro/bench_visp.cpp).
//
// Conventions are ViSP's, which are the project's (docs/conventions.md): normalised image
// coordinates x = (u - u0)/px, y = (v - v0)/py; camera frame x right, y down, z forward; a line is
// x cos(theta) + y sin(theta) = rho. Columns of an interaction matrix are the camera twist
// (vx, vy, vz, wx, wy, wz) in the camera frame, m/s and rad/s: d(feature)/dt = L * twist.
//
// Errors: arguments ViSP would refuse (depth <= 0, a plane through the optical centre, non-finite
// values) throw std::invalid_argument naming the argument, before ViSP is called. Pure functions;
// thread-safe (each call builds its own ViSP objects).

#include <Eigen/Core>

namespace pepper::visp_adapter {

/// Two feature rows by the six camera-twist columns.
using InteractionMatrix = Eigen::Matrix<double, 2, 6>;

/// Plane a X + b Y + c Z + d_m = 0 in the camera frame (metres), d_m != 0: any plane through a
/// 3D line that does not contain the optical centre gives the line's depth terms.
struct PlaneCam {
  double a = 0.0;
  double b = 0.0;
  double c = 0.0;
  double d_m = 1.0;
};

/// vpFeaturePoint::interaction(): rows (x, y) of the point (x_norm, y_norm) at depth depth_m > 0.
InteractionMatrix point_interaction(double x_norm, double y_norm, double depth_m);

/// vpFeatureLine::interaction(): rows (rho, theta) of the line x cos(theta) + y sin(theta) = rho
/// lying in plane_cam.
InteractionMatrix line_interaction(double rho, double theta_rad, const PlaneCam& plane_cam);

}  // namespace pepper::visp_adapter
