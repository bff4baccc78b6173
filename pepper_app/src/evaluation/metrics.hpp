#pragma once
// Path-following metrics of the closed-loop evaluation (docs/evaluation.md): projection of a
// position onto the taught path (a polyline of ground-truth base positions), signed lateral
// deviation, RMS / max over the "converged" part of a run, the rate of change of omega, key
// images per metre and percentiles of per-frame times.
//
// Frames and units (docs/conventions.md): positions in the world frame, metres; the lateral
// deviation is > 0 when the point is to the LEFT of the path seen along its direction of travel;
// arc length `s_m` runs from the path's first point. Times in seconds, rates in rad/s^2.
// Pure functions and value types; thread-safe. A polyline with fewer than 2 distinct points
// throws std::invalid_argument (broken contract); empty sample sets give NaN statistics.

#include <Eigen/Core>
#include <span>
#include <vector>

namespace pepper::app::evaluation {

/// Projection of a point onto a polyline.
struct PathProjection {
  double s_m = 0.0;          ///< arc length of the foot point (< 0 before the start, > length
                             ///< past the end: the end pieces are extended as lines)
  double lateral_m = 0.0;    ///< signed distance, > 0 left of the direction of travel
  double distance_m = 0.0;   ///< |lateral_m|
  Eigen::Vector2d foot_m = Eigen::Vector2d::Zero();
};

class Polyline {
 public:
  /// Consecutive duplicate points (closer than 1e-9 m) are dropped. Throws
  /// std::invalid_argument when fewer than 2 distinct points remain.
  explicit Polyline(std::vector<Eigen::Vector2d> points_m);

  double length_m() const { return cum_m_.back(); }
  const std::vector<Eigen::Vector2d>& points() const { return points_; }
  /// Point at arc length s (clamped to [0, length]).
  Eigen::Vector2d at(double s_m) const;

  /// Nearest point over the whole polyline (ties: smallest s).
  PathProjection project(const Eigen::Vector2d& p_m) const;
  /// Nearest point among the pieces that overlap the arc-length window [s_lo_m, s_hi_m]
  /// (used to follow a run along a path that comes back near itself, e.g. a loop tour).
  PathProjection project_in_window(const Eigen::Vector2d& p_m, double s_lo_m,
                                   double s_hi_m) const;

 private:
  PathProjection project_on_piece(const Eigen::Vector2d& p_m, size_t i) const;
  std::vector<Eigen::Vector2d> points_;
  std::vector<double> cum_m_;  ///< arc length at each vertex
};

/// Follows a moving point along a polyline: the first projection searches s in
/// [0, initial_search_m], later ones a window [s - back_m, s + ahead_m] around the last foot, so
/// that a loop tour's end is not mistaken for its start.
class PathTracker {
 public:
  PathTracker(const Polyline& path, double initial_search_m, double back_m = 0.5,
              double ahead_m = 1.5);
  PathProjection update(const Eigen::Vector2d& p_m);

 private:
  const Polyline& path_;
  double initial_search_m_;
  double back_m_;
  double ahead_m_;
  bool started_ = false;
  double s_m_ = 0.0;
};

/// Root mean square; NaN when empty.
double rms(std::span<const double> values);
/// Largest |value|; NaN when empty.
double max_abs(std::span<const double> values);
/// q-quantile (q in [0, 1]) by linear interpolation between order statistics; NaN when empty.
double percentile(std::vector<double> values, double q);

/// RMS of the finite-difference rate (v_k - v_{k-1}) / (t_k - t_{k-1}) over consecutive samples
/// (pairs with a non-positive interval are skipped); NaN with fewer than 2 samples.
/// For omega in rad/s and t in s the result is in rad/s^2.
double rate_rms(std::span<const double> values, std::span<const double> t_s);

/// Key images per metre of taught path; NaN when the length is not positive.
double key_images_per_m(int key_images, double path_length_m);

/// Lateral deviation statistics over the "converged" part of a run: the samples from the first
/// one whose travelled distance is at least skip_m AND at or after which |lateral| has fallen
/// below converged_below_m once (converged_below_m <= 0: the distance rule alone).
struct DeviationStats {
  double rms_m = 0.0;             ///< NaN when no sample qualifies
  double max_m = 0.0;             ///< max |lateral|, NaN when no sample qualifies
  int samples = 0;
  double converged_from_m = -1;   ///< travelled distance where the converged part starts (-1: never)
  double first_under_5cm_m = -1;  ///< travelled distance where |lateral| first fell < 5 cm (-1: never)
};

/// travelled_m and lateral_m are per-sample series of equal length (throws otherwise).
DeviationStats lateral_stats(std::span<const double> travelled_m, std::span<const double> lateral_m,
                             double skip_m, double converged_below_m = 0.0);

}  // namespace pepper::app::evaluation
