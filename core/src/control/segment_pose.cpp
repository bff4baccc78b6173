#include "core/control/segment_pose.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <opencv2/core.hpp>
#include <random>
#include <sstream>
#include <stdexcept>

namespace pepper::core::control {

std::vector<std::string> SegmentPoseOptions::validate() const {
  std::vector<std::string> errors;
  auto check = [&](bool ok, const char* name, double value, const char* range) {
    if (!ok) {
      std::ostringstream os;
      os << "control.vnhv.pose." << name << " = " << value << " must be " << range;
      errors.push_back(os.str());
    }
  };
  check(std::isfinite(min_parallax_rad) && min_parallax_rad > 0.0, "min_parallax_rad",
        min_parallax_rad, "> 0");
  check(std::isfinite(max_reprojection_px) && max_reprojection_px > 0.0, "max_reprojection_px",
        max_reprojection_px, "> 0");
  check(min_points >= 3, "min_points", min_points, ">= 3");
  check(ransac_iterations >= 1, "ransac_iterations", ransac_iterations, ">= 1");
  check(gauss_newton_iterations >= 1, "gauss_newton_iterations", gauss_newton_iterations, ">= 1");
  check(std::isfinite(max_segment_yaw_rad) && max_segment_yaw_rad > 0.0 &&
            max_segment_yaw_rad < std::numbers::pi,
        "max_segment_yaw_rad", max_segment_yaw_rad, "in (0, pi)");
  return errors;
}

namespace {

constexpr double kMinDepth = 1e-6;  // in segment units: in front of the camera

void check_inputs(double focal_px, const SegmentPoseOptions& options, const char* who) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument(std::string(who) + ": " + errors.front());
  }
  if (!std::isfinite(focal_px) || focal_px <= 0.0) {
    throw std::invalid_argument(std::string(who) + ": focal_px must be finite and > 0");
  }
}

// Reprojection error (normalised units) of X_r seen from pose at x; infinite behind the camera.
double reprojection_error(const PlanarPose& pose, const cv::Vec3d& X_r, const cv::Point2d& x) {
  const cv::Vec3d Xc = to_camera(pose, X_r);
  if (Xc[2] <= kMinDepth) return std::numeric_limits<double>::infinity();
  return std::hypot(Xc[0] / Xc[2] - x.x, Xc[1] / Xc[2] - x.y);
}

// Pose from the linear system in w = (c, s, t_x, t_z) over the given points (>= 2).
std::optional<PlanarPose> linear_resection(const std::vector<cv::Vec3d>& X,
                                           const std::vector<cv::Point2d>& x,
                                           const std::vector<int>& use) {
  cv::Matx44d AtA = cv::Matx44d::zeros();
  cv::Vec4d Atb(0, 0, 0, 0);
  for (const int i : use) {
    const double Xr = X[i][0], Yr = X[i][1], Zr = X[i][2], u = x[i].x, v = x[i].y;
    const cv::Vec4d row1(u * Zr - Xr, -u * Xr - Zr, -1.0, u);  // u Z_C - X_C = 0
    const cv::Vec4d row2(v * Zr, -v * Xr, 0.0, v);             // v Z_C = Y
    AtA += row1 * row1.t() + row2 * row2.t();
    Atb += row2 * Yr;
  }
  cv::Vec4d w;
  if (!cv::solve(AtA, Atb, w, cv::DECOMP_LU)) return std::nullopt;
  const double norm_cs = std::hypot(w[0], w[1]);
  // (c, s) must be a rotation: far from unit norm the sample is degenerate (e.g. points at
  // the camera's height, which constrain depth through v Z_C = Y not at all).
  if (!std::isfinite(norm_cs) || norm_cs < 0.5 || norm_cs > 1.5) return std::nullopt;
  const double c = w[0] / norm_cs, s = w[1] / norm_cs, tx = w[2], tz = w[3];
  // t = (c py - s px, 0, -(c px + s py)) inverted.
  return PlanarPose{-s * tx - c * tz, c * tx - s * tz, std::atan2(s, c)};
}

// One Gauss-Newton step on the reprojection errors of `use` in (px, py, yaw). false when the
// normal equations are singular.
bool gauss_newton_step(const std::vector<cv::Vec3d>& X, const std::vector<cv::Point2d>& x,
                       const std::vector<int>& use, PlanarPose& pose) {
  cv::Matx33d JtJ = cv::Matx33d::zeros();
  cv::Vec3d Jtr(0, 0, 0);
  const double c = std::cos(pose.yaw_rad), s = std::sin(pose.yaw_rad);
  for (const int i : use) {
    const cv::Vec3d Xc = to_camera(pose, X[i]);
    if (Xc[2] <= kMinDepth) continue;
    const double inv_z = 1.0 / Xc[2];
    const double u = Xc[0] * inv_z, v = Xc[1] * inv_z;
    // d(X_C, Z_C) / d(px, py, yaw) from the model in the header.
    const cv::Vec3d dXc(-s, c, Xc[2]);
    const cv::Vec3d dZc(-c, -s, -Xc[0]);
    const cv::Vec3d ju = (dXc - u * dZc) * inv_z;
    const cv::Vec3d jv = -v * inv_z * dZc;
    const double ru = u - x[i].x, rv = v - x[i].y;
    JtJ += ju * ju.t() + jv * jv.t();
    Jtr += ju * ru + jv * rv;
  }
  cv::Vec3d delta;
  if (!cv::solve(JtJ, -Jtr, delta, cv::DECOMP_CHOLESKY)) return false;
  pose.x_m += delta[0];
  pose.y_m += delta[1];
  pose.yaw_rad = wrap_angle_rad(pose.yaw_rad + delta[2]);
  return true;
}

// IP's pose on the arc model for its yaw psi (see fit_arc_segment).
PlanarPose arc_pose(double psi_rad) {
  return {-std::cos(0.5 * psi_rad), -std::sin(0.5 * psi_rad), psi_rad};
}

// Robust cost of the arc model at psi: sum of Cauchy(Sampson distance / scale) over the matches.
double arc_cost(const std::vector<CornerObservation>& matches, double psi_rad, double scale) {
  const PlanarPose prev = arc_pose(psi_rad);
  const double c = std::cos(psi_rad), s = std::sin(psi_rad);
  const cv::Vec3d t = to_camera(prev, {0, 0, 0});  // t[1] == 0: planar
  // E = [t]x R_y(psi) (x_IP^T E x_IN = 0) has four non-zero entries for a planar motion:
  // E = [[0, -t2, 0], [t2 c + t0 s, 0, t2 s - t0 c], [0, t0, 0]]. The products and sums below
  // are those of the full 3x3 products without the terms that are exact zeros (same values;
  // ~2x faster, on the grid of fit_arc_segment that runs ~1900 times per new segment).
  const double e01 = -t[2], e10 = t[2] * c + t[0] * s, e12 = t[2] * s - t[0] * c, e21 = t[0];
  // sum log(1 + r^2) as the log of products of up to kChunk factors: one log per chunk instead
  // of one per match (the grid of fit_arc_segment evaluates ~1900 angles per segment, and the
  // logs were most of the navigator's time on a switch frame: perf, bench_navigator_real). The
  // factors are >= 1, at most kChunk of them <= kLargeFactor each share a product (< 1e288: no
  // overflow), larger ones take their own log; the sum differs from the per-match one by
  // rounding only.
  constexpr int kChunk = 16;
  constexpr double kLargeFactor = 1e18;
  double cost = 0.0, product = 1.0;
  int in_chunk = 0;
  for (const CornerObservation& m : matches) {
    const double ax = m.next_norm.x, ay = m.next_norm.y, bx = m.other_norm.x, by = m.other_norm.y;
    const double ea0 = e01 * ay, ea1 = e10 * ax + e12, ea2 = e21 * ay;  // E a
    const double etb0 = e10 * by, etb1 = e01 * bx + e21;                // (E^T b)[0..1]
    const double den = ea0 * ea0 + ea1 * ea1 + etb0 * etb0 + etb1 * etb1;
    const double r = den > 0.0 ? (bx * ea0 + by * ea1 + ea2) / std::sqrt(den) / scale : 0.0;
    const double factor = 1.0 + r * r;
    if (factor > kLargeFactor) {
      cost += std::log(factor);
      continue;
    }
    product *= factor;
    if (++in_chunk == kChunk) {
      cost += std::log(product);
      product = 1.0;
      in_chunk = 0;
    }
  }
  return cost + std::log(product);
}

}  // namespace

std::optional<PlanarPose> fit_arc_segment(const std::vector<CornerObservation>& matches,
                                          double focal_px, const SegmentPoseOptions& options) {
  check_inputs(focal_px, options, "fit_arc_segment");
  if (static_cast<int>(matches.size()) < options.min_points) return std::nullopt;
  const double scale = options.max_reprojection_px / focal_px;
  // Grid at a quarter pixel of rotation: the cost has local minima (Cauchy), the grid finds the
  // basin, golden section the minimum within one grid step.
  const double step = 0.25 / focal_px;
  const int half = static_cast<int>(std::ceil(options.max_segment_yaw_rad / step));
  double best_psi = 0.0, best_cost = std::numeric_limits<double>::infinity();
  for (int k = -half; k <= half; ++k) {
    const double psi = k * step;
    const double cost = arc_cost(matches, psi, scale);
    if (cost < best_cost) {
      best_cost = cost;
      best_psi = psi;
    }
  }
  double lo = best_psi - step, hi = best_psi + step;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = arc_cost(matches, x1, scale), f2 = arc_cost(matches, x2, scale);
  for (int it = 0; it < 30; ++it) {
    if (f1 < f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - g * (hi - lo);
      f1 = arc_cost(matches, x1, scale);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + g * (hi - lo);
      f2 = arc_cost(matches, x2, scale);
    }
  }
  return arc_pose(0.5 * (lo + hi));
}

cv::Vec3d to_camera(const PlanarPose& c_in_r, const cv::Vec3d& X_r) {
  const double c = std::cos(c_in_r.yaw_rad), s = std::sin(c_in_r.yaw_rad);
  const double dz = X_r[2] - c_in_r.x_m;  // forward offset from C
  const double dx = X_r[0] + c_in_r.y_m;  // rightward offset from C
  return {s * dz + c * dx, X_r[1], c * dz - s * dx};
}

std::optional<SegmentModel> build_segment_model(const PlanarPose& prev_in_next,
                                                const std::vector<CornerObservation>& matches,
                                                double focal_px,
                                                const SegmentPoseOptions& options) {
  check_inputs(focal_px, options, "build_segment_model");
  PlanarPose prev = prev_in_next;
  const double baseline = std::hypot(prev.x_m, prev.y_m);
  if (!std::isfinite(baseline) || baseline < 1e-9) return std::nullopt;
  prev.x_m /= baseline;
  prev.y_m /= baseline;

  // Planar transform IN -> IP as a matrix: X_IP = R_y X_IN + t.
  const double c = std::cos(prev.yaw_rad), s = std::sin(prev.yaw_rad);
  const cv::Matx33d R(c, 0, s, 0, 1, 0, -s, 0, c);
  const cv::Vec3d t = to_camera(prev, cv::Vec3d(0, 0, 0));
  const double max_err = options.max_reprojection_px / focal_px;
  const double min_cos_parallax = std::cos(options.min_parallax_rad);

  SegmentModel model;
  model.prev_in_next = prev;
  for (const CornerObservation& m : matches) {
    const cv::Vec3d d_next(m.next_norm.x, m.next_norm.y, 1.0);
    const cv::Vec3d d_prev(m.other_norm.x, m.other_norm.y, 1.0);
    const cv::Vec3d r_next = R * d_next;  // IN's ray in IP's camera frame
    const double cos_parallax = r_next.dot(d_prev) / (cv::norm(r_next) * cv::norm(d_prev));
    if (cos_parallax > min_cos_parallax) continue;
    // Depths (l_next, l_prev) minimising |l_next r_next + t - l_prev d_prev|^2.
    const double a = r_next.dot(r_next), b = -r_next.dot(d_prev), d = d_prev.dot(d_prev);
    const double det = a * d - b * b;
    if (std::abs(det) < 1e-12) continue;
    const double g0 = -r_next.dot(t), g1 = d_prev.dot(t);
    const double l_next = (d * g0 - b * g1) / det;
    const double l_prev = (a * g1 - b * g0) / det;
    if (l_next <= kMinDepth || l_prev <= kMinDepth) continue;
    const cv::Vec3d X = l_next * d_next;
    // IN is the origin of its own frame (identity pose); behind either camera: infinite error.
    if (reprojection_error(PlanarPose{}, X, m.next_norm) > max_err ||
        reprojection_error(prev, X, m.other_norm) > max_err) {
      continue;
    }
    model.point_by_corner[m.corner] = X;
  }
  if (static_cast<int>(model.point_by_corner.size()) < options.min_points) return std::nullopt;
  return model;
}

std::optional<PlanarFix> planar_resection(const std::vector<cv::Vec3d>& X_next,
                                          const std::vector<cv::Point2d>& x_cur, double focal_px,
                                          const SegmentPoseOptions& options,
                                          const PosePrior* prior) {
  check_inputs(focal_px, options, "planar_resection");
  if (X_next.size() != x_cur.size()) {
    throw std::invalid_argument("planar_resection: " + std::to_string(X_next.size()) +
                                " points but " + std::to_string(x_cur.size()) + " observations");
  }
  if (prior && !(prior->sigma_x > 0.0 && prior->sigma_y > 0.0 && prior->sigma_yaw_rad > 0.0 &&
                 prior->gate_chi2 > 0.0)) {
    throw std::invalid_argument("planar_resection: the prior's sigmas and gate must be > 0");
  }
  const int n = static_cast<int>(X_next.size());
  if (n < options.min_points) return std::nullopt;
  const double thr = options.max_reprojection_px / focal_px;
  // Inliers among `subset` (indices into the points) and the MSAC cost over it.
  auto inliers_of = [&](const PlanarPose& pose, const std::vector<int>& subset, double* cost) {
    std::vector<int> in;
    double sum = 0.0;
    for (const int i : subset) {
      const double e = reprojection_error(pose, X_next[i], x_cur[i]);
      if (e < thr) {
        in.push_back(i);
        sum += e * e;
      } else {
        sum += thr * thr;
      }
    }
    if (cost) *cost = sum;
    return in;
  };
  struct Structure {
    PlanarFix fix;
    std::vector<int> inliers;
  };
  // One rigid structure among `subset`: RANSAC (MSAC cost) over 2-point samples with a fixed
  // seed (the result depends on the inputs only), then Gauss-Newton on its inliers.
  auto fit = [&](const std::vector<int>& subset) -> std::optional<Structure> {
    const int m = static_cast<int>(subset.size());
    if (m < std::max(2, options.min_points)) return std::nullopt;
    std::mt19937 rng(0x5e9);
    std::optional<PlanarPose> best;
    double best_cost = std::numeric_limits<double>::infinity();
    for (int it = 0; it < options.ransac_iterations; ++it) {
      const int i = static_cast<int>(rng() % static_cast<unsigned>(m));
      int j = static_cast<int>(rng() % static_cast<unsigned>(m - 1));
      if (j >= i) ++j;
      const auto pose = linear_resection(X_next, x_cur, {subset[i], subset[j]});
      if (!pose) continue;
      double cost = 0.0;
      inliers_of(*pose, subset, &cost);
      if (cost < best_cost) {
        best_cost = cost;
        best = pose;
      }
    }
    if (!best) return std::nullopt;
    PlanarPose pose = *best;
    std::vector<int> in = inliers_of(pose, subset, nullptr);
    for (int it = 0; it < options.gauss_newton_iterations; ++it) {
      if (static_cast<int>(in.size()) < options.min_points) return std::nullopt;
      if (!gauss_newton_step(X_next, x_cur, in, pose)) return std::nullopt;
      in = inliers_of(pose, subset, nullptr);
    }
    if (static_cast<int>(in.size()) < options.min_points) return std::nullopt;
    double sum_sq = 0.0;
    for (const int i : in) {
      const double e = reprojection_error(pose, X_next[i], x_cur[i]);
      sum_sq += e * e;
    }
    Structure s;
    s.fix.pose = pose;
    s.fix.inliers = static_cast<int>(in.size());
    s.fix.rms_px = focal_px * std::sqrt(sum_sq / static_cast<double>(in.size()));
    s.inliers = std::move(in);
    return s;
  };

  std::vector<int> all(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) all[static_cast<size_t>(i)] = i;
  auto first = fit(all);
  if (!first || !prior) return first ? std::optional<PlanarFix>(first->fix) : std::nullopt;

  // Sequential RANSAC: each structure's inliers leave the pool, the next is sought in the rest.
  std::vector<Structure> structures{std::move(*first)};
  std::vector<bool> taken(static_cast<size_t>(n), false);
  for (const int i : structures.front().inliers) taken[static_cast<size_t>(i)] = true;
  while (static_cast<int>(structures.size()) < kMaxStructures) {
    std::vector<int> rest;
    for (int i = 0; i < n; ++i) {
      if (!taken[static_cast<size_t>(i)]) rest.push_back(i);
    }
    auto next = fit(rest);
    if (!next) break;
    for (const int i : next->inliers) taken[static_cast<size_t>(i)] = true;
    structures.push_back(std::move(*next));
  }
  auto d2_of = [&](const PlanarPose& p) {
    const double dx = (p.x_m - prior->pose.x_m) / prior->sigma_x;
    const double dy = (p.y_m - prior->pose.y_m) / prior->sigma_y;
    const double dyaw = std::remainder(p.yaw_rad - prior->pose.yaw_rad, 2.0 * std::numbers::pi) /
                        prior->sigma_yaw_rad;
    return dx * dx + dy * dy + dyaw * dyaw;
  };
  const Structure* chosen = nullptr;
  for (const Structure& s : structures) {
    if (d2_of(s.fix.pose) > prior->gate_chi2) continue;
    if (!chosen || s.fix.inliers > chosen->fix.inliers) chosen = &s;
  }
  PlanarFix fix = chosen ? chosen->fix : structures.front().fix;
  fix.structures = static_cast<int>(structures.size());
  fix.prior_d2 = d2_of(fix.pose);
  fix.within_prior = chosen != nullptr;
  return fix;
}

std::optional<PlanarFix> locate_in_segment(const SegmentModel& model,
                                           const std::vector<CornerObservation>& matches,
                                           double focal_px, const SegmentPoseOptions& options,
                                           const PosePrior* prior) {
  std::vector<cv::Vec3d> X;
  std::vector<cv::Point2d> x;
  for (const CornerObservation& m : matches) {
    const auto it = model.point_by_corner.find(m.corner);
    if (it == model.point_by_corner.end()) continue;
    X.push_back(it->second);
    x.push_back(m.other_norm);
  }
  return planar_resection(X, x, focal_px, options, prior);
}

}  // namespace pepper::core::control
