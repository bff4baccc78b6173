// Planar rigid transforms and their robust fit (see planar_rigid.hpp).
#include "core/ceiling/planar_rigid.hpp"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace pepper::core::ceiling {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

cv::Point2d PlanarPose::apply(const cv::Point2d& p_b) const {
  const double c = std::cos(theta_rad), s = std::sin(theta_rad);
  return {c * p_b.x - s * p_b.y + x_m, s * p_b.x + c * p_b.y + y_m};
}

PlanarPose PlanarPose::inverse() const {
  const double c = std::cos(theta_rad), s = std::sin(theta_rad);
  return {-(c * x_m + s * y_m), -(-s * x_m + c * y_m), -theta_rad};
}

PlanarPose PlanarPose::operator*(const PlanarPose& T_b_c) const {
  const cv::Point2d t = apply({T_b_c.x_m, T_b_c.y_m});
  return {t.x, t.y, wrap_angle_rad(theta_rad + T_b_c.theta_rad)};
}

double wrap_angle_rad(double angle_rad) {
  double a = std::remainder(angle_rad, 2.0 * kPi);
  if (a <= -kPi) a += 2.0 * kPi;
  return a;
}

PlanarPose fit_rigid(const std::vector<cv::Point2d>& src, const std::vector<cv::Point2d>& dst) {
  if (src.size() != dst.size())
    throw std::invalid_argument("fit_rigid: src and dst must have the same number of points");
  if (src.size() < 2) throw std::invalid_argument("fit_rigid: needs at least 2 point pairs");
  cv::Point2d cs(0, 0), cd(0, 0);
  for (size_t i = 0; i < src.size(); ++i) {
    cs += src[i];
    cd += dst[i];
  }
  cs *= 1.0 / static_cast<double>(src.size());
  cd *= 1.0 / static_cast<double>(src.size());
  // The rotation maximising sum dst' . R src' is atan2(sum of cross, sum of dot) of the centred
  // points (2D Procrustes without scale).
  double dot = 0.0, cross = 0.0;
  for (size_t i = 0; i < src.size(); ++i) {
    const cv::Point2d a = src[i] - cs, b = dst[i] - cd;
    dot += a.x * b.x + a.y * b.y;
    cross += a.x * b.y - a.y * b.x;
  }
  PlanarPose T;
  T.theta_rad = std::atan2(cross, dot);
  const cv::Point2d rc = PlanarPose{0, 0, T.theta_rad}.apply(cs);
  T.x_m = cd.x - rc.x;
  T.y_m = cd.y - rc.y;
  return T;
}

void RigidRansacOptions::check() const {
  if (!(std::isfinite(inlier_threshold_m) && inlier_threshold_m > 0.0))
    throw std::invalid_argument("ransac_rigid: inlier_threshold_m must be finite and > 0");
  if (min_inliers < 2) throw std::invalid_argument("ransac_rigid: min_inliers must be >= 2");
  if (iterations <= 0) throw std::invalid_argument("ransac_rigid: iterations must be > 0");
}

namespace {

int count_inliers(const PlanarPose& T, const std::vector<cv::Point2d>& src,
                  const std::vector<cv::Point2d>& dst, double threshold2,
                  std::vector<uint8_t>* mask) {
  int n = 0;
  if (mask) mask->assign(src.size(), 0);
  for (size_t i = 0; i < src.size(); ++i) {
    const cv::Point2d r = T.apply(src[i]) - dst[i];
    if (r.x * r.x + r.y * r.y <= threshold2) {
      ++n;
      if (mask) (*mask)[i] = 1;
    }
  }
  return n;
}

}  // namespace

RigidFit ransac_rigid(const std::vector<cv::Point2d>& src, const std::vector<cv::Point2d>& dst,
                      const RigidRansacOptions& options) {
  options.check();
  if (src.size() != dst.size())
    throw std::invalid_argument("ransac_rigid: src and dst must have the same number of points");
  RigidFit fit;
  const int n = static_cast<int>(src.size());
  if (n < options.min_inliers) return fit;
  const double t2 = options.inlier_threshold_m * options.inlier_threshold_m;
  std::mt19937 rng(options.seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  PlanarPose best;
  int best_count = -1;
  for (int it = 0; it < options.iterations; ++it) {
    const int i = pick(rng);
    int j = pick(rng);
    if (i == j) j = (j + 1) % n;
    // Two pairs whose lengths disagree cannot be related by a rigid motion: skip the count.
    const double ls = cv::norm(src[i] - src[j]), ld = cv::norm(dst[i] - dst[j]);
    if (ls < 1e-6 || std::abs(ls - ld) > 2.0 * options.inlier_threshold_m) continue;
    const PlanarPose T = fit_rigid({src[i], src[j]}, {dst[i], dst[j]});
    const int count = count_inliers(T, src, dst, t2, nullptr);
    if (count > best_count) {
      best_count = count;
      best = T;
    }
  }
  if (best_count < options.min_inliers) return fit;
  // Least squares on the consensus, re-scored, while the consensus grows.
  std::vector<uint8_t> mask;
  int count = count_inliers(best, src, dst, t2, &mask);
  for (int round = 0; round < 3; ++round) {
    std::vector<cv::Point2d> s, d;
    for (int k = 0; k < n; ++k)
      if (mask[static_cast<size_t>(k)]) {
        s.push_back(src[static_cast<size_t>(k)]);
        d.push_back(dst[static_cast<size_t>(k)]);
      }
    const PlanarPose refined = fit_rigid(s, d);
    std::vector<uint8_t> refined_mask;
    const int refined_count = count_inliers(refined, src, dst, t2, &refined_mask);
    if (refined_count < count) break;
    best = refined;
    const bool grew = refined_count > count;
    mask = std::move(refined_mask);
    count = refined_count;
    if (!grew) break;
  }
  if (count < options.min_inliers) return fit;
  // The reported transform is the least-squares one of the final consensus (the loop may have
  // stopped on a hypothesis whose refinement lost inliers).
  std::vector<cv::Point2d> s, d;
  for (int k = 0; k < n; ++k)
    if (mask[static_cast<size_t>(k)]) {
      s.push_back(src[static_cast<size_t>(k)]);
      d.push_back(dst[static_cast<size_t>(k)]);
    }
  best = fit_rigid(s, d);
  fit.found = true;
  fit.T_dst_src = best;
  fit.inlier = std::move(mask);
  fit.inliers = count;
  double sum2 = 0.0;
  for (int k = 0; k < n; ++k)
    if (fit.inlier[static_cast<size_t>(k)]) {
      const cv::Point2d r = best.apply(src[static_cast<size_t>(k)]) - dst[static_cast<size_t>(k)];
      sum2 += r.x * r.x + r.y * r.y;
    }
  fit.rms_m = std::sqrt(sum2 / count);
  return fit;
}

}  // namespace pepper::core::ceiling
