#pragma once
// Checking the configured ceiling height at teach against the wheel odometry (issue 24;
// docs/method/ceiling.md "Checking the ceiling height at teach").
//
// Why it can be checked: the canonical view places a ceiling point at h / rise times its ray's
// horizontal direction (canonical_view.hpp), h the ceiling's height above the optical centre as
// configured. Every horizontal offset the view measures is therefore h_configured / h_true times
// the true one, and so is the mosaic built from it: with k = h_configured / h_true the observed
// base-frame points are p' = k p + (1 - k) c (c = the optical centre on the base, the view's
// origin), and the chained poses put the OPTICAL CENTRE on a path that is exactly k times its
// true path (the base's own path is k times the truth plus (1 - k) (R_j - R_i) c, up to 1.4 cm
// for a half turn with Pepper's c = 7 cm and k = 0.9). The odometry measures the same path at
// its own scale (a few per cent off: wheel radius, slip). So
//   s = |chained displacement of the optical centre| / |odometry displacement of it| ~= k,
//   h_true above the camera ~= h_configured / s,
// up to the odometry's distance-scale error and the chain's own drift (both in the figures).
//
// Estimator: the taught frames are cut into consecutive windows of `window_m` of odometry travel
// of the base (the odometry's step lengths, so turns on the spot add nothing). A window is broken
// off (not used, the next starts after the break) at a frame without a pose or without odometry,
// at a re-localisation or a loop closure (the chained pose jumps there) and at a step of either
// pose longer than `max_step_m` (an odometry reset, a jump of the chain). A complete window whose
// optical-centre odometry chord is shorter than `min_chord_m` (mostly turning) is skipped. Each
// window gives the ratio r of the two chords (chords, not summed step lengths: the chain's
// per-frame jitter of a few millimetres would add up over a path). The ratios' median and their
// robust spread (1.4826 x the median absolute deviation, at least 0.5 % of the median) reject
// windows beyond `outlier_sigmas` spreads (a mis-posed stretch); s is the mean of the rest, its
// uncertainty their standard deviation / sqrt(n). Fewer than `min_windows` windows left: no
// estimate.
//
// The verdict `disagrees`: the estimated height above the camera differs from the configured one
// by more than `warn_relative` of it (the scale error of every distance in the mosaic) AND by
// more than `warn_sigmas` times its uncertainty. The floor covers what the window spread does
// not: the odometry's own scale error (the simulator's wheels read 1.5 % long)
// and the chain's (0.4-1.3 % long on renders). The check never changes the height: a teach
// under a wrong height is re-taught with the measured one.
//
// Units and frames: metres, radians; T_mosaic_base (mosaic_builder.hpp) and T_odom_base
// (core/odometry.hpp) are both base poses, in frames that differ by a rigid transform (only
// displacement lengths are compared). Errors: bad options or a configured height that is not
// > 0 throw std::invalid_argument naming the field; too little usable motion is a value (status).
// Pure, no state.

#include <opencv2/core/types.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/ceiling/mosaic_builder.hpp"
#include "core/ceiling/planar_rigid.hpp"
#include "core/odometry.hpp"

namespace pepper::core::ceiling {

struct HeightCheckOptions {
  /// Odometry travel of the base per window, > 0. Long enough that the chain's pose jitter
  /// (mm) is small against it, short enough for many windows on a tour of a few metres.
  double window_m = 0.75;
  /// A window whose optical centre moved less than this in a straight line (odometry) is skipped
  /// (turns), in (0, window_m].
  double min_chord_m = 0.5;
  /// A frame-to-frame step of the base longer than this, in the mosaic or the odometry, breaks
  /// the window (a jump: 0.25 m is 3.75 m/s at 15 Hz, Pepper drives at most 0.55 m/s), > 0.
  double max_step_m = 0.25;
  /// Windows beyond this many robust spreads from the median are rejected, > 0.
  double outlier_sigmas = 3.0;
  /// Fewer windows left after the rejection: no estimate, >= 2.
  int min_windows = 4;
  /// The verdict (see the header's comment): relative disagreement beyond this, >= 0 ...
  double warn_relative = 0.05;
  /// ... and beyond this many standard errors of the estimate, >= 0.
  double warn_sigmas = 3.0;

  /// Throws std::invalid_argument naming the first invalid field (as "height_check.<field>").
  void check() const;
};

/// One taught frame as the estimator sees it.
struct HeightCheckFrame {
  std::optional<PlanarPose> T_mosaic_base;  ///< nullopt: the builder found no pose
  std::optional<PlanarPose> T_odom_base;    ///< nullopt: the frame came without odometry
  bool jump = false;  ///< the chained pose may jump here (re-localised, closed a loop)
};

/// The frames of a teach: the builder's results and each frame's odometry (same length).
/// Throws std::invalid_argument when the lengths differ.
std::vector<HeightCheckFrame> height_check_frames(
    const std::vector<MosaicFrameResult>& results,
    const std::vector<std::optional<OdometryPose>>& odometry);

enum class HeightCheckStatus {
  kEstimated,
  kNoOdometry,     ///< no two consecutive frames with a pose and odometry
  kTooFewWindows,  ///< too little usable straight motion (short tour, turns, losses)
};
std::string to_string(HeightCheckStatus status);
/// Throws std::invalid_argument for an unknown name.
HeightCheckStatus height_check_status_from_string(const std::string& name);

struct HeightCheck {
  HeightCheckStatus status = HeightCheckStatus::kNoOdometry;
  double configured_height_m = 0.0;        ///< above the floor, as taught
  double configured_above_camera_m = 0.0;  ///< above the optical centre, as taught, > 0
  int windows = 0;                         ///< used for the estimate
  int windows_rejected = 0;                ///< complete windows rejected as outliers
  int windows_turning = 0;                 ///< complete windows skipped: chord < min_chord_m
  double odometry_m = 0.0;                 ///< odometry chords of the windows used, summed
  // The figures below are set when status == kEstimated (else 0).
  double scale_ratio = 0.0;         ///< s = chained / odometry displacement, mean of the windows
  double scale_ratio_spread = 0.0;  ///< standard deviation of the windows' ratios
  double scale_ratio_sigma = 0.0;   ///< standard error of s (spread / sqrt(windows))
  double estimated_above_camera_m = 0.0;  ///< configured_above_camera_m / s
  double estimated_height_m = 0.0;        ///< above the floor (the camera's height + the above)
  double estimated_sigma_m = 0.0;         ///< of both, from scale_ratio_sigma
  bool disagrees = false;                 ///< the verdict (HeightCheckOptions::warn_*)

  bool estimated() const { return status == HeightCheckStatus::kEstimated; }
  /// The scale error: estimated_above_camera_m / configured_above_camera_m - 1 = 1 / s - 1 (0
  /// without an estimate); > 0: the ceiling is higher than configured, the mosaic too short.
  double relative_error() const;
  /// Messages naming each invalid field; empty when valid.
  std::vector<std::string> validate() const;
};

/// Estimates the ceiling's height from `frames` (see the header's comment). `cam_in_base_m`: the
/// optical centre's horizontal offset from the base's rotation axis (observation.hpp);
/// `configured_height_m` / `configured_above_camera_m`: the teach's ceiling, above the floor and
/// above the optical centre (0 < above_camera <= height).
HeightCheck check_ceiling_height(const std::vector<HeightCheckFrame>& frames,
                                 const cv::Point2d& cam_in_base_m, double configured_height_m,
                                 double configured_above_camera_m,
                                 const HeightCheckOptions& options = {});

}  // namespace pepper::core::ceiling
