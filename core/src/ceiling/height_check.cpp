// Checking the configured ceiling height against the odometry (see height_check.hpp).
#include "core/ceiling/height_check.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pepper::core::ceiling {

namespace {

[[noreturn]] void bad(const std::string& field, double value, const std::string& range) {
  throw std::invalid_argument("height_check." + field + " = " + std::to_string(value) +
                              " must be " + range);
}

double median(std::vector<double> v) {
  const size_t n = v.size();
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n / 2), v.end());
  const double hi = v[n / 2];
  if (n % 2 == 1) return hi;
  return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n / 2)));
}

// 1 / Phi^-1(3/4): the median absolute deviation of a normal sample times this is its sigma.
constexpr double kMadToSigma = 1.4826;
// The robust spread is at least this fraction of the median ratio, so that windows that agree to
// rounding (an exact chain) are not rejected as outliers of a zero spread.
constexpr double kMinRelativeSpread = 0.005;

}  // namespace

void HeightCheckOptions::check() const {
  if (!(window_m > 0.0)) bad("window_m", window_m, "> 0");
  if (!(min_chord_m > 0.0 && min_chord_m <= window_m))
    bad("min_chord_m", min_chord_m, "in (0, window_m]");
  if (!(max_step_m > 0.0)) bad("max_step_m", max_step_m, "> 0");
  if (!(outlier_sigmas > 0.0)) bad("outlier_sigmas", outlier_sigmas, "> 0");
  if (min_windows < 2) bad("min_windows", min_windows, ">= 2");
  if (!(warn_relative >= 0.0)) bad("warn_relative", warn_relative, ">= 0");
  if (!(warn_sigmas >= 0.0)) bad("warn_sigmas", warn_sigmas, ">= 0");
}

std::vector<HeightCheckFrame> height_check_frames(
    const std::vector<MosaicFrameResult>& results,
    const std::vector<std::optional<OdometryPose>>& odometry) {
  if (results.size() != odometry.size()) {
    throw std::invalid_argument("height_check_frames: " + std::to_string(results.size()) +
                                " builder results for " + std::to_string(odometry.size()) +
                                " odometry readings");
  }
  std::vector<HeightCheckFrame> out(results.size());
  for (size_t i = 0; i < results.size(); ++i) {
    const MosaicFrameResult& r = results[i];
    if (r.localised) out[i].T_mosaic_base = r.T_mosaic_base;
    if (odometry[i])
      out[i].T_odom_base = from_odometry(*odometry[i]);
    out[i].jump = r.relocalised || r.closed_loop;
  }
  return out;
}

std::string to_string(HeightCheckStatus status) {
  switch (status) {
    case HeightCheckStatus::kEstimated:
      return "estimated";
    case HeightCheckStatus::kNoOdometry:
      return "no_odometry";
    case HeightCheckStatus::kTooFewWindows:
      return "too_few_windows";
  }
  return "unknown";
}

HeightCheckStatus height_check_status_from_string(const std::string& name) {
  for (const HeightCheckStatus s : {HeightCheckStatus::kEstimated, HeightCheckStatus::kNoOdometry,
                                    HeightCheckStatus::kTooFewWindows}) {
    if (to_string(s) == name) return s;
  }
  throw std::invalid_argument("unknown height check status \"" + name +
                              "\" (estimated, no_odometry, too_few_windows)");
}

double HeightCheck::relative_error() const {
  return estimated() ? estimated_above_camera_m / configured_above_camera_m - 1.0 : 0.0;
}

std::vector<std::string> HeightCheck::validate() const {
  std::vector<std::string> e;
  if (!(configured_above_camera_m > 0.0 && std::isfinite(configured_height_m) &&
        configured_height_m >= configured_above_camera_m))
    e.push_back("height_check: configured_above_camera_m must be > 0 and <= configured_height_m");
  if (windows < 0 || windows_rejected < 0 || windows_turning < 0)
    e.push_back("height_check: window counts must be >= 0");
  if (!(odometry_m >= 0.0)) e.push_back("height_check: odometry_m must be >= 0");
  if (estimated()) {
    if (windows < 2) e.push_back("height_check: an estimate needs >= 2 windows");
    if (!(scale_ratio > 0.0 && std::isfinite(scale_ratio)))
      e.push_back("height_check: scale_ratio must be finite and > 0");
    if (!(scale_ratio_spread >= 0.0 && scale_ratio_sigma >= 0.0 && estimated_sigma_m >= 0.0))
      e.push_back("height_check: spreads must be >= 0");
    if (!(estimated_above_camera_m > 0.0 && std::isfinite(estimated_height_m) &&
          estimated_height_m >= estimated_above_camera_m))
      e.push_back("height_check: estimated_above_camera_m must be > 0 and <= estimated_height_m");
  } else if (disagrees) {
    e.push_back("height_check: disagrees without an estimate");
  }
  return e;
}

HeightCheck check_ceiling_height(const std::vector<HeightCheckFrame>& frames,
                                 const cv::Point2d& cam_in_base_m, double configured_height_m,
                                 double configured_above_camera_m,
                                 const HeightCheckOptions& options) {
  options.check();
  if (!(configured_above_camera_m > 0.0 && std::isfinite(configured_height_m) &&
        configured_height_m >= configured_above_camera_m)) {
    throw std::invalid_argument(
        "check_ceiling_height: configured_above_camera_m = " +
        std::to_string(configured_above_camera_m) +
        " must be > 0 and <= configured_height_m = " + std::to_string(configured_height_m));
  }
  HeightCheck out;
  out.configured_height_m = configured_height_m;
  out.configured_above_camera_m = configured_above_camera_m;

  // The optical centre's position under a base pose (the one point the chain scales exactly).
  auto centre = [&](const PlanarPose& T) { return T.apply(cam_in_base_m); };
  auto usable = [](const HeightCheckFrame& f) { return f.T_mosaic_base && f.T_odom_base; };

  std::vector<double> ratios, chords_m;
  bool any_step = false;  // two consecutive usable frames: the tour had odometry at all
  size_t start = 0;       // the current window's first frame (usable), or frames.size()
  double travelled_m = 0.0;
  auto restart = [&](size_t i) {
    start = i < frames.size() && usable(frames[i]) ? i : frames.size();
    travelled_m = 0.0;
  };
  restart(0);
  for (size_t i = 1; i < frames.size(); ++i) {
    const HeightCheckFrame& f = frames[i];
    // A window ends at a frame without a pose or odometry and at a jump of the chain (the jump
    // lies between frames i - 1 and i: frame i may start the next window).
    if (start == frames.size() || !usable(f) || !usable(frames[i - 1]) || f.jump) {
      restart(i);
      continue;
    }
    const HeightCheckFrame& p = frames[i - 1];
    any_step = true;
    const double odom_step_m = std::hypot(f.T_odom_base->x_m - p.T_odom_base->x_m,
                                          f.T_odom_base->y_m - p.T_odom_base->y_m);
    const double chain_step_m = std::hypot(f.T_mosaic_base->x_m - p.T_mosaic_base->x_m,
                                           f.T_mosaic_base->y_m - p.T_mosaic_base->y_m);
    if (odom_step_m > options.max_step_m || chain_step_m > options.max_step_m) {
      restart(i);
      continue;
    }
    travelled_m += odom_step_m;
    if (travelled_m < options.window_m) continue;
    const HeightCheckFrame& a = frames[start];
    const cv::Point2d odom_chord = centre(*f.T_odom_base) - centre(*a.T_odom_base);
    const cv::Point2d chain_chord = centre(*f.T_mosaic_base) - centre(*a.T_mosaic_base);
    const double odom_m = std::hypot(odom_chord.x, odom_chord.y);
    if (odom_m < options.min_chord_m) {
      ++out.windows_turning;
    } else {
      ratios.push_back(std::hypot(chain_chord.x, chain_chord.y) / odom_m);
      chords_m.push_back(odom_m);
    }
    restart(i);  // windows share their end frame: consecutive, not overlapping
  }
  if (!any_step) {
    out.status = HeightCheckStatus::kNoOdometry;
    return out;
  }

  // Robust rejection around the median, then the mean of the rest.
  std::vector<double> kept;
  double kept_chords_m = 0.0;
  if (!ratios.empty()) {
    const double med = median(ratios);
    std::vector<double> dev;
    for (const double r : ratios) dev.push_back(std::abs(r - med));
    const double spread = std::max(kMadToSigma * median(dev), kMinRelativeSpread * med);
    for (size_t k = 0; k < ratios.size(); ++k) {
      if (std::abs(ratios[k] - med) <= options.outlier_sigmas * spread) {
        kept.push_back(ratios[k]);
        kept_chords_m += chords_m[k];
      }
    }
  }
  out.windows_rejected = static_cast<int>(ratios.size() - kept.size());
  out.windows = static_cast<int>(kept.size());
  out.odometry_m = kept_chords_m;
  if (out.windows < options.min_windows) {
    out.status = HeightCheckStatus::kTooFewWindows;
    return out;
  }
  double sum = 0.0;
  for (const double r : kept) sum += r;
  const double mean = sum / static_cast<double>(kept.size());
  double ss = 0.0;
  for (const double r : kept) ss += (r - mean) * (r - mean);
  const double sd = std::sqrt(ss / static_cast<double>(kept.size() - 1));

  out.status = HeightCheckStatus::kEstimated;
  out.scale_ratio = mean;
  out.scale_ratio_spread = sd;
  out.scale_ratio_sigma = sd / std::sqrt(static_cast<double>(kept.size()));
  out.estimated_above_camera_m = configured_above_camera_m / mean;
  out.estimated_height_m =
      configured_height_m - configured_above_camera_m + out.estimated_above_camera_m;
  // d(h / s) = h / s^2 ds.
  out.estimated_sigma_m = out.estimated_above_camera_m * out.scale_ratio_sigma / mean;
  // Relative to the height above the camera: the scale of every distance in the mosaic.
  const double off_m = std::abs(out.estimated_above_camera_m - configured_above_camera_m);
  out.disagrees = off_m > options.warn_relative * configured_above_camera_m &&
                  off_m > options.warn_sigmas * out.estimated_sigma_m;
  return out;
}

}  // namespace pepper::core::ceiling
