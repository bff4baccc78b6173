// vpFeaturePoint / vpFeatureLine behind Eigen types (see visual_features.hpp).
#include "visp_adapter/visual_features.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include <visp3/core/vpMatrix.h>
#include <visp3/visual_features/vpFeatureLine.h>
#include <visp3/visual_features/vpFeaturePoint.h>

#include "visp_matrix.hpp"

namespace pepper::visp_adapter {
namespace {

void require_finite(const char* function, const char* name, double value) {
  if (!std::isfinite(value)) {
    throw std::invalid_argument(std::string(function) + ": " + name + " must be finite");
  }
}

}  // namespace

InteractionMatrix point_interaction(double x_norm, double y_norm, double depth_m) {
  require_finite("point_interaction", "x_norm", x_norm);
  require_finite("point_interaction", "y_norm", y_norm);
  // vpFeaturePoint throws for Z <= 0 (a point behind or on the camera); say so in our words.
  if (!(std::isfinite(depth_m) && depth_m > 0.0)) {
    throw std::invalid_argument("point_interaction: depth_m = " + std::to_string(depth_m) +
                                " must be finite and > 0");
  }
  vpFeaturePoint p;
  p.buildFrom(x_norm, y_norm, depth_m);
  return to_eigen<2, 6>(p.interaction());
}

InteractionMatrix line_interaction(double rho, double theta_rad, const PlaneCam& plane_cam) {
  require_finite("line_interaction", "rho", rho);
  require_finite("line_interaction", "theta_rad", theta_rad);
  require_finite("line_interaction", "plane_cam.a", plane_cam.a);
  require_finite("line_interaction", "plane_cam.b", plane_cam.b);
  require_finite("line_interaction", "plane_cam.c", plane_cam.c);
  // D = 0 is a plane through the optical centre: it gives no depth (ViSP divides by D).
  if (!(std::isfinite(plane_cam.d_m) && plane_cam.d_m != 0.0)) {
    throw std::invalid_argument("line_interaction: plane_cam.d_m must be finite and != 0");
  }
  vpFeatureLine l;
  l.buildFrom(rho, theta_rad, plane_cam.a, plane_cam.b, plane_cam.c, plane_cam.d_m);
  return to_eigen<2, 6>(l.interaction());
}

}  // namespace pepper::visp_adapter
