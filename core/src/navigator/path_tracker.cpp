#include "core/navigator/path_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pepper::core::navigator {
namespace {

double wrap(double a) {
  a = std::remainder(a, 2.0 * M_PI);
  return a <= -M_PI ? a + 2.0 * M_PI : a;
}

// Heading changes below this on a piece shorter than kInPlaceLengthM: two key images at one pose
// (nothing to drive).
constexpr double kNoTurnRad = 0.02;

}  // namespace

OdometryPose compose(const OdometryPose& a, const OdometryPose& b) {
  const double c = std::cos(a.yaw_rad), s = std::sin(a.yaw_rad);
  return {a.x_m + c * b.x_m - s * b.y_m, a.y_m + s * b.x_m + c * b.y_m,
          wrap(a.yaw_rad + b.yaw_rad)};
}

OdometryPose between(const OdometryPose& a, const OdometryPose& b) {
  const double c = std::cos(a.yaw_rad), s = std::sin(a.yaw_rad);
  const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m;
  return {c * dx + s * dy, -s * dx + c * dy, wrap(b.yaw_rad - a.yaw_rad)};
}

TaughtPathTracker::TaughtPathTracker(const std::vector<std::optional<OdometryPose>>& taught) {
  usable_ = taught.size() >= 2;
  for (const auto& p : taught) {
    if (!p || !std::isfinite(p->x_m) || !std::isfinite(p->y_m) || !std::isfinite(p->yaw_rad)) {
      usable_ = false;
      break;
    }
    taught_.push_back(*p);
  }
  if (!usable_) taught_.clear();
  length_to_m_.assign(taught_.size(), 0.0);
  for (size_t i = 1; i < taught_.size(); ++i) {
    const double piece_m = std::hypot(taught_[i].x_m - taught_[i - 1].x_m,
                                      taught_[i].y_m - taught_[i - 1].y_m);
    const bool spot = piece_in_place(static_cast<int>(i) - 1);
    length_to_m_[i] = length_to_m_[i - 1] + (spot ? 0.0 : piece_m);
  }
}

void TaughtPathTracker::reset() {
  X_.reset();
  last_odom_.reset();
  piece_ = 0;
  last_s_m_.reset();
  moved_since_m_ = 0.0;
}

void TaughtPathTracker::set(const OdometryPose& X_teach_base, const OdometryPose& odom,
                            int from_piece) {
  X_ = X_teach_base;
  last_odom_ = odom;
  piece_ = std::clamp(from_piece, 0, std::max(0, key_count() - 2));
  last_s_m_.reset();  // placed by vision: the next deviation may project anywhere ahead
  moved_since_m_ = 0.0;
}

void TaughtPathTracker::predict(const OdometryPose& odom) {
  if (X_ && last_odom_) {
    const OdometryPose step = between(*last_odom_, odom);
    X_ = compose(*X_, step);
    if (std::isfinite(step.x_m) && std::isfinite(step.y_m)) {
      moved_since_m_ += std::hypot(step.x_m, step.y_m);
    }
  }
  last_odom_ = odom;
}

std::pair<double, double> TaughtPathTracker::correct(const OdometryPose& X_fix) {
  if (!X_) {
    X_ = X_fix;
    return {0.0, 0.0};
  }
  const double dx = X_fix.x_m - X_->x_m, dy = X_fix.y_m - X_->y_m;
  const std::pair<double, double> error{std::hypot(dx, dy),
                                        std::abs(wrap(X_fix.yaw_rad - X_->yaw_rad))};
  moved_since_m_ += error.first;
  X_ = OdometryPose{X_fix.x_m, X_fix.y_m, wrap(X_fix.yaw_rad)};
  return error;
}

void TaughtPathTracker::shift(const OdometryPose& delta) {
  if (!X_) return;
  moved_since_m_ += std::hypot(delta.x_m, delta.y_m);
  X_ = compose(*X_, delta);
}

bool TaughtPathTracker::piece_short(int i) const {
  const OdometryPose& a = taught_[static_cast<size_t>(i)];
  const OdometryPose& b = taught_[static_cast<size_t>(i) + 1];
  return std::hypot(b.x_m - a.x_m, b.y_m - a.y_m) < kInPlaceLengthM;
}

bool TaughtPathTracker::piece_in_place(int i) const {
  if (!piece_short(i)) return false;
  const OdometryPose& a = taught_[static_cast<size_t>(i)];
  const OdometryPose& b = taught_[static_cast<size_t>(i) + 1];
  // A short piece of an arc (key images a few centimetres apart on a feature-poor curve) is a
  // chord, not a turn on the spot: its turning radius is that of the arc.
  const double turn = std::abs(wrap(b.yaw_rad - a.yaw_rad));
  return std::hypot(b.x_m - a.x_m, b.y_m - a.y_m) < kInPlaceMaxRadiusM * turn;
}

double TaughtPathTracker::fraction_on(int i) const {
  const OdometryPose& a = taught_[static_cast<size_t>(i)];
  const OdometryPose& b = taught_[static_cast<size_t>(i) + 1];
  if (piece_short(i)) {
    const double turn = wrap(b.yaw_rad - a.yaw_rad);
    if (std::abs(turn) < kNoTurnRad) return 1.0;  // two key images at one pose
    if (piece_in_place(i)) return wrap(X_->yaw_rad - a.yaw_rad) / turn;
  }
  const double ux = b.x_m - a.x_m, uy = b.y_m - a.y_m;
  return ((X_->x_m - a.x_m) * ux + (X_->y_m - a.y_m) * uy) / (ux * ux + uy * uy);
}

void TaughtPathTracker::advance_to(int piece) {
  piece_ = std::max(piece_, std::min(piece, std::max(0, key_count() - 2)));
  if (last_s_m_ && usable_) last_s_m_ = std::max(*last_s_m_, length_to_m_[piece_]);
}

std::optional<PathDeviation> TaughtPathTracker::deviation() {
  if (!usable_ || !X_) return std::nullopt;
  const int last_piece = key_count() - 2;
  double f = fraction_on(piece_);
  const double reach_m = last_s_m_ ? *last_s_m_ + moved_since_m_ + kAdvanceSlackM
                                   : std::numeric_limits<double>::infinity();
  while (f >= 1.0 && piece_ < last_piece && length_to_m_[piece_ + 1] <= reach_m) {
    ++piece_;
    f = fraction_on(piece_);
  }
  const double piece_m = length_to_m_[piece_ + 1] - length_to_m_[piece_];
  last_s_m_ = std::min(length_to_m_[piece_] + std::clamp(f, 0.0, 1.0) * piece_m, reach_m);
  moved_since_m_ = 0.0;
  const OdometryPose& a = taught_[static_cast<size_t>(piece_)];
  const OdometryPose& b = taught_[static_cast<size_t>(piece_) + 1];
  const double turn = wrap(b.yaw_rad - a.yaw_rad);
  PathDeviation d;
  d.piece = piece_;
  d.progress = piece_ + std::clamp(f, 0.0, 1.0);
  d.s_m = *last_s_m_;
  d.in_place = piece_in_place(piece_);
  if (d.in_place) {
    d.remaining_turn_rad = wrap(b.yaw_rad - X_->yaw_rad);
    d.heading_rad = wrap(X_->yaw_rad - (a.yaw_rad + std::clamp(f, 0.0, 1.0) * turn));
    return d;
  }
  const double length_m = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
  // Two key images at one pose (a teach that stood still): the piece has no direction of its
  // own; the taught heading gives it, and it has no curvature.
  const bool has_length = length_m >= kMinDirectionLengthM;
  const double ux = has_length ? (b.x_m - a.x_m) / length_m : std::cos(a.yaw_rad);
  const double uy = has_length ? (b.y_m - a.y_m) / length_m : std::sin(a.yaw_rad);
  d.lateral_m = ux * (X_->y_m - a.y_m) - uy * (X_->x_m - a.x_m);
  d.heading_rad = wrap(X_->yaw_rad - (a.yaw_rad + std::clamp(f, 0.0, 1.0) * turn));
  d.curvature_1_m = has_length ? turn / length_m : 0.0;
  return d;
}

}  // namespace pepper::core::navigator
