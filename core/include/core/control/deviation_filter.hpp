#pragma once
// Filter for the VNHV deviation (lateral offset y, heading theta w.r.t. the segment IP -> IN;
// vnhv_law.hpp): a two-state extended Kalman filter.
//  - predict: the unicycle with the robot's own last command (v, omega) over the frame interval,
//    y += v sin(theta + omega dt / 2) dt, theta += omega dt; commands are not the true motion,
//    the process noise (per second) covers the difference;
//  - correct: with a measured deviation (segment_pose.hpp), gated on its normalised innovation
//    (chi-square, 2 dof). A filter that keeps rejecting is more likely wrong than the
//    measurements: after max_rejections consecutive rejections it restarts on the measurement.
//  - estimate: nullopt before the first measurement and when no measurement was accepted for
//    longer than max_prediction_s (the caller then uses another law).
// Time is the frames' t_ns (deterministic; no wall clock). Not thread-safe: one per navigator.

#include <cstdint>
#include <opencv2/core/matx.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/control/planar_pose.hpp"

namespace pepper::core::control {

struct DeviationFilterOptions {
  double measurement_sigma_m = 0.05;    ///< lateral measurement noise, m, > 0
  double measurement_sigma_rad = 0.05;  ///< heading measurement noise, rad, > 0
  double process_sigma_m = 0.02;        ///< lateral drift of the prediction, m / sqrt(s), > 0
  double process_sigma_rad = 0.03;      ///< heading drift of the prediction, rad / sqrt(s), > 0
  double gate_chi2 = 13.8;              ///< innovation gate, chi-square 2 dof (99.9 %), > 0
  int max_rejections = 5;               ///< consecutive rejections before a restart, >= 1
  double max_prediction_s = 1.0;  ///< prediction-only validity (frame time), s, >= 0
  std::vector<std::string> validate() const;
};

class DeviationFilter {
 public:
  enum class Correction { kStarted, kAccepted, kRejected, kRestarted };

  /// Throws std::invalid_argument for invalid options.
  explicit DeviationFilter(const DeviationFilterOptions& options = {});

  /// Forget everything (new segment).
  void reset();
  /// Advance the state to t_ns with the command applied since the last call (no-op before the
  /// first measurement). Throws std::invalid_argument when t_ns goes back or inputs are not
  /// finite.
  /// With a curved reference (curvature_1_m, > 0 left) the path's own turn is subtracted:
  /// theta' = omega - kappa v cos(theta) / (1 - kappa y) (1 - kappa y clamped at 0.1).
  void predict(double v_m_s, double omega_rad_s, int64_t t_ns, double curvature_1_m = 0.0);
  /// Fuse a measurement taken at t_ns (call predict(.., t_ns) first once started). weight in
  /// (0, 1]: the measurement's noise variance is divided by it (a robust weight from elsewhere).
  Correction correct(const SegmentDeviation& measured, int64_t t_ns, double weight = 1.0);
  /// The current estimate at t_ns (see file comment for nullopt).
  std::optional<SegmentDeviation> estimate(int64_t t_ns) const;

 private:
  void start(const SegmentDeviation& measured, int64_t t_ns, double weight);

  DeviationFilterOptions options_;
  bool started_ = false;
  double y_m_ = 0.0, theta_rad_ = 0.0;
  cv::Matx22d P_ = cv::Matx22d::zeros();  ///< covariance of (y, theta)
  int64_t t_ns_ = 0;
  int64_t last_accepted_t_ns_ = 0;
  int rejections_ = 0;
};

}  // namespace pepper::core::control
