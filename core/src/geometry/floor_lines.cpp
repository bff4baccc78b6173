#include "core/geometry/floor_lines.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

namespace pepper::core::geometry {

namespace {

// A floor point needs its ray this far below the horizon (the ray's downward component over its
// forward one): closer to the horizon a pixel spans metres of floor.
constexpr double kMinDepression = 1e-3;
// The lines fix a direction when their information along it is at least this (1/m^2: a sigma
// of 10 cm or less).
constexpr double kMinInformation_1_m2 = 100.0;

struct FloorLine {
  Eigen::Vector2d n;  // unit normal
  double c = 0.0;     // n . p = c
  Eigen::Vector2d d;  // unit direction, p1 - p0
};

// The floor point of the segment's end `far`, or, when it lies beyond the range (or above the
// horizon), of the point of the segment from `near` towards it where the range ends (bisection
// in the image: a floor line's image is a line).
std::optional<Eigen::Vector2d> clipped_floor_point(const cv::Point2d& near, const cv::Point2d& far,
                                                   const FloorCamera& camera,
                                                   double max_range_m) {
  if (const auto p = floor_point(far, camera, max_range_m)) return p;
  double lo = 0.0, hi = 1.0;  // near is within range at lo, far is not at hi
  for (int i = 0; i < 30; ++i) {
    const double mid = 0.5 * (lo + hi);
    (floor_point(near + (far - near) * mid, camera, max_range_m) ? lo : hi) = mid;
  }
  return floor_point(near + (far - near) * lo, camera, max_range_m);
}

// The vertical component of the unit normal of the plane through the camera centre and the
// segment, in the level frame (x right, y down, z forward).
double leverage(const NormSegment& s, const FloorCamera& camera) {
  const double c = std::cos(camera.pitch_rad), sn = std::sin(camera.pitch_rad);
  auto level = [&](const cv::Point2d& p) {
    return Eigen::Vector3d(p.x, c * p.y + sn, -sn * p.y + c);
  };
  const Eigen::Vector3d n = level(s.p0).cross(level(s.p1));
  const double norm = n.norm();
  return norm > 0.0 ? std::abs(n.y()) / norm : 0.0;
}

std::optional<FloorLine> floor_line(const NormSegment& s, const FloorCamera& camera,
                                    double max_range_m) {
  // The end nearer the camera (lower in the image) must be on the floor within range; the other
  // is cut where the range ends.
  const bool p0_near = s.p0.y >= s.p1.y;
  const cv::Point2d& near = p0_near ? s.p0 : s.p1;
  const cv::Point2d& far = p0_near ? s.p1 : s.p0;
  const auto p0 = floor_point(near, camera, max_range_m);
  if (!p0) return std::nullopt;
  const auto p1 = clipped_floor_point(near, far, camera, max_range_m);
  if (!p1) return std::nullopt;
  const Eigen::Vector2d v = *p1 - *p0;
  const double len = v.norm();
  if (!(len > 1e-6)) return std::nullopt;
  FloorLine l;
  l.d = v / len;
  l.n = Eigen::Vector2d(-l.d.y(), l.d.x());
  l.c = l.n.dot(*p0);
  return l;
}

Eigen::Matrix2d rot(double a) {
  Eigen::Matrix2d r;
  r << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  return r;
}

// The equation's right side and the lines' direction mismatch for perturbed inputs (the numeric
// propagation below); nullopt when a perturbed segment leaves the floor.
struct Reading {
  Eigen::Vector2d n;
  double z = 0.0;
  double direction_error = 0.0;
};
std::optional<Reading> read(const NormSegment& a, const NormSegment& b, double yaw_rad,
                            const FloorCamera& cam_a, const FloorCamera& cam_b,
                            double max_range_m) {
  const auto la = floor_line(a, cam_a, max_range_m);
  const auto lb = floor_line(b, cam_b, max_range_m);
  if (!la || !lb) return std::nullopt;
  const Eigen::Vector2d nb_in_a = rot(yaw_rad) * lb->n;
  const double dot = la->n.dot(nb_in_a);
  const double s = dot >= 0.0 ? 1.0 : -1.0;
  Reading r;
  r.n = la->n;
  r.z = la->c - s * lb->c;
  r.direction_error = std::acos(std::min(1.0, std::abs(dot)));
  return r;
}

}  // namespace

std::optional<Eigen::Vector2d> floor_point(const cv::Point2d& norm, const FloorCamera& camera,
                                           double max_range_m) {
  // Level frame (x right, y down, z forward): R_x(-pitch) (u, v, 1).
  const double c = std::cos(camera.pitch_rad), s = std::sin(camera.pitch_rad);
  const double x = norm.x;
  const double y = c * norm.y + s;   // downward
  const double z = -s * norm.y + c;  // forward
  if (!(z > 0.0) || !(y > kMinDepression * z)) return std::nullopt;
  const double t = camera.height_m / y;
  const Eigen::Vector2d p(t * z, -t * x);  // forward, left
  if (!(p.norm() <= max_range_m)) return std::nullopt;
  return p;
}

CameraOnBase pepper_top_camera(double head_pitch_rad) {
  constexpr double kPivotHeightM = 1.153 - 0.16284;
  constexpr double kPivotForwardM = 0.048 - 0.08601;
  const double c = std::cos(head_pitch_rad), s = std::sin(head_pitch_rad);
  // R_y(pitch) (0.08601, 0, 0.16284): pitch > 0 turns the head's x axis down.
  return {kPivotHeightM - 0.08601 * s + 0.16284 * c, kPivotForwardM + 0.08601 * c + 0.16284 * s};
}

std::vector<std::string> FloorLineOptions::validate() const {
  std::vector<std::string> errors;
  auto bad = [&](const char* name, double v, const char* range) {
    std::ostringstream os;
    os << name << " = " << v << ": must be " << range;
    errors.push_back(os.str());
  };
  if (!(max_range_m > 0.0)) bad("max_range_m", max_range_m, "> 0");
  if (!(endpoint_sigma > 0.0)) bad("endpoint_sigma", endpoint_sigma, "> 0");
  if (!(sway_sigma_rad >= 0.0)) bad("sway_sigma_rad", sway_sigma_rad, ">= 0");
  if (!(max_direction_error_rad > 0.0)) {
    bad("max_direction_error_rad", max_direction_error_rad, "> 0");
  }
  if (!(gate_sigmas > 0.0)) bad("gate_sigmas", gate_sigmas, "> 0");
  if (min_inliers < 1) bad("min_inliers", min_inliers, ">= 1");
  if (!(min_leverage > 0.0 && min_leverage < 1.0)) bad("min_leverage", min_leverage, "in (0, 1)");
  if (!(max_angle_to_forward_rad > 0.0 && max_angle_to_forward_rad <= M_PI / 2)) {
    bad("max_angle_to_forward_rad", max_angle_to_forward_rad, "in (0, pi/2]");
  }
  return errors;
}

std::optional<FloorLineEquation> floor_line_equation(const NormSegment& seg_a,
                                                     const NormSegment& seg_b, double yaw_rad,
                                                     const FloorCamera& camera,
                                                     const FloorLineOptions& options,
                                                     double yaw_sigma_rad) {
  if (leverage(seg_a, camera) < options.min_leverage ||
      leverage(seg_b, camera) < options.min_leverage) {
    return std::nullopt;
  }
  const auto r0 = read(seg_a, seg_b, yaw_rad, camera, camera, options.max_range_m);
  if (!r0) return std::nullopt;
  // The line's direction is (n.y, -n.x): its angle to the forward axis is that of n to the left.
  if (std::abs(r0->n.y()) < std::cos(options.max_angle_to_forward_rad) - 1e-12) {
    return std::nullopt;
  }
  // Numeric propagation: each endpoint moved across its segment by endpoint_sigma, each view's
  // pitch by sway_sigma_rad; the squared changes of z and of the direction mismatch add up.
  double var_z = 0.0, var_dir = 0.0;
  auto add = [&](const std::optional<Reading>& r, double scale) {
    if (!r) {  // the perturbation leaves the floor: the line is too close to the horizon
      var_z = std::numeric_limits<double>::infinity();
      return;
    }
    var_z += std::pow((r->z - r0->z) * scale, 2);
    var_dir += std::pow((r->direction_error - r0->direction_error) * scale, 2);
  };
  constexpr double kStep = 0.25;  // of a sigma: small enough to stay linear
  for (int view = 0; view < 2; ++view) {
    const NormSegment& s = view == 0 ? seg_a : seg_b;
    const cv::Point2d along = s.p1 - s.p0;
    const double len = std::hypot(along.x, along.y);
    if (!(len > 0.0)) return std::nullopt;
    const cv::Point2d across(-along.y / len, along.x / len);
    for (int end = 0; end < 2; ++end) {
      NormSegment moved = s;
      (end == 0 ? moved.p0 : moved.p1) += across * (kStep * options.endpoint_sigma);
      add(view == 0 ? read(moved, seg_b, yaw_rad, camera, camera, options.max_range_m)
                    : read(seg_a, moved, yaw_rad, camera, camera, options.max_range_m),
          1.0 / kStep);
    }
    if (options.sway_sigma_rad > 0.0) {
      FloorCamera tilted = camera;
      tilted.pitch_rad += kStep * options.sway_sigma_rad;
      add(view == 0 ? read(seg_a, seg_b, yaw_rad, tilted, camera, options.max_range_m)
                    : read(seg_a, seg_b, yaw_rad, camera, tilted, options.max_range_m),
          1.0 / kStep);
    }
  }
  if (!std::isfinite(var_z)) return std::nullopt;
  const double sigma_dir = std::sqrt(var_dir + yaw_sigma_rad * yaw_sigma_rad);
  if (r0->direction_error > options.max_direction_error_rad + options.gate_sigmas * sigma_dir) {
    return std::nullopt;  // not the same floor direction after the yaw: not a floor line pair
  }
  return FloorLineEquation{r0->n, r0->z, std::max(std::sqrt(var_z), 1e-4)};
}

std::optional<FloorFix> estimate_floor_position(
    const std::vector<std::pair<NormSegment, NormSegment>>& pairs, const FloorCamera& camera,
    const FloorPrior& prior, const FloorLineOptions& options) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument("estimate_floor_position: " + errors.front());
  }
  if (!(camera.height_m > 0.0) || !(std::abs(camera.pitch_rad) < 1.0)) {
    throw std::invalid_argument("estimate_floor_position: camera height must be > 0 m and |pitch| < 1 rad");
  }
  const double g2 = options.gate_sigmas * options.gate_sigmas;
  // Usable lines inside the prior's gate.
  std::vector<FloorLineEquation> lines;
  int usable = 0;
  for (const auto& [a, b] : pairs) {
    const auto e = floor_line_equation(a, b, prior.yaw_rad, camera, options, prior.yaw_sigma_rad);
    if (!e) continue;
    ++usable;
    const double innovation = e->z_m - e->n.dot(prior.t_m);
    const double s = e->sigma_m * e->sigma_m + e->n.dot(prior.cov_m2 * e->n);
    if (innovation * innovation <= g2 * s) lines.push_back(*e);
  }
  if (static_cast<int>(lines.size()) < options.min_inliers) return std::nullopt;
  // Proposals: each line's one-line update of the prior, with its covariance. A line agrees
  // with a proposal when its residual is within the gate of its own and the proposal's sigma
  // (two lines 2 sigmas off each way still agree: they are one structure).
  struct Proposal {
    Eigen::Vector2d t;
    Eigen::Matrix2d cov;
  };
  std::vector<Proposal> proposals;
  for (const FloorLineEquation& e : lines) {
    const Eigen::Vector2d pn = prior.cov_m2 * e.n;
    const double s = e.sigma_m * e.sigma_m + e.n.dot(pn);
    proposals.push_back({prior.t_m + pn * ((e.z_m - e.n.dot(prior.t_m)) / s),
                         prior.cov_m2 - pn * pn.transpose() / s});
  }
  auto agrees = [&](const FloorLineEquation& e, const Proposal& p) {
    const double r = e.z_m - e.n.dot(p.t);
    return r * r <= g2 * (e.sigma_m * e.sigma_m + e.n.dot(p.cov * e.n));
  };
  double best_info = -1.0;
  Proposal best = proposals.front();
  for (const Proposal& p : proposals) {
    double info = 0.0;
    for (const FloorLineEquation& e : lines) {
      if (agrees(e, p)) info += 1.0 / (e.sigma_m * e.sigma_m);
    }
    if (info > best_info) {
      best_info = info;
      best = p;
    }
  }
  // Information-form least squares of the prior and the agreeing lines, re-gated once at the
  // result.
  const Eigen::Matrix2d prior_info = prior.cov_m2.inverse();
  FloorFix fix;
  fix.usable = usable;
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::Matrix2d info = Eigen::Matrix2d::Zero();
    Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
    int inliers = 0;
    for (const FloorLineEquation& e : lines) {
      if (!agrees(e, best)) continue;
      const double w = 1.0 / (e.sigma_m * e.sigma_m);
      info += w * e.n * e.n.transpose();
      rhs += w * e.z_m * e.n;
      ++inliers;
    }
    if (inliers < options.min_inliers) return std::nullopt;
    const Eigen::Matrix2d total = prior_info + info;
    best.t = total.ldlt().solve(prior_info * prior.t_m + rhs);
    best.cov = total.inverse();
    fix.t_m = best.t;
    fix.cov_m2 = best.cov;
    fix.info_1_m2 = info;
    fix.info_vec_1_m = rhs;
    fix.inliers = inliers;
  }
  // Directions the lines inform only weakly keep the prior's position and covariance: a corridor's
  // two edges, each a little tilted by noise, would otherwise move the position along them
  // through their tilts (centimetres per centimetre of lateral noise).
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(fix.info_1_m2);
  Eigen::Matrix2d strong = Eigen::Matrix2d::Zero();
  for (int i = 0; i < 2; ++i) {
    if (eig.eigenvalues()(i) >= kMinInformation_1_m2) {
      strong += eig.eigenvectors().col(i) * eig.eigenvectors().col(i).transpose();
    }
  }
  if (strong.isZero()) return std::nullopt;
  const Eigen::Matrix2d weak = Eigen::Matrix2d::Identity() - strong;
  fix.t_m = prior.t_m + strong * (fix.t_m - prior.t_m);
  fix.cov_m2 = strong * fix.cov_m2 * strong + weak * prior.cov_m2 * weak;
  return fix;
}

}  // namespace pepper::core::geometry
