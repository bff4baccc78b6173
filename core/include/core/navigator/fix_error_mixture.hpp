#pragma once
// The odometry estimate's update by a segment's VNHV fixes, when a segment's fixes may come from
// the room or from an object moved since teaching.
//
// Why: every fix of a segment comes from one reconstruction (IN's triangulated points) and from
// one rigid structure in it, so its error is mostly shared by the segment's fixes
// (shared_fix_error.hpp). That shared error has two very different sizes: where the structure is
// the room, a few millimetres (measured: room_corridor_room, VGA, no disturbance, 36 straight
// segments: lateral RMS 0.44 cm, max 1.45 cm; heading RMS 0.0035 rad); where it is a moved shelf,
// tens of centimetres and degrees (moved furniture: 10-35 cm, 0.03-0.13 rad). One Gaussian
// cannot be both: a small sigma follows a moved shelf all the way (each fix is close to a
// prediction that followed the previous ones), a large one under-uses the room's good fixes
// (gen_room_1, light x0.7: a drifted estimate kept half its error into a turn; docs/method/
// navigator.md "Fixes from the room or from a moved object").
//
// So two hypotheses per segment, each the shared-error model with its own sigma: "usual" (the
// room) and "moved" (a moved object). Each fix updates both; their probabilities follow the
// likelihood of the segment's fixes so far under each (a Gaussian-sum filter over the
// segment: each hypothesis keeps its own estimate, as an offset from the mixture's mean); the
// estimate is the mixture's mean and its variance the mixture's. (A first version collapsed the
// two into one estimate after every fix; then each hypothesis's shared-error estimate no longer
// matched the estimate it was made for, and after a placement "moved" won on fixes that agreed
// with the estimate: DeadReckoning.TelemetryShowsThePredictionTheFixesAreWeighedAgainst.) A few fixes that keep reading far from the odometry make "moved" likely, and then
// they hardly move the estimate; fixes near it keep "usual" and are used as before.
//
// Axes: 0 along the robot, 1 across it, 2 heading (m, m, rad). A source that measures only some
// axes (the lines' heading, the floor lines' lateral position) leaves the others unmodelled: NaN
// sigmas there. Pure; not thread-safe.

#include <array>
#include <cmath>

#include "core/navigator/shared_fix_error.hpp"

namespace pepper::core::navigator {

using Axes3 = std::array<double, 3>;

/// Per axis, > 0; all three NaN on an axis the source does not measure (not modelled).
struct FixErrorMixtureOptions {
  Axes3 usual_sigma{0.03, 0.01, 0.005};  ///< shared error when the structure is the room
  Axes3 moved_sigma{0.5, 0.3, 0.1};      ///< shared error when it is a moved object
  Axes3 noise_sigma{0.05, 0.01, 0.003};  ///< each fix's own white noise
  double moved_prior = 0.1;              ///< probability of "moved" for a new segment, (0, 1)

  /// Whether axis `axis` is modelled (its sigmas are not NaN).
  bool models(int axis) const { return !std::isnan(usual_sigma[static_cast<size_t>(axis)]); }
};

class FixErrorMixture {
 public:
  /// A new segment model (or a placed estimate), from the estimate's variances now. Throws
  /// std::invalid_argument for sigmas <= 0 (or NaN on some but not all three of an axis, or on
  /// every axis), a prior outside (0, 1) or a variance <= 0.
  void begin(const FixErrorMixtureOptions& options, const Axes3& est_var);
  /// One fix: the innovation (fix minus the estimate, robot axes; NaN on an axis the fix does
  /// not measure, and always on the axes not modelled) and the fix's weight in (0, 1] (divides
  /// the noise variance). Each hypothesis updates its own estimate; returns the move of the
  /// mixture's mean (on an unmeasured axis only where the hypotheses' estimates differ and their
  /// probabilities change), by which the caller moves the estimate. Throws
  /// std::invalid_argument for an infinite innovation, one on an axis not modelled, or a weight
  /// outside (0, 1].
  Axes3 update(const Axes3& innovation, double weight);
  /// The mixture's variance per axis (the estimate's, for the caller's sigmas). This and
  /// expected(), expected_var() are NaN on the axes not modelled.
  Axes3 variance() const;
  /// Whether axis `axis` is modelled (FixErrorMixtureOptions::models).
  bool models(int axis) const { return options_.models(axis); }
  /// The odometry grew axis `axis`'s sigma by `d_sigma` (>= 0): every hypothesis's too. Axes
  /// below (grow, rescale) must be modelled: std::invalid_argument otherwise.
  void grow(int axis, double d_sigma);
  /// Another source corrected the estimate's axis `axis` by a Kalman update that took its
  /// variance from `before` to `after`: every hypothesis's variance scales alike.
  void rescale(int axis, double before, double after);
  /// Probability that this segment's structure is the room, given its fixes so far.
  double usual_probability() const;
  /// Where the room's next fix is expected (relative to the estimate) and that expectation's
  /// variance, per axis: the "usual" hypothesis's. This is the resection's prior, which picks
  /// the room among the structures in view (control::PosePrior); a moved object's structure is
  /// what it must not pick, so its hypothesis does not widen the gate.
  Axes3 expected() const;
  Axes3 expected_var() const;

 private:
  struct Hypothesis {
    std::array<SharedFixError, 3> error;
    Axes3 offset{};  ///< this hypothesis's estimate minus the mixture's mean
    Axes3 var{};     ///< this hypothesis's estimate variance
  };
  FixErrorMixtureOptions options_;
  Hypothesis usual_, moved_;
  double log_odds_moved_ = 0.0;  ///< log P(moved) / P(usual)
};

}  // namespace pepper::core::navigator
