#pragma once
// One axis (along, across or heading) of the odometry estimate's update by VNHV fixes whose
// errors are shared within a segment.
//
// Why: every fix of a segment comes from one reconstruction of it (control/segment_pose.hpp:
// IN's triangulated points) and, where objects moved since teaching, from one rigid structure
// in them. Their errors are therefore mostly one error, not fifteen independent ones per second.
// An update that takes each fix as independent trusts a segment's fixes more with every frame,
// so a structure whose error grows slowly (a moved, turned shelf: the robot drives the taught
// path turned about it) is followed all the way: each fix is close to a prediction that followed
// the previous fixes. Measured in room_corridor_room with moved furniture (VGA, run 1;
// docs/method/navigator.md "Fixes from the room or from a moved object"): the fixes' heading
// drifted 0.07 rad from the truth over 1.2 m, about six times the odometry's own heading error
// over that distance, and every one of them was inside the gate. fix_error_mixture.hpp uses
// this model twice, for the room's shared error and for a moved object's.
//
// Model, per axis, with e the estimate's error and b the segment's shared fix error:
//   fix - estimate = e + b + n,  n white with variance R (divided by the fix's weight),
//   b ~ N(0, sigma_b^2) when the segment begins, constant over the segment.
// The state (e, b) is updated by the Kalman equations with e's variance P, b's variance B and
// their covariance C; odometry adds to P only. So the fixes of one segment together move the
// estimate at most as far as one measurement of variance sigma_b^2 would, and a new segment (a
// new reconstruction, another structure) brings new evidence.
//
// Units are the axis's (m or rad). Pure; not thread-safe.

namespace pepper::core::navigator {

class SharedFixError {
 public:
  /// A new segment model: its fixes' shared error is unknown, sigma_b (> 0) a priori.
  void begin(double sigma_b);
  /// One fix. est_var: the estimate's variance P (updated in place); innovation: fix minus
  /// estimate; noise_var: R, the fix's own white noise variance (> 0). Returns the correction
  /// to add to the estimate. Throws std::invalid_argument for a variance <= 0 or not finite.
  double update(double& est_var, double innovation, double noise_var);
  /// Another source (floor lines, the lines' heading) changed the estimate's variance from
  /// `before` to `after` by a Kalman update: the covariance with the shared error scales alike.
  void rescale(double before, double after);
  /// Where the next fix is expected, relative to the estimate, and that expectation's variance.
  double expected() const { return bias_; }
  /// est_var + B + 2 C + noise_var; never below noise_var (|C| <= sqrt(P B) keeps it there for
  /// any P the caller has not grown or shrunk without telling).
  double expected_var(double est_var, double noise_var) const;
  double bias() const { return bias_; }
  double bias_var() const { return bias_var_; }
  double cross_cov() const { return cross_cov_; }

 private:
  double bias_ = 0.0;
  double bias_var_ = 0.0;
  double cross_cov_ = 0.0;
};

}  // namespace pepper::core::navigator
