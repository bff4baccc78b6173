#pragma once
// A detected image line segment and its normalised (rho, theta) form.
//
// Convention (docs/conventions.md, METHOD.md "Control law"): in normalised image coordinates a
// line is `x_norm cos(theta) + y_norm sin(theta) = rho`. Canonical form: theta in (-pi/2, pi/2]
// (so cos(theta) >= 0: the normal points to +x, or to +y for a horizontal line), rho any sign.
// Consequences: a vertical image line has theta = 0 and rho = its x_norm; a horizontal image line
// has theta = pi/2 and rho = its y_norm; the foot of the perpendicular from the principal point is
// (rho cos(theta), rho sin(theta)), so `rho * cos(theta)` is the feature X of the control law.
//
// Segment orientation: p0_px -> p1_px is oriented so that the brighter side lies on the left of
// the direction of travel in the image (x right, y down): with d the unit direction p0 -> p1, the
// mean image gradient across the segment has a positive component along (d_y, -d_x). The
// LBD-style descriptor is computed in this frame, so the order is part of the serialised data.

#include <opencv2/core/types.hpp>

namespace pepper::core::features {

/// Normalised line parameters in canonical form (see file comment).
struct RhoTheta {
  double rho = 0.0;
  double theta_rad = 0.0;
};

/// Canonical (rho, theta) of the infinite line through two distinct normalised points.
/// Throws std::invalid_argument when the points coincide (|a - b| < 1e-12).
RhoTheta rho_theta_from_points(const cv::Point2d& a_norm, const cv::Point2d& b_norm);

/// Brings any (rho, theta) to the canonical range (theta in (-pi/2, pi/2]); same line.
RhoTheta canonical_rho_theta(double rho, double theta_rad);

/// Homogeneous line (a, b, c) with a*x + b*y + c = 0 and a^2 + b^2 = 1, from (rho, theta).
cv::Vec3d homogeneous_line(const RhoTheta& l);

struct LineSegment {
  cv::Point2f p0_px;       ///< first endpoint, pixels (oriented, see file comment)
  cv::Point2f p1_px;       ///< second endpoint, pixels
  cv::Point2d p0_norm;     ///< p0 in normalised coordinates (intrinsics of the image)
  cv::Point2d p1_norm;     ///< p1 in normalised coordinates
  RhoTheta line;           ///< canonical normalised form of the supporting line
  float length_px = 0.0f;  ///< |p1 - p0| in pixels
};

}  // namespace pepper::core::features
