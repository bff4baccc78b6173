#include "core/ceiling/ceiling_navigator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "core/control/planar_pose.hpp"
#include "core/features/feature_overlay.hpp"

namespace pepper::core::ceiling {

namespace nav = core::navigator;

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

control::PlanarPose to_control(const PlanarPose& p) { return {p.x_m, p.y_m, p.theta_rad}; }

/// Heading weight of the first segment choice, m per rad: a start 0.3 m off the tour and
/// 10 degrees off its heading (evaluate's largest perturbations) still prefers the segment it
/// stands beside to one crossing there the other way (a tour that comes back on itself).
constexpr double kSegmentHeadingWeightMPerRad = 0.5;

}  // namespace

std::vector<std::string> CeilingNavigatorOptions::validate() const {
  std::vector<std::string> e;
  if (!(max_forward_m > 0.0)) e.push_back("max_forward_m must be > 0");
  if (!(arc_min_turn_rad >= 0.0)) e.push_back("arc_min_turn_rad must be >= 0");
  if (!(turn_in_place_gain_1_s > 0.0)) e.push_back("turn_in_place_gain_1_s must be > 0");
  if (!(coast_max_error_m >= 0.0)) e.push_back("coast_max_error_m must be >= 0");
  if (!(coast_max_s >= 0.0)) e.push_back("coast_max_s must be >= 0");
  for (const auto& m : vnhv.validate()) e.push_back("vnhv: " + m);
  for (const auto& m : schedule.validate()) e.push_back("schedule: " + m);
  return e;
}

namespace {

const CeilingNavigatorOptions& checked(const CeilingNavigatorOptions& o) {
  const auto e = o.validate();
  if (!e.empty()) throw std::invalid_argument("CeilingNavigatorOptions: " + e.front());
  return o;
}

const CeilingTour& checked(const CeilingTour& t) {
  const auto e = t.validate();
  if (!e.empty()) throw std::invalid_argument("CeilingNavigator: invalid ceiling tour: " + e.front());
  if (t.relay_images.size() < 2) {
    throw std::invalid_argument("CeilingNavigator: the ceiling tour has fewer than 2 relay images");
  }
  return t;
}

}  // namespace

CeilingNavigator::CeilingNavigator(Mosaic mosaic, CeilingTour tour, const CeilingCamera& camera,
                                   const cv::Point2d& cam_in_base_m,
                                   const CeilingNavigatorOptions& options)
    : tour_(checked(tour)),
      options_(checked(options)),
      view_(std::make_unique<CanonicalView>(
          camera, fit_frame(camera, mosaic.px_per_m, options.max_forward_m))),
      cam_in_base_m_(cam_in_base_m),
      localiser_(std::move(mosaic), options.localiser),
      schedule_(options.schedule) {}

CeilingStepResult CeilingNavigator::step(const Frame& frame) {
  const CameraIntrinsics& k = view_->camera().intrinsics;
  if (frame.gray.empty() || frame.gray.type() != CV_8UC1) {
    throw std::invalid_argument("CeilingNavigator::step: frame " + std::to_string(frame.index) +
                                " is not a non-empty CV_8UC1 image");
  }
  if (frame.gray.cols != k.width_px || frame.gray.rows != k.height_px) {
    throw std::invalid_argument("CeilingNavigator::step: frame " + std::to_string(frame.index) +
                                " is " + std::to_string(frame.gray.cols) + "x" +
                                std::to_string(frame.gray.rows) + ", the camera's is " +
                                std::to_string(k.width_px) + "x" + std::to_string(k.height_px));
  }
  const auto t0 = Clock::now();
  cv::Mat seen;
  const cv::Mat canonical = view_->warp(frame.gray, &seen);
  const CeilingObservation obs =
      observe(*view_, cam_in_base_m_, extract_landmarks(canonical, seen, options_.landmarks));
  const double perceive_ms = ms_since(t0);
  CeilingStepResult r = step_observation(obs, frame.t_ns, frame.odom);
  r.ceiling.perceive_ms = perceive_ms;
  features::FeatureOverlay& overlay = r.step.telemetry.overlay;
  overlay.key_index = r.step.telemetry.in;
  for (const int i : r.ceiling.inlier_observations) {
    if (overlay.points_px.size() >= features::FeatureOverlay::kMaxPoints) break;
    if (const auto p = view_->to_image(cv::Point2d(obs.p_canon_px[static_cast<size_t>(i)]))) {
      overlay.points_px.emplace_back(static_cast<float>(p->x), static_cast<float>(p->y));
    }
  }
  r.step.telemetry.frame_index = frame.index;
  r.step.telemetry.timings.extract_ms = perceive_ms;
  r.step.telemetry.timings.total_ms = ms_since(t0);
  return r;
}

nav::Command CeilingNavigator::stop(nav::StopReason reason, nav::NavState state) {
  state_ = state;
  schedule_.reset();
  last_v_m_s_ = 0.0;
  nav::Command c;
  c.stop = true;
  c.reason = reason;
  return c;
}

int CeilingNavigator::nearest_segment(const PlanarPose& T_mosaic_base) const {
  const auto& relays = tour_.relay_images;
  const cv::Point2d p(T_mosaic_base.x_m, T_mosaic_base.y_m);
  int best = 0;
  double best_cost = 1e300;
  for (size_t i = 0; i + 1 < relays.size(); ++i) {
    const cv::Point2d a(relays[i].T_mosaic_base.x_m, relays[i].T_mosaic_base.y_m);
    const cv::Point2d b(relays[i + 1].T_mosaic_base.x_m, relays[i + 1].T_mosaic_base.y_m);
    const cv::Point2d ab = b - a;
    const double len2 = ab.dot(ab);
    const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    const double dir_rad =
        len2 > 0.0 ? std::atan2(ab.y, ab.x) : relays[i + 1].T_mosaic_base.theta_rad;
    const double cost = cv::norm(p - (a + t * ab)) +
                        kSegmentHeadingWeightMPerRad *
                            std::abs(wrap_angle_rad(T_mosaic_base.theta_rad - dir_rad));
    if (cost < best_cost) {
      best_cost = cost;
      best = static_cast<int>(i);
    }
  }
  return best;
}

bool CeilingNavigator::arc_segment(int next) const {
  const auto& r = tour_.relay_images;
  return std::abs(wrap_angle_rad(r[next].T_mosaic_base.theta_rad -
                                 r[next - 1].T_mosaic_base.theta_rad)) > options_.arc_min_turn_rad;
}

bool CeilingNavigator::chord_usable(int next) const {
  constexpr double kMinChordM = 0.03;
  const PlanarPose prev_in_next =
      tour_.relay_images[next].T_mosaic_base.inverse() * tour_.relay_images[next - 1].T_mosaic_base;
  // IN's heading is +x in its frame; the chord IP -> IN is -prev_in_next.
  return std::hypot(prev_in_next.x_m, prev_in_next.y_m) >= kMinChordM && prev_in_next.x_m < 0.0;
}

bool CeilingNavigator::passed(int next, const PlanarPose& T_mosaic_base) const {
  const PlanarPose T_in_mosaic = tour_.relay_images[next].T_mosaic_base.inverse();
  const PlanarPose base_in_next = T_in_mosaic * T_mosaic_base;
  const PlanarPose prev_in_next = T_in_mosaic * tour_.relay_images[next - 1].T_mosaic_base;
  // An arc, or a segment without a usable chord, ends along IN's heading (+x); a chord along
  // IP -> IN, i.e. -prev_in_next.
  if (arc_segment(next) || !chord_usable(next)) return base_in_next.x_m >= 0.0;
  return prev_in_next.x_m * base_in_next.x_m + prev_in_next.y_m * base_in_next.y_m <= 0.0;
}

double CeilingNavigator::demand(const PlanarPose& T_mosaic_base, nav::Telemetry& tel,
                                bool& in_place) {
  in_place = false;
  const PlanarPose T_in_mosaic = tour_.relay_images[next_].T_mosaic_base.inverse();
  const control::PlanarPose prev = to_control(T_in_mosaic * tour_.relay_images[next_ - 1].T_mosaic_base);
  const control::PlanarPose here = to_control(T_in_mosaic * T_mosaic_base);
  const bool arc = arc_segment(next_);
  const double kappa_1_m = arc ? control::arc_curvature(prev) : 0.0;
  std::optional<control::SegmentDeviation> dev;
  if (arc) {
    dev = control::deviation_from_arc(prev, here);
  } else if (chord_usable(next_)) {
    dev = control::deviation_from_segment(prev, here);
  }
  if (!dev) {
    // IP and IN coincide (a turn on the spot was taught), their chord is too short to give a
    // direction, or the robot is at the arc's centre: no line to follow, only IN's heading.
    dev = control::SegmentDeviation{here.y_m, control::wrap_angle_rad(here.yaw_rad)};
  }
  tel.vnhv_lateral_m = dev->lateral_m;
  tel.vnhv_heading_rad = dev->heading_rad;
  const double v = last_v_m_s_ > 0.0 ? last_v_m_s_ : options_.schedule.v_straight_m_s;
  const auto omega =
      control::vnhv_omega(v, dev->lateral_m, dev->heading_rad, options_.vnhv, kappa_1_m);
  if (omega) return *omega;
  // Facing too far off the path for the chained form: turn on the spot towards its direction.
  in_place = true;
  return -options_.turn_in_place_gain_1_s * dev->heading_rad;
}

void CeilingNavigator::fill_arrival(const PlanarPose& T_mosaic_base, bool from_fix,
                                    nav::Telemetry& tel) const {
  const PlanarPose in_final =
      tour_.relay_images.back().T_mosaic_base.inverse() * T_mosaic_base;
  tel.arrival_along_m = in_final.x_m;
  tel.arrival_lateral_m = in_final.y_m;
  tel.arrival_heading_rad = wrap_angle_rad(in_final.theta_rad);
  tel.arrival_source =
      from_fix ? nav::Telemetry::ArrivalSource::kVision : nav::Telemetry::ArrivalSource::kOdometry;
}

CeilingStepResult CeilingNavigator::step_observation(const CeilingObservation& observation,
                                                     int64_t t_ns,
                                                     const std::optional<OdometryPose>& odom) {
  if (last_t_ns_ && t_ns < *last_t_ns_) {
    throw std::invalid_argument("CeilingNavigator: frame time " + std::to_string(t_ns) +
                                " ns is before the previous frame's " +
                                std::to_string(*last_t_ns_) + " ns");
  }
  last_t_ns_ = t_ns;
  CeilingStepResult out;
  nav::Telemetry& tel = out.step.telemetry;
  CeilingTelemetry& ct = out.ceiling;
  tel.t_ns = t_ns;
  tel.vnhv_model_points = -1;
  const int n_relays = static_cast<int>(tour_.relay_images.size());
  auto finish = [&](nav::Command c) {
    tel.state = state_;
    tel.reason = c.reason;
    tel.ip = next_ >= 1 ? next_ - 1 : -1;
    tel.in = next_;
    tel.inn = next_ >= 0 && next_ + 1 < n_relays ? next_ + 1 : -1;
    out.step.command = c;
    return out;
  };

  // Final states: stop on every further frame.
  if (state_ == nav::NavState::kTourComplete) return finish(stop(nav::StopReason::kTourComplete, state_));
  if (broken_) return finish(stop(nav::StopReason::kRelayBreak, nav::NavState::kLost));

  // Localisation: around the previous pose (carried by the odometry since the last fix) while
  // navigating, over the whole mosaic before the first fix and once lost.
  const auto t_loc = Clock::now();
  const bool tracking = state_ == nav::NavState::kNavigating ||
                        state_ == nav::NavState::kDeadReckoning;
  // The odometry's possible error since the last fix grows with this frame's motion.
  if (odom && prev_odom_) {
    const PlanarPose step = odometry_motion(*prev_odom_, *odom);
    const double d_m = std::hypot(step.x_m, step.y_m);
    coast_heading_error_rad_ += kOdometryYawErrorPerRad * std::abs(wrap_angle_rad(step.theta_rad)) +
                                kOdometryYawErrorPerM * d_m;
    coast_error_m_ += (kOdometryDistanceErrorPerM + coast_heading_error_rad_) * d_m;
  }
  prev_odom_ = odom;
  std::optional<PlanarPose> predicted;
  if (tracking && last_fix_ && last_fix_odom_ && odom) {
    const PlanarPose delta = odometry_motion(*last_fix_odom_, *odom);
    predicted = *last_fix_ * delta;
    ct.coasted_m = std::hypot(delta.x_m, delta.y_m);
  } else if (tracking) {
    predicted = last_pose_;
  }
  MosaicFix fix;
  if (predicted) {
    fix = localiser_.localise(observation, predicted);
    ct.prior_used = true;
  }
  if (!fix.found) {
    // Without a prior (first fix, lost, or the prior's neighbourhood did not match).
    fix = localiser_.localise(observation);
    ct.prior_used = false;
    tel.localization_ran = true;
  }
  ct.localise_ms = ms_since(t_loc);
  tel.timings.localize_ms = ct.localise_ms;
  ct.fix = fix.found;
  ct.matches = fix.matches;
  ct.inliers = fix.inliers;
  if (fix.found) ct.inlier_observations = std::move(fix.inlier_observations);
  tel.n_points_next = fix.inliers;
  tel.localization_best_count = fix.inliers;

  PlanarPose pose;
  bool from_fix = false;
  if (fix.found) {
    pose = fix.T_mosaic_base;
    from_fix = true;
    last_fix_ = pose;
    last_fix_t_ns_ = t_ns;
    last_fix_odom_ = odom;
    coast_heading_error_rad_ = coast_error_m_ = 0.0;
    ct.coasted_m = 0.0;
    if (next_ < 0) next_ = nearest_segment(pose) + 1;
    if (state_ != nav::NavState::kNavigating) schedule_.reset();
    state_ = nav::NavState::kNavigating;
  } else if (tracking && predicted && last_fix_odom_ && odom && options_.coast_max_error_m > 0.0 &&
             coast_error_m_ <= options_.coast_max_error_m &&
             (t_ns - last_fix_t_ns_) * 1e-9 <= options_.coast_max_s) {
    pose = *predicted;
    state_ = nav::NavState::kDeadReckoning;
    tel.dead_reckoned_m = ct.coasted_m;
    ct.coast_error_m = coast_error_m_;
  } else {
    last_pose_.reset();
    return finish(state_ == nav::NavState::kNotLocalized
                      ? stop(nav::StopReason::kNotLocalized, nav::NavState::kNotLocalized)
                      : stop(nav::StopReason::kFeaturesLost, nav::NavState::kLost));
  }
  ct.pose_known = true;
  ct.T_mosaic_base = pose;
  last_pose_ = pose;
  tel.localization_best = next_;

  // Switching: past IN along the segment -> the next segment; past the final relay image: done.
  while (passed(next_, pose)) {
    if (next_ + 1 >= n_relays) {
      fill_arrival(pose, from_fix, tel);
      return finish(stop(nav::StopReason::kTourComplete, nav::NavState::kTourComplete));
    }
    ++next_;
    tel.switched = true;
  }
  if (std::find(tour_.breaks.begin(), tour_.breaks.end(), next_ - 1) != tour_.breaks.end()) {
    // No landmark links IP and IN: the teach lost the ceiling between them, the relay poses may
    // not be consistent. Stopped for good; the replay session ends on this reason.
    broken_ = true;
    return finish(stop(nav::StopReason::kRelayBreak, nav::NavState::kLost));
  }

  const auto t_ctl = Clock::now();
  bool in_place = false;
  const double omega_demand = demand(pose, tel, in_place);
  if (from_fix) {
    tel.vnhv_fix_lateral_m = tel.vnhv_lateral_m;
    tel.vnhv_fix_heading_rad = tel.vnhv_heading_rad;
  }
  tel.omega_demand_rad_s = omega_demand;
  const control::BaseCommand b = schedule_.step(omega_demand, t_ns);
  tel.turning = b.turning;
  nav::Command c;
  c.v_m_s = in_place ? 0.0 : b.v_m_s;
  c.omega_rad_s = b.omega_rad_s;
  c.stop = false;
  c.reason = nav::StopReason::kNone;
  last_v_m_s_ = c.v_m_s;
  tel.timings.control_ms = ms_since(t_ctl);
  return finish(c);
}

}  // namespace pepper::core::ceiling
