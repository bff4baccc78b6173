// Relative yaw from matched horizontal lines (see line_yaw.hpp).
#include "core/geometry/line_yaw.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <opencv2/core/matx.hpp>

namespace pepper::core::geometry {
namespace {

constexpr double kHalfPi = 0.5 * std::numbers::pi;

// Level-frame ray of a normalised point: x_level = R_x(-pitch) x_cam.
cv::Vec3d level_ray(const cv::Point2d& p, double c, double s) {
  // R_x(-pitch) = [[1, 0, 0], [0, c, s], [0, -s, c]] with c, s = cos, sin pitch.
  return {p.x, c * p.y + s, -s * p.y + c};
}

struct LevelSegment {
  cv::Vec3d p0, p1;  // level-frame rays of the endpoints
  cv::Vec3d n;       // unit normal of the plane through the camera centre and the segment
};

std::optional<LevelSegment> level_segment(const NormSegment& seg, double c, double s,
                                          double min_leverage) {
  LevelSegment l{level_ray(seg.p0, c, s), level_ray(seg.p1, c, s), {}};
  const cv::Vec3d n = l.p0.cross(l.p1);
  const double norm = cv::norm(n);
  if (!(norm > 1e-12)) return std::nullopt;
  l.n = n / norm;
  if (std::abs(l.n[1]) < min_leverage) return std::nullopt;
  return l;
}

// Horizontal direction of a's line: n_a x (0, 1, 0) = (-n_z, 0, n_x).
cv::Vec3d horizontal_direction(const cv::Vec3d& n) { return {-n[2], 0.0, n[0]}; }

cv::Vec3d rotate_y(const cv::Vec3d& d, double yaw_rad) {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  return {c * d[0] + s * d[2], d[1], -s * d[0] + c * d[2]};
}

// The root of n_b . R_y(yaw) d = 0 with |yaw| < pi / 2 (d horizontal).
double root(const cv::Vec3d& n_b, const cv::Vec3d& d) {
  // n_b . R_y(yaw) d = cos(yaw) (n0 d0 + n2 d2) + sin(yaw) (n0 d2 - n2 d0).
  const double a = n_b[0] * d[0] + n_b[2] * d[2], b = n_b[0] * d[2] - n_b[2] * d[0];
  double yaw = std::atan2(-a, b);
  if (yaw > kHalfPi) yaw -= std::numbers::pi;
  if (yaw <= -kHalfPi) yaw += std::numbers::pi;
  return yaw;
}

// Dihedral angle between b's plane and the plane through the camera centre, b's midpoint and the
// vanishing point v: zero when b's line passes through v; about the image angle between the
// segment and the direction from its midpoint to v, and defined when v is at infinity.
double residual(const LevelSegment& b, const cv::Vec3d& v) {
  const cv::Vec3d mid = 0.5 * (b.p0 + b.p1);
  cv::Vec3d m = mid.cross(v);
  const double norm = cv::norm(m);
  if (!(norm > 1e-12)) return 0.0;  // the vanishing point is on the midpoint's ray
  m /= norm;
  return std::atan2(cv::norm(m.cross(b.n)), std::abs(m.dot(b.n)));
}

}  // namespace

std::vector<std::string> LineYawOptions::validate() const {
  std::vector<std::string> errors;
  auto check = [&](bool ok, const char* name, double value, const char* range) {
    if (!ok) {
      std::ostringstream os;
      os << "line_yaw." << name << " = " << value << " must be " << range;
      errors.push_back(os.str());
    }
  };
  check(min_leverage > 0.0 && min_leverage < 1.0, "min_leverage", min_leverage, "in (0, 1)");
  check(std::isfinite(endpoint_sigma) && endpoint_sigma > 0.0, "endpoint_sigma", endpoint_sigma,
        "> 0");
  check(std::isfinite(sway_sigma_rad) && sway_sigma_rad >= 0.0, "sway_sigma_rad", sway_sigma_rad,
        ">= 0");
  check(std::isfinite(gate_sigmas) && gate_sigmas > 0.0, "gate_sigmas", gate_sigmas, "> 0");
  check(min_inliers >= 1, "min_inliers", min_inliers, ">= 1");
  check(std::isfinite(max_sigma_rad) && max_sigma_rad > 0.0, "max_sigma_rad", max_sigma_rad,
        "> 0");
  return errors;
}

double line_yaw_residual_rad(const NormSegment& seg_a, const NormSegment& seg_b, double yaw_rad,
                             double pitch_rad) {
  const double c = std::cos(pitch_rad), s = std::sin(pitch_rad);
  const auto a = level_segment(seg_a, c, s, 1e-9);
  const auto b = level_segment(seg_b, c, s, 1e-9);
  if (!a || !b) return kHalfPi;
  return residual(*b, rotate_y(horizontal_direction(a->n), yaw_rad));
}

std::optional<LineYaw> estimate_line_yaw(const std::vector<std::pair<NormSegment, NormSegment>>& pairs,
                                         double pitch_rad, const LineYawOptions& options,
                                         const YawPrior* prior) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument("estimate_line_yaw: " + errors.front());
  }
  if (!std::isfinite(pitch_rad)) throw std::invalid_argument("estimate_line_yaw: pitch_rad is not finite");
  if (prior && !(prior->sigma_rad > 0.0 && std::isfinite(prior->yaw_rad))) {
    throw std::invalid_argument("estimate_line_yaw: the prior needs a finite yaw and a sigma > 0");
  }
  const double c = std::cos(pitch_rad), s = std::sin(pitch_rad);
  struct Usable {
    cv::Vec3d d_a;  // unit horizontal direction in a
    LevelSegment b;
    double length_a, length_b;  // normalised image lengths
  };
  std::vector<Usable> use;
  use.reserve(pairs.size());
  for (const auto& [sa, sb] : pairs) {
    const auto a = level_segment(sa, c, s, options.min_leverage);
    const auto b = level_segment(sb, c, s, options.min_leverage);
    if (!a || !b) continue;
    // A line on the horizon (a horizontal line at the camera's height) has a plane with no
    // horizontal normal component: its equation holds for every yaw. Not usable.
    constexpr double kMinHorizontal = 1e-2;
    if (std::hypot(a->n[0], a->n[2]) < kMinHorizontal || std::hypot(b->n[0], b->n[2]) < kMinHorizontal) {
      continue;
    }
    cv::Vec3d d = horizontal_direction(a->n);
    d /= cv::norm(d);
    use.push_back({d, *b, std::hypot(sa.p1.x - sa.p0.x, sa.p1.y - sa.p0.y),
                   std::hypot(sb.p1.x - sb.p0.x, sb.p1.y - sb.p0.y)});
  }
  const int n = static_cast<int>(use.size());
  if (n < options.min_inliers) return std::nullopt;

  // Each line's equation f_i(yaw) = n_b . R_y(yaw) d_a (unit vectors) with its noise: the plane
  // normals' directions err by about the endpoint noise over the segment's length in each view,
  // plus the base's sway; its information is f_i'(yaw)^2 / sigma_i^2. A wall seen face-on has
  // f_i' near zero: it agrees with almost any yaw and must not outvote the lines that pin it
  // (counting lines did, on Pepper's key images).
  std::vector<double> var(static_cast<size_t>(n));
  const double e2 = options.endpoint_sigma * options.endpoint_sigma;
  for (int i = 0; i < n; ++i) {
    const Usable& u = use[static_cast<size_t>(i)];
    const double la2 = u.length_a * u.length_a, lb2 = u.length_b * u.length_b;
    var[static_cast<size_t>(i)] = e2 * (1.0 / std::max(la2, 1e-12) + 1.0 / std::max(lb2, 1e-12)) +
                                  options.sway_sigma_rad * options.sway_sigma_rad;
  }
  // f_i and f_i' at the yaw whose cosine and sine are cy, sy (computed once per yaw: support()
  // evaluates every line at every proposal).
  auto f_of = [&](int i, double cy, double sy, double* df) {
    const Usable& u = use[static_cast<size_t>(i)];
    const cv::Vec3d& nb = u.b.n;
    const double a = nb[0] * u.d_a[0] + nb[2] * u.d_a[2], b = nb[0] * u.d_a[2] - nb[2] * u.d_a[0];
    *df = -sy * a + cy * b;
    return cy * a + sy * b;
  };
  const double gate2 = options.gate_sigmas * options.gate_sigmas;
  // Inliers of a yaw (|f_i| within gate_sigmas of its noise) and their information.
  auto support = [&](double yaw, std::vector<int>* inliers) {
    const double cy = std::cos(yaw), sy = std::sin(yaw);
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
      double df = 0.0;
      const double f = f_of(i, cy, sy, &df);
      if (f * f <= gate2 * var[static_cast<size_t>(i)]) {
        sum += df * df / var[static_cast<size_t>(i)];
        if (inliers) inliers->push_back(i);
      }
    }
    return sum;
  };
  double best_yaw = 0.0, best_support = -1.0;
  for (int i = 0; i < n; ++i) {
    const Usable& u = use[static_cast<size_t>(i)];
    const double yaw = root(u.b.n, u.d_a);
    if (prior && std::abs(yaw - prior->yaw_rad) > options.gate_sigmas * prior->sigma_rad) continue;
    const double sup = support(yaw, nullptr);
    if (sup > best_support) {
      best_support = sup;
      best_yaw = yaw;
    }
  }
  if (best_support < 0.0) return std::nullopt;  // no proposal near the prior
  std::vector<int> inliers;
  support(best_yaw, &inliers);
  if (static_cast<int>(inliers.size()) < options.min_inliers) return std::nullopt;

  // Weighted Gauss-Newton on the inliers' f_i.
  double yaw = best_yaw;
  for (int it = 0; it < 6; ++it) {
    double jtj = 0.0, jtr = 0.0;
    const double cy = std::cos(yaw), sy = std::sin(yaw);
    for (const int i : inliers) {
      double df = 0.0;
      const double f = f_of(i, cy, sy, &df);
      jtj += df * df / var[static_cast<size_t>(i)];
      jtr += df * f / var[static_cast<size_t>(i)];
    }
    if (!(jtj > 0.0)) break;
    const double step = -jtr / jtj;
    yaw += step;
    if (std::abs(step) < 1e-9) break;
  }
  if (!(std::abs(yaw) < kHalfPi)) return std::nullopt;
  inliers.clear();
  const double information = support(yaw, &inliers);
  if (static_cast<int>(inliers.size()) < options.min_inliers || !(information > 0.0)) {
    return std::nullopt;
  }
  LineYaw out;
  out.yaw_rad = yaw;
  out.inliers = static_cast<int>(inliers.size());
  out.usable = n;
  double sum_sq = 0.0;
  for (const int i : inliers) {
    const double r = residual(use[static_cast<size_t>(i)].b, rotate_y(use[static_cast<size_t>(i)].d_a, yaw));
    sum_sq += r * r;
  }
  out.rms_residual_rad = std::sqrt(sum_sq / static_cast<double>(inliers.size()));
  out.sigma_rad = 1.0 / std::sqrt(information);
  if (out.sigma_rad > options.max_sigma_rad) return std::nullopt;
  return out;
}

}  // namespace pepper::core::geometry
