#include "evaluation/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace pepper::app::evaluation {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}
}  // namespace

Polyline::Polyline(std::vector<Eigen::Vector2d> points_m) {
  for (const auto& p : points_m) {
    if (!p.allFinite()) throw std::invalid_argument("Polyline: non-finite point");
    if (points_.empty() || (p - points_.back()).norm() > 1e-9) points_.push_back(p);
  }
  if (points_.size() < 2) {
    throw std::invalid_argument("Polyline: needs at least 2 distinct points, got " +
                                std::to_string(points_.size()));
  }
  cum_m_.assign(points_.size(), 0.0);
  for (size_t i = 1; i < points_.size(); ++i) {
    cum_m_[i] = cum_m_[i - 1] + (points_[i] - points_[i - 1]).norm();
  }
}

Eigen::Vector2d Polyline::at(double s_m) const {
  s_m = std::clamp(s_m, 0.0, length_m());
  const auto it = std::upper_bound(cum_m_.begin(), cum_m_.end(), s_m);
  const size_t i = std::min<size_t>(std::max<ptrdiff_t>(it - cum_m_.begin(), 1), points_.size() - 1);
  const double len = cum_m_[i] - cum_m_[i - 1];
  const double f = len > 0 ? (s_m - cum_m_[i - 1]) / len : 0.0;
  return points_[i - 1] + f * (points_[i] - points_[i - 1]);
}

PathProjection Polyline::project_on_piece(const Eigen::Vector2d& p, size_t i) const {
  const Eigen::Vector2d a = points_[i], b = points_[i + 1];
  const Eigen::Vector2d d = b - a;
  const double len = d.norm();
  // The first and last pieces extend beyond the path's ends, so that a point before the start
  // or past the end gets its perpendicular (lateral) distance, not its distance to the end
  // point (that is an along-track error); s then runs below 0 or above the length.
  const double lo = i == 0 ? -std::numeric_limits<double>::infinity() : 0.0;
  const double hi = i + 2 == points_.size() ? std::numeric_limits<double>::infinity() : 1.0;
  const double f = std::clamp((p - a).dot(d) / (len * len), lo, hi);
  PathProjection out;
  out.foot_m = a + f * d;
  out.s_m = cum_m_[i] + f * len;
  out.distance_m = (p - out.foot_m).norm();
  // Side from the piece's direction.
  const double side = cross2(d, p - a) >= 0.0 ? 1.0 : -1.0;
  out.lateral_m = side * out.distance_m;
  return out;
}

PathProjection Polyline::project(const Eigen::Vector2d& p_m) const {
  return project_in_window(p_m, -std::numeric_limits<double>::infinity(),
                           std::numeric_limits<double>::infinity());
}

PathProjection Polyline::project_in_window(const Eigen::Vector2d& p_m, double s_lo_m,
                                           double s_hi_m) const {
  PathProjection best;
  best.distance_m = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < points_.size(); ++i) {
    if (cum_m_[i + 1] < s_lo_m || cum_m_[i] > s_hi_m) continue;
    const PathProjection c = project_on_piece(p_m, i);
    if (c.distance_m < best.distance_m - 1e-12) best = c;
  }
  if (!std::isfinite(best.distance_m)) return project(p_m);  // empty window: whole path
  return best;
}

PathTracker::PathTracker(const Polyline& path, double initial_search_m, double back_m,
                         double ahead_m)
    : path_(path), initial_search_m_(initial_search_m), back_m_(back_m), ahead_m_(ahead_m) {}

PathProjection PathTracker::update(const Eigen::Vector2d& p_m) {
  const PathProjection pr = started_
                                ? path_.project_in_window(p_m, s_m_ - back_m_, s_m_ + ahead_m_)
                                : path_.project_in_window(p_m, 0.0, initial_search_m_);
  started_ = true;
  s_m_ = pr.s_m;
  return pr;
}

double rms(std::span<const double> values) {
  if (values.empty()) return kNaN;
  double sum = 0.0;
  for (double v : values) sum += v * v;
  return std::sqrt(sum / static_cast<double>(values.size()));
}

double max_abs(std::span<const double> values) {
  if (values.empty()) return kNaN;
  double m = 0.0;
  for (double v : values) m = std::max(m, std::abs(v));
  return m;
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return kNaN;
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (pos - static_cast<double>(lo)) * (values[hi] - values[lo]);
}

double rate_rms(std::span<const double> values, std::span<const double> t_s) {
  if (values.size() != t_s.size()) throw std::invalid_argument("rate_rms: size mismatch");
  std::vector<double> rates;
  for (size_t i = 1; i < values.size(); ++i) {
    const double dt = t_s[i] - t_s[i - 1];
    if (dt > 0.0) rates.push_back((values[i] - values[i - 1]) / dt);
  }
  return rms(rates);
}

double key_images_per_m(int key_images, double path_length_m) {
  return path_length_m > 0.0 ? key_images / path_length_m : kNaN;
}

DeviationStats lateral_stats(std::span<const double> travelled_m, std::span<const double> lateral_m,
                             double skip_m, double converged_below_m) {
  if (travelled_m.size() != lateral_m.size()) {
    throw std::invalid_argument("lateral_stats: travelled_m and lateral_m differ in size");
  }
  DeviationStats out;
  std::vector<double> kept;
  bool under = converged_below_m <= 0.0;
  for (size_t i = 0; i < lateral_m.size(); ++i) {
    if (out.first_under_5cm_m < 0.0 && std::abs(lateral_m[i]) < 0.05) {
      out.first_under_5cm_m = travelled_m[i];
    }
    if (!under && std::abs(lateral_m[i]) < converged_below_m) under = true;
    if (travelled_m[i] >= skip_m && under) {
      if (out.converged_from_m < 0.0) out.converged_from_m = travelled_m[i];
      kept.push_back(lateral_m[i]);
    }
  }
  out.samples = static_cast<int>(kept.size());
  out.rms_m = rms(kept);
  out.max_m = max_abs(kept);
  return out;
}

}  // namespace pepper::app::evaluation
