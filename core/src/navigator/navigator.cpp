#include "core/navigator/navigator.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "core/control/visual_features.hpp"
#include "core/geometry/floor_lines.hpp"
#include "core/geometry/line_yaw.hpp"
#include "core/navigator/transitions.hpp"

namespace pepper::core::navigator {

const char* to_string(ControllerKind k) {
  switch (k) {
    case ControllerKind::kIbvs:
      return "ibvs";
    case ControllerKind::kVnhv:
      return "vnhv";
  }
  return "unknown";
}

features::MatcherOptions matcher_for(control::FeatureMode mode, features::MatcherOptions base) {
  base.match_lines = mode != control::FeatureMode::kPointsOnly;
  base.match_points = mode != control::FeatureMode::kLinesOnly;
  return base;
}

const char* to_string(NavState s) {
  switch (s) {
    case NavState::kNotLocalized:
      return "not_localized";
    case NavState::kNavigating:
      return "navigating";
    case NavState::kHolding:
      return "holding";
    case NavState::kLost:
      return "lost";
    case NavState::kTourComplete:
      return "tour_complete";
    case NavState::kOverdue:
      return "overdue";
    case NavState::kDeadReckoning:
      return "dead_reckoning";
  }
  return "unknown";
}

const char* to_string(StopReason r) {
  switch (r) {
    case StopReason::kNone:
      return "none";
    case StopReason::kNotLocalized:
      return "not_localized";
    case StopReason::kFeaturesLost:
      return "features_lost";
    case StopReason::kTourComplete:
      return "tour_complete";
    case StopReason::kSegmentOverdue:
      return "segment_overdue";
    case StopReason::kRelayBreak:
      return "relay_break";
  }
  return "unknown";
}

const char* to_string(Telemetry::ArrivalSource s) {
  switch (s) {
    case Telemetry::ArrivalSource::kNone:
      return "none";
    case Telemetry::ArrivalSource::kVision:
      return "vision";
    case Telemetry::ArrivalSource::kOdometry:
      return "odometry";
  }
  return "unknown";
}

std::vector<std::string> NavigatorOptions::validate() const {
  std::vector<std::string> errors;
  auto append = [&](std::vector<std::string> more, const char* prefix) {
    for (auto& e : more) errors.push_back(prefix + e);
  };
  append(ibvs.validate(), "");
  append(vnhv.validate(), "");
  append(schedule.validate(), "");
  append(initial.validate(), "");
  append(switching.validate(), "");
  append(extractor.validate(), "features.");
  append(matcher.validate(), "matching.");
  auto check = [&](bool ok, const char* name, double value, const char* range) {
    if (!ok) {
      std::ostringstream os;
      os << "navigator." << name << " = " << value << " must be " << range;
      errors.push_back(os.str());
    }
  };
  check(hold_s >= 0, "hold_s", hold_s, ">= 0");
  check(min_line_matches >= 1, "min_line_matches", min_line_matches, ">= 1");
  check(min_point_matches >= 1, "min_point_matches", min_point_matches, ">= 1");
  check(min_scale_points >= 3, "min_scale_points", min_scale_points, ">= 3");
  check(arrival_min_scale_points >= 3, "arrival_min_scale_points", arrival_min_scale_points,
        ">= 3");
  check(blind_switch_min_driven_fraction >= 0.0 && blind_switch_min_driven_fraction <= 1.0,
        "blind_switch_min_driven_fraction", blind_switch_min_driven_fraction,
        "0 (off) or in (0, 1]");
  check(segment_overdue_factor >= 0.0, "segment_overdue_factor", segment_overdue_factor, ">= 0");
  check(segment_overdue_min_s >= 0, "segment_overdue_min_s", segment_overdue_min_s, ">= 0");
  check(scale_quantile > 0.0 && scale_quantile < 1.0, "scale_quantile", scale_quantile,
        "in (0, 1)");
  check(min_scale_lines >= 0, "min_scale_lines", min_scale_lines, ">= 0");
  check(min_scale_pairs >= 1, "min_scale_pairs", min_scale_pairs, ">= 1");
  check(scale_line_max_angle_rad > 0.0 && scale_line_max_angle_rad <= 0.5,
        "scale_line_max_angle_rad", scale_line_max_angle_rad, "in (0, 0.5]");
  check(dead_reckoning_max_lateral_sigma_m > 0.0, "dead_reckoning_max_lateral_sigma_m",
        dead_reckoning_max_lateral_sigma_m, "> 0");
  check(odometry_steer_max_m > 0.0, "odometry_steer_max_m", odometry_steer_max_m, "> 0");
  check(min_point_texture >= 0.0, "min_point_texture", min_point_texture, ">= 0");
  check(arrival_scale_ratio > 0.0 && arrival_scale_ratio < 2.0, "arrival_scale_ratio",
        arrival_scale_ratio, "in (0, 2)");
  return errors;
}

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

Command stop_command(StopReason reason) {
  Command c;
  c.stop = true;
  c.reason = reason;
  return c;
}

control::LineRhoTheta to_control(const features::RhoTheta& l) { return {l.rho, l.theta_rad}; }

struct LineSets {
  std::vector<control::LineRhoTheta> current, key;
};
LineSets line_sets(const features::TwoViewMatches& m, const features::ImageFeatures& key,
                   const features::ImageFeatures& current) {
  LineSets s;
  for (const features::LineMatch& lm : m.lines) {
    s.key.push_back(to_control(key.lines[lm.idx_a].line));
    s.current.push_back(to_control(current.lines[lm.idx_b].line));
  }
  return s;
}

struct PointSets {
  std::vector<cv::Point2d> current, key;
};
// Minimum eigenvalue of the mean structure tensor of `gray` in a 7x7 window at p (central
// differences); 0 at the border.
double min_texture_eig(const cv::Mat& gray, const cv::Point2f& p) {
  constexpr int kHalf = 3;
  const int cx = cvRound(p.x), cy = cvRound(p.y);
  if (cx - kHalf - 1 < 0 || cy - kHalf - 1 < 0 || cx + kHalf + 1 >= gray.cols ||
      cy + kHalf + 1 >= gray.rows) {
    return 0.0;
  }
  double a = 0, b = 0, c = 0;
  for (int y = cy - kHalf; y <= cy + kHalf; ++y) {
    const uint8_t* row = gray.ptr<uint8_t>(y);
    const uint8_t* up = gray.ptr<uint8_t>(y - 1);
    const uint8_t* down = gray.ptr<uint8_t>(y + 1);
    for (int x = cx - kHalf; x <= cx + kHalf; ++x) {
      const double gx = 0.5 * (row[x + 1] - row[x - 1]);
      const double gy = 0.5 * (down[x] - up[x]);
      a += gx * gx;
      b += gx * gy;
      c += gy * gy;
    }
  }
  constexpr double kN = (2 * kHalf + 1) * (2 * kHalf + 1);
  a /= kN;
  b /= kN;
  c /= kN;
  return 0.5 * (a + c - std::sqrt((a - c) * (a - c) + 4 * b * b));
}

// Point pairs (key, current) of a two-view result; with `gray`, only those whose current
// location is textured (min_texture_eig >= min_texture).
PointSets point_sets(const features::TwoViewMatches& m, const cv::Mat& gray = cv::Mat(),
                     double min_texture = 0.0) {
  PointSets s;
  for (const features::PointMatch& pm : m.points) {
    if (!gray.empty() && min_texture_eig(gray, pm.b_px) < min_texture) continue;
    s.key.push_back(pm.a_norm);
    s.current.push_back(pm.b_norm);
  }
  return s;
}

std::vector<std::optional<OdometryPose>> taught_odometry(const memory::VisualMemory& map) {
  std::vector<std::optional<OdometryPose>> out;
  for (const memory::KeyImage& k : map.key_images) out.push_back(k.odom);
  return out;
}

// "Passed IN by travel" without odometry (maps built from image folders, or a robot that reports
// none): a switch is wanted once the distance commanded on a segment entered by a switch reaches
// this x its taught length while IN's scale is unknown. The taught length of such a map is itself
// the taught time x vnhv.teach_speed_m_s, hence the margin. Measured when it was an option
// (session 14, room_corridor_room light run 2, VGA, seed 1): key image 12 faces a bare wall;
// with the light change neither it nor key image 13 kept a point, no rule fired, the robot drove
// 0.39 m on the 0.08 m segment 11 -> 12 into the first left turn's wall and was lost at 6.0 m;
// with 2 it switched after 0.18 m and completed (1.7 / 4.4 cm). Since then the map keeps
// odometry, and the odometry source of the rule took over there.
constexpr double kPassedByCommandsFactor = 2.0;
// Arrival when the final image fades, where there is no odometry (maps built from image
// folders, a robot that reports none): on the final segment, once the scale ratio with the final
// image has read at least this, frames where it cannot be measured any more (a close-up of the
// furniture that ends the tour) also count as arrival (same consecutive-frame rule); stopping a
// few centimetres short is the safe side. Measured when it was an option for every map (session
// 17, room_corridor_room, VGA, seed 1, runs 5 and 8 of 10): the ratio read 0.968-0.978 2-3 cm
// before the final image, then 0-8 points and <= 6 lines, and the robot drove 0.35 m on into the
// lab shelf. With odometry the arrival on odometry covers it: the rule off changed no run of
// the generated screening nor of room_corridor_room's 10 starts (docs/method/navigator.md,
// ablations), so it acts only where the odometry cannot.
constexpr double kArrivalFadeRatio = 0.95;
// "Passed IN by odometry" while vision's scale ratio is known: the estimate past IN by this many
// sigmas along the robot (one-sided, P = 0.98).
constexpr double kPassedSigmas = 2.0;
// Floor lines (geometry/floor_lines.hpp) correct the odometry estimate's lateral position only,
// from lines within this angle of IN's forward axis. Why: in white_corridor under light x1.4 the
// along position from lines across the view (the lamps' reflections in the shiny floor, which
// back-project to a third of their distance) ran 1.2 m ahead and the tour ended 2.3 m early
// (run 9, `evaluate --world worlds/white_corridor.yaml --starts 10 --run 9 --seed 1 --size 640x480
// --disturbance light --light-factor 1.4 --trace DIR`).
constexpr double kFloorLineMaxAngleRad = 0.5;

// The heading of the odometry estimate has a sigma (errors_, estimate_errors.hpp), the
// odometry's error model: it grows by kOdometryYawErrorPerRad of every turn and
// kOdometryYawErrorPerM per metre (core/odometry.hpp), is
// kPlacedHeadingSigmaRad when a (re)localisation places the estimate at a key image's taught
// pose, and shrinks with each VNHV fix (kFixErrors below). Where no VNHV fix corrects the
// estimate, the heading relative to IN from the matched horizontal lines (geometry/line_yaw.hpp)
// corrects the heading, as the room's or a moved object's (kLineYawErrors below).
constexpr double kPlacedHeadingSigmaRad = 0.1;
constexpr double kMinLineYawSigmaRad = 0.005;  // the lines' own sigma, floored: sway, lens
constexpr double kHeadingGateSigmas = 3.0;
// The estimate's position sigmas along and across the robot's heading (errors_: along and
// across), the same kind of model: along grows by kOdometryDistanceErrorPerM of every
// metre (core/odometry.hpp), across by the heading's sigma times the
// metre (a heading error turns into a sideways one); both are kPlacedPositionSigmaM when a
// (re)localisation places the estimate at a key image's taught pose (starts are up to 0.4 m along
// and 0.2 m across from it), and shrink with each VNHV fix (kFixErrors below). A lateral sigma of
// kLocatedLateralSigmaM or less counts as located across the path (floor lines: the odometry may
// steer, as after a VNHV fix).
constexpr double kPlacedPositionSigmaM = 0.5;
constexpr double kLocatedLateralSigmaM = 0.03;
// A VNHV fix's error is mostly its segment's, shared by every fix of the segment, and of one of
// two sizes: the room's model (measured, room_corridor_room, VGA, no disturbance, 36 straight
// segments, `evaluate --run 1 --trace`: per-segment mean lateral error RMS 0.44 cm, max 1.45 cm;
// heading RMS 0.0035 rad) or a moved object's (moved furniture: 10-35 cm, 0.03-0.13 rad). The
// update weighs both (fix_error_mixture.hpp); each fix also has its own noise (within a segment,
// lateral RMS 0.46 cm; a fix's whole error: lateral RMS 0.65 cm, p99 2.6 cm, heading RMS 0.002
// rad, p99 0.008 rad over 1504 fixes). Along the axis (the points' depth) nothing was measured:
// 5 cm for the room's shared error and for the noise, a guess. A fix's weight against the
// prediction (Tukey's, vnhv_omega) divides the noise variances: a fix near the gate's edge hardly
// moves the estimate.
constexpr FixErrorMixtureOptions kFixErrors{/*usual_sigma=*/{0.05, 0.01, 0.005},
                                            /*moved_sigma=*/{0.5, 0.3, 0.1},
                                            /*noise_sigma=*/{0.05, 0.01, 0.003},
                                            /*moved_prior=*/0.1};
// The lines' heading has the fixes' two kinds of error (fix_error_mixture.hpp): every line yaw of
// a segment is measured against IN's lines, and a moved shelf's boards are as horizontal as the
// room's skirting. Taken as independent, a turned shelf's line yaws walked the heading to the
// shelf's turn in small steps, each inside a 3-sigma gate (room_corridor_room, furniture, run 3:
// 148 corrections, -0.131 rad, the shelf turned 0.127 rad; docs/method/navigator.md). Measured
// in robotics_room, window_corridor and room_corridor_room without disturbance (VGA, `evaluate
// --starts 10 --run 2 --seed 1 --trace DIR`, 24 straight segments with line yaws, line yaw
// minus the true yaw relative to IN): per-segment mean RMS 0.0045 rad, max 0.020 (room_corridor_
// room's IN 6, in runs 1 and 2); within a segment RMS 0.0032 rad (below the floor
// kMinLineYawSigmaRad). The room's sigma, 0.01 rad, covers that maximum at two sigmas; a moved
// object's, 0.1 rad, a shelf turned by up to about 15 degrees. The heading axis alone.
constexpr double kNotModelled = std::numeric_limits<double>::quiet_NaN();
constexpr FixErrorMixtureOptions kLineYawErrors{
    /*usual_sigma=*/{kNotModelled, kNotModelled, 0.01},
    /*moved_sigma=*/{kNotModelled, kNotModelled, 0.1},
    /*noise_sigma=*/{kNotModelled, kNotModelled, kMinLineYawSigmaRad},
    /*moved_prior=*/0.1};
// The floor lines' lateral position has the same two kinds of error: a segment's floor lines
// are IN's, and a moved bench's or shelf's foot on the floor is a floor line too (room_corridor_
// room, furniture, run 8: the floor lines put the robot 15-25 cm right of where it was, for a
// metre, and it ended 0.31 m from the end). Measured without disturbance (VGA, `evaluate
// --starts 10 --run 2 --seed 1 --trace DIR`, straight segments, the lines' lateral position alone
// minus the true one; telemetry floor_lateral_lines_m): robotics_room 6 segments, per-segment
// mean RMS 2.3 cm, max 4.5 cm; window_corridor 13 segments, 0.26 cm, max 0.74 cm;
// room_corridor_room one frame. Within a segment RMS 2.4 and 0.25 cm, below the lines' own
// reported sigma (median 6.8 and 1.3 cm), which is each fix's noise here (the option's 1 cm is
// its floor). The room's sigma, 4 cm, is about the measured maximum; a moved object's 0.3 m.
// The across axis alone.
constexpr FixErrorMixtureOptions kFloorErrors{/*usual_sigma=*/{kNotModelled, 0.04, kNotModelled},
                                              /*moved_sigma=*/{kNotModelled, 0.3, kNotModelled},
                                              /*noise_sigma=*/{kNotModelled, 0.01, kNotModelled},
                                              /*moved_prior=*/0.1};
// A key-image switch that the image decided (a paper rule, neither "passed IN by travel" source)
// says the robot is at IN, along the path: a measurement of the estimate's along axis. Measured
// (QVGA traces of 15 generated and shipped worlds, docs/method/navigator.md "The first switch
// after a placement"): the true position at such a switch is IN -1.3 cm (median), p05 -14 cm,
// p95 +7 cm, RMS 5.9 cm, while the estimate's own error there is RMS 4.1 cm once fixes and
// odometry carry it, and 0.5 m right after a (re)localisation placed it (kPlacedPositionSigmaM).
// So only the first such switch after a placement is taken: later ones are no better than the
// estimate, and their errors are alike switch after switch (a few centimetres early), so taking
// them all pulled the estimate ahead (measured worse, in the doc). Two kinds of error: the
// usual one, and a look-alike's (key images a few centimetres apart in a turn fire the rules
// tens of centimetres early), which the mixture weighs against the estimate's sigma.
constexpr FixErrorMixtureOptions kSwitchErrors{/*usual_sigma=*/{0.05, kNotModelled, kNotModelled},
                                               /*moved_sigma=*/{0.4, kNotModelled, kNotModelled},
                                               /*noise_sigma=*/{0.05, kNotModelled, kNotModelled},
                                               /*moved_prior=*/0.2};
// Turning on the spot on odometry: yaw rate per radian still to turn, 1/s; and the heading error
// (rad) beyond which the robot turns on the spot before driving on.
constexpr double kTurnGain_1_s = 1.5;
constexpr double kTurnFirstRad = 0.5;

// IN-side corner index and normalised coordinates of KLT tracks from IN (view a) into another
// image (view b), for the VNHV segment pose (control/segment_pose.hpp).
std::vector<control::CornerObservation> corner_observations(const features::TwoViewMatches& m) {
  std::vector<control::CornerObservation> out;
  out.reserve(m.points.size());
  for (const features::PointMatch& p : m.points) out.push_back({p.idx_a, p.a_norm, p.b_norm});
  return out;
}

}  // namespace

Navigator::Navigator(memory::VisualMemory map, const NavigatorOptions& options)
    : map_(std::move(map)),
      options_(options),
      extractor_(map_.camera, options.extractor),
      schedule_(options.schedule),
      vnhv_filter_(options.vnhv.filter),
      errors_(kFixErrors, kLineYawErrors, kFloorErrors, kSwitchErrors),
      tracker_(taught_odometry(map_)) {
  options_.ibvs.mode = options_.features;
  options_.matcher = matcher_for(options_.features, options_.matcher);
  if (const auto errors = options_.validate(); !errors.empty()) {
    throw std::invalid_argument("Navigator: " + errors.front());
  }
  if (map_.key_images.size() < 2) {
    throw std::invalid_argument("Navigator: the map has fewer than 2 key images");
  }
}

void Navigator::reset() {
  state_ = NavState::kNotLocalized;
  ever_localised_ = false;
  final_fix_.reset();
  switcher_.reset();
  schedule_.reset();
  has_command_ = false;
  last_t_ns_.reset();
  vnhv_segment_next_ = -1;
  segment_start_t_ns_.reset();
  segment_from_switch_ = false;
  segment_driven_m_ = 0.0;
  final_ratio_in_ = -1;
  klt_starts_.clear();
  tracker_.reset();
  odom_.reset();
  blind_m_ = blind_rad_ = 0.0;
  odom_since_fix_m_ = 1e9;
  errors_.place({kPlacedPositionSigmaM, kPlacedPositionSigmaM, kPlacedHeadingSigmaRad});
  drift_report_pending_ = false;
}

void Navigator::ensure_pyramids(const localization::Segment& seg) {
  const int last = seg.next_next.value_or(seg.next);
  for (int i = 0; i < static_cast<int>(map_.key_images.size()); ++i) {
    features::ImageFeatures& f = map_.key_images[i].features;
    const bool wanted = i >= seg.prev && i <= last;
    if (wanted && f.klt_pyramid.empty()) features::build_klt_pyramid(f, options_.matcher.klt);
    if (!wanted && !f.klt_pyramid.empty()) features::release_klt_pyramid(f);
  }
}

std::optional<double> Navigator::scale_ratio(const features::TwoViewMatches& m,
                                             const features::ImageFeatures& key_image,
                                             const features::ImageFeatures& current,
                                             int min_points) const {
  constexpr double kMinSeparationNorm = 0.05;
  const PointSets s = point_sets(m);
  const int n_points = static_cast<int>(s.key.size());
  std::vector<double> ratios;
  if (n_points >= min_points) {
    localization::append_point_scale_ratios(s.key, s.current, kMinSeparationNorm, ratios);
    return localization::quantile_ratio(ratios, options_.scale_quantile);
  }
  if (options_.min_scale_lines == 0 || m.n_lines() < options_.min_scale_lines) {
    return std::nullopt;
  }
  std::vector<localization::LineCorrespondence> lines;
  lines.reserve(m.lines.size());
  for (const features::LineMatch& lm : m.lines) {
    const features::LineSegment& a = key_image.lines.at(static_cast<size_t>(lm.idx_a));
    const features::LineSegment& b = current.lines.at(static_cast<size_t>(lm.idx_b));
    lines.push_back({a.p0_norm, a.p1_norm, b.p0_norm, b.p1_norm});
  }
  localization::append_line_scale_ratios(lines, options_.scale_line_max_angle_rad,
                                         kMinSeparationNorm, ratios);
  if (static_cast<int>(ratios.size()) < options_.min_scale_pairs) return std::nullopt;
  return localization::quantile_ratio(ratios, options_.scale_quantile);
}

bool Navigator::blind_switch_allowed() const {
  const double fraction = options_.blind_switch_min_driven_fraction;
  if (fraction <= 0.0 || !segment_from_switch_ || !switcher_ || !segment_start_t_ns_) return true;
  return segment_driven_m_ >= fraction * segment_taught_m();
}

double Navigator::segment_taught_ns() const {
  const localization::Segment& seg = switcher_->segment();
  return static_cast<double>(map_.key_images[seg.next].t_ns - map_.key_images[seg.prev].t_ns);
}

void Navigator::begin_segment(int64_t t_ns, bool from_switch) {
  segment_start_t_ns_ = t_ns;
  segment_from_switch_ = from_switch;
  segment_driven_m_ = 0.0;
}

double Navigator::segment_taught_m() const {
  // Below this the teach drive turned (nearly) on the spot: no length to scale a segment with.
  constexpr double kMinTravelledSegmentM = 0.01;
  const localization::Segment& seg = switcher_->segment();
  const double driven_m =
      map_.key_images[seg.next].travelled_m - map_.key_images[seg.prev].travelled_m;  // NaN: none
  if (driven_m >= kMinTravelledSegmentM) return driven_m;
  return segment_taught_ns() * 1e-9 * options_.vnhv.teach_speed_m_s;
}

bool Navigator::segment_overdue(int64_t t_ns) const {
  if (options_.segment_overdue_factor <= 0.0 || !switcher_ || !segment_start_t_ns_) return false;
  const double allowed_ns = std::max(options_.segment_overdue_min_s * 1e9,
                                     options_.segment_overdue_factor * segment_taught_ns());
  return static_cast<double>(t_ns - *segment_start_t_ns_) > allowed_ns;
}

void Navigator::remember_tracks(const features::FrameMatcher& fm) {
  klt_starts_.clear();
  ++remembered_frames_;
  if (!switcher_) return;
  const localization::Segment& seg = switcher_->segment();
  for (const int i : {seg.prev, seg.next, seg.next_next.value_or(-1)}) {
    if (const features::TwoViewMatches* m = i >= 0 ? fm.computed_two_view(i) : nullptr) {
      // The next frame retries only a share of the corners this one did not track.
      klt_starts_[i] = {m->points,
                        features::klt_corners_to_skip(m->klt_untracked, remembered_frames_ + 1,
                                                      options_.matcher.klt.retry_untracked_frames)};
    }
  }
}

bool Navigator::localize(features::FrameMatcher& fm, Telemetry& tel) {
  const auto t0 = Clock::now();
  // After a loss, odometry along the taught path says where the robot should be: those key
  // images are verified whatever the appearance vote ranks first.
  // When the replay starts, the operator has placed the robot at the tour's start (README,
  // user guide): the first key images are expected there.
  std::vector<int> expected;
  if (odom_ && tracker_.usable()) {
    if (const auto d = tracker_.deviation()) {
      for (int k = d->piece - 1; k <= d->piece + 2; ++k) expected.push_back(k);
    }
  }
  if (expected.empty() && !ever_localised_) expected = {0, 1, 2};
  const localization::InitialLocalizationReport report =
      localization::localize_in_map(fm, map_, options_.initial, expected);
  tel.localization_ran = true;
  tel.localization_best = report.result.best;
  tel.localization_best_count = report.result.best_count;
  tel.localization_verified = report.verified;
  if (report.result.segment) {
    ever_localised_ = true;
    switcher_.emplace(*report.result.segment, static_cast<int>(map_.key_images.size()),
                      options_.switching);
    // The robot is between IP and IN of the segment found. An odometry estimate carried from
    // before (a loss) is kept where it agrees; otherwise it starts at IP's taught pose, behind
    // the robot rather than ahead of it: an estimate behind is caught up by the next key-image
    // switch (the tracker advances with it), while one ahead fires "passed IN by travel" and
    // the taught turns before the robot is there. Measured (docs/evaluation.md, session 34):
    // placed at the best key image (often IN), gen_room_7's start estimate was 0.63 m ahead, and
    // the replay turned its first spot turn that early and diverged.
    if (odom_ && tracker_.usable()) {
      const OdometryPose& placed = tracker_.taught(report.result.segment->prev);
      const auto& X = tracker_.estimate();
      constexpr double kAgreeM = 1.0;
      if (!X || std::hypot(X->x_m - placed.x_m, X->y_m - placed.y_m) > kAgreeM) {
        tracker_.set(placed, *odom_, report.result.segment->prev);
        errors_.place({kPlacedPositionSigmaM, kPlacedPositionSigmaM, kPlacedHeadingSigmaRad});
      } else {
        tracker_.set(*X, *odom_, report.result.segment->prev);
      }
    }
    schedule_.reset();
    has_command_ = false;
  }
  tel.timings.localize_ms = ms_since(t0);
  return report.result.segment.has_value();
}

std::optional<double> Navigator::ibvs_omega(features::FrameMatcher& fm, Telemetry& tel) {
  const localization::Segment& seg = switcher_->segment();
  const features::ImageFeatures& cur = fm.current();
  const features::TwoViewMatches& tv_n = fm.two_view_for_control(seg.next, key(seg.next));
  const features::TwoViewMatches* tv_nn =
      seg.next_next ? &fm.two_view_for_control(*seg.next_next, key(*seg.next_next)) : nullptr;
  control::IbvsInput in;
  if (tv_n.n_lines() >= options_.min_line_matches) {
    const LineSets s = line_sets(tv_n, key(seg.next), cur);
    control::ModalityError m;
    m.err_next = control::line_feature_X(s.current) - control::line_feature_X(s.key);
    m.jacobian = control::line_jacobian_dX_domega(s.current);
    if (tv_nn && tv_nn->n_lines() >= options_.min_line_matches) {
      const LineSets s2 = line_sets(*tv_nn, key(*seg.next_next), cur);
      m.err_next_next = control::line_feature_X(s2.current) - control::line_feature_X(s2.key);
    }
    in.lines = m;
  }
  const PointSets s = point_sets(tv_n, cur.gray, options_.min_point_texture);
  if (static_cast<int>(s.current.size()) >= options_.min_point_matches) {
    control::ModalityError m;
    m.err_next = control::point_feature_x(s.current) - control::point_feature_x(s.key);
    m.jacobian = control::point_jacobian_dx_domega(s.current);
    if (tv_nn) {
      const PointSets s2 = point_sets(*tv_nn, cur.gray, options_.min_point_texture);
      if (static_cast<int>(s2.current.size()) >= options_.min_point_matches) {
        m.err_next_next = control::point_feature_x(s2.current) - control::point_feature_x(s2.key);
      }
    }
    in.points = m;
  }
  const control::IbvsResult r = control::compute_ibvs_omega(in, options_.ibvs);
  if (in.lines) {
    tel.line_err_next = in.lines->err_next;
    tel.line_err_next_next = in.lines->err_next_next.value_or(kNaN);
    tel.J_L = in.lines->jacobian;
  }
  if (in.points) {
    tel.point_err_next = in.points->err_next;
    tel.point_err_next_next = in.points->err_next_next.value_or(kNaN);
    tel.J_P = in.points->jacobian;
  }
  tel.used_lines = r.used_lines;
  tel.used_points = r.used_points;
  return r.omega_rad_s;
}

bool Navigator::vnhv_planar_motion_ok(const features::TwoViewMatches& next_prev,
                                      double focal_px) const {
  if (!next_prev.essential_found) return false;
  std::vector<cv::Point2d> next, prev;
  for (const features::PointMatch& p : next_prev.points) {
    next.push_back(p.a_norm);
    prev.push_back(p.b_norm);
  }
  // The perception layer's reliability test of a planar two-view motion (enough points,
  // decisive cheirality, rotation about the vertical, translation in the floor plane, parallax
  // after derotation: not a turn on the spot). Its motion is not used (fit_arc_segment is).
  // Measured (robotics_room, QVGA, 2 starts): lateral RMS 9.6 cm with this test, 11.1 cm without
  // (the extra segments were turns with 5-20 cm between the key images).
  return geometry::planar_view_prior(next_prev.E_b_a, next, prev, focal_px,
                                     options_.matcher.trifocal)
      .has_value();
}

std::optional<double> Navigator::vnhv_omega(features::FrameMatcher& fm, Telemetry& tel) {
  const localization::Segment& seg = switcher_->segment();
  const control::VnhvOptions& o = options_.vnhv;
  const double focal_px = map_.camera.fx_px;
  if (vnhv_segment_next_ != seg.next) {
    // New segment: reconstruct it once (IN's corners tracked into IP, a = IN, b = IP).
    vnhv_segment_next_ = seg.next;
    vnhv_filter_.reset();
    vnhv_model_.reset();
    errors_.begin();  // a new model: its fixes' shared error is new too
    vnhv_pose_ = o.pose;
    const double taught_m = segment_taught_m();
    const features::TwoViewMatches next_prev =
        features::match_two_view(key(seg.next), key(seg.prev), options_.matcher);
    if (vnhv_planar_motion_ok(next_prev, focal_px)) {
      const std::vector<control::CornerObservation> obs = corner_observations(next_prev);
      const std::optional<control::PlanarPose> prev =
          control::fit_arc_segment(obs, focal_px, o.pose);
      const double turn_rad = prev ? std::abs(prev->yaw_rad) : 0.0;
      if (prev && turn_rad <= o.max_segment_turn_rad && taught_m >= o.straight_min_length_m) {
        // A long straight segment: distant points count too.
        vnhv_pose_.min_parallax_rad = o.straight_min_parallax_rad;
        vnhv_pose_.min_points = o.straight_min_points;
      }
      if (prev && turn_rad <= std::max(o.max_segment_turn_rad, o.max_arc_turn_rad)) {
        vnhv_model_ = control::build_segment_model(*prev, obs, focal_px, vnhv_pose_);
      }
    }
    // One segment unit is the chord IP -> IN; a straight segment's taught length is its chord.
    vnhv_m_per_unit_ = taught_m;
    vnhv_curvature_1_m_ = 0.0;
    if (vnhv_model_ && std::abs(vnhv_model_->prev_in_next.yaw_rad) > o.max_segment_turn_rad) {
      // A turning segment follows its arc. The taught duration gives the arc's length: metres
      // per segment unit = length / (turn / |kappa in units|).
      const control::PlanarPose& p = vnhv_model_->prev_in_next;
      const double kappa_unit = control::arc_curvature(p);
      const double arc_units = std::abs(p.yaw_rad) / std::abs(kappa_unit);
      vnhv_m_per_unit_ /= arc_units;
      vnhv_curvature_1_m_ = kappa_unit / vnhv_m_per_unit_;
    }
  } else {
    // The command sent after the previous frame moved the robot until now.
    vnhv_filter_.predict(has_command_ ? last_command_.v_m_s : 0.0,
                         has_command_ ? last_command_.omega_rad_s : 0.0, tel.t_ns,
                         vnhv_curvature_1_m_);
  }
  tel.vnhv_model_points = vnhv_model_ ? static_cast<int>(vnhv_model_->point_by_corner.size()) : 0;
  if (!vnhv_model_) return std::nullopt;
  const features::TwoViewMatches& tv_n = fm.two_view(seg.next, key(seg.next));
  bool past_next = false;
  const std::optional<control::PosePrior> prior = resection_prior(seg.next);
  const auto fix = control::locate_in_segment(*vnhv_model_, corner_observations(tv_n), focal_px,
                                              vnhv_pose_, prior ? &*prior : nullptr);
  tel.vnhv_structures = fix ? fix->structures : 0;
  tel.vnhv_fix_refused = fix && !fix->within_prior;
  // A fix's weight against the prediction (Tukey's biweight of its Mahalanobis distance, zero at
  // the gate): one near the gate's edge hardly pulls. With a fixed pull, a moved structure that
  // hovered at the gate's edge was accepted now and then, each time pulling the estimate halfway
  // to itself, until every fix of it was within the gate (room_corridor_room, furniture, run 4).
  const double fix_weight =
      fix && prior ? std::pow(std::max(0.0, 1.0 - fix->prior_d2 / prior->gate_chi2), 2) : 1.0;
  // How far the fix extrapolates IN's reconstruction (docs/method/navigator.md, "A fix's error
  // and its distance from IN").
  if (fix) tel.vnhv_fix_r_units = std::hypot(fix->pose.x_m, fix->pose.y_m);
  const control::PlanarPose& prev = vnhv_model_->prev_in_next;  // IN at the origin
  const bool arc = vnhv_curvature_1_m_ != 0.0;
  auto deviation_of = [&](const control::PlanarPose& pose) {
    auto dev =
        arc ? control::deviation_from_arc(prev, pose) : control::deviation_from_segment(prev, pose);
    if (dev) dev->lateral_m *= vnhv_m_per_unit_;  // segment units -> m
    return dev;
  };
  if (prior) {
    tel.vnhv_fix_d2 = fix ? fix->prior_d2 : kNaN;
    tel.vnhv_fix_weight = fix ? fix_weight : kNaN;
    if (fix) {  // the gate's terms, in metres (control::locate_in_segment's d2)
      tel.vnhv_gate_dx_m = (fix->pose.x_m - prior->pose.x_m) * vnhv_m_per_unit_;
      tel.vnhv_gate_dy_m = (fix->pose.y_m - prior->pose.y_m) * vnhv_m_per_unit_;
      tel.vnhv_gate_dyaw_rad =
          std::remainder(fix->pose.yaw_rad - prior->pose.yaw_rad, 2.0 * std::numbers::pi);
      tel.vnhv_gate_sigma_x_m = prior->sigma_x * vnhv_m_per_unit_;
      tel.vnhv_gate_sigma_y_m = prior->sigma_y * vnhv_m_per_unit_;
      tel.vnhv_gate_sigma_yaw_rad = prior->sigma_yaw_rad;
    }
    if (const auto dev = deviation_of(prior->pose)) {
      tel.odom_lateral_m = dev->lateral_m;
      tel.odom_heading_rad = dev->heading_rad;
    }
    tel.odom_lateral_sigma_m = lateral_sigma_m();
    tel.odom_heading_sigma_rad = heading_sigma_rad();
  }
  if (fix && !fix->within_prior) {
    if (const auto dev = deviation_of(fix->pose)) {
      tel.vnhv_fix_lateral_m = dev->lateral_m;
      tel.vnhv_fix_heading_rad = dev->heading_rad;
    }
  }
  if (fix && fix->within_prior && fix_weight > 0.0) {
    // With odometry, the estimate takes the fix first: its update also says how likely the
    // segment's fixes are the room's rather than a moved object's (fix_error_mixture.hpp).
    double room_probability = 1.0;
    if (odom_ && tracker_.usable()) {
      // The fix is the robot's pose in IN's frame, in segment units: in metres, from IN's taught
      // pose, it is where the robot is on the taught path.
      const OdometryPose in_next{fix->pose.x_m * vnhv_m_per_unit_, fix->pose.y_m * vnhv_m_per_unit_,
                                 fix->pose.yaw_rad};
      const OdometryPose fix_teach = compose(tracker_.taught(seg.next), in_next);
      if (!tracker_.estimate()) {
        fix_correction_ = tracker_.correct(fix_teach);
      } else {
        // Per axis of the robot, against the error this segment's fixes share.
        const OdometryPose y = between(*tracker_.estimate(), fix_teach);
        fix_correction_ = std::make_pair(std::hypot(y.x_m, y.y_m), std::abs(y.yaw_rad));
        const Axes3 d = errors_.update(FixSource::kVnhv, {y.x_m, y.y_m, y.yaw_rad}, fix_weight);
        tracker_.shift(OdometryPose{d[0], d[1], d[2]});
        room_probability = errors_.model(FixSource::kVnhv).usual_probability();
        tel.vnhv_fix_room_probability = room_probability;
      }
      // A segment whose fixes are more likely a moved object's did not locate the robot.
      if (room_probability >= 0.5) {
        if (seg.next + 1 == static_cast<int>(map_.key_images.size())) {
          final_fix_.emplace(in_next, tel.t_ns);
        }
        odom_since_fix_m_ = 0.0;
        fixed_this_frame_ = true;
        if (drift_report_pending_) {
          // The first fix after a blind stretch: how far the odometry had drifted.
          tel.drift_corrected_m = fix_correction_->first;
          tel.drift_corrected_rad = fix_correction_->second;
          drift_report_pending_ = false;
        }
      }
    }
    const bool room = room_probability >= 0.5;
    if (room) {
      // Past IN: beyond the normal through IN to the arc's tangent there (+x), or to the chord.
      past_next =
          arc ? fix->pose.x_m > 0.0 : prev.x_m * fix->pose.x_m + prev.y_m * fix->pose.y_m < 0.0;
    }
    if (auto dev = deviation_of(fix->pose)) {
      tel.vnhv_fix_lateral_m = dev->lateral_m;
      tel.vnhv_fix_heading_rad = dev->heading_rad;
      if (room) vnhv_filter_.correct(*dev, tel.t_ns, fix_weight * room_probability);
    }
  }
  const auto est = vnhv_filter_.estimate(tel.t_ns);
  if (!est) return std::nullopt;
  tel.vnhv_lateral_m = est->lateral_m;
  tel.vnhv_heading_rad = est->heading_rad;
  // Past IN (the switch to the next segment comes later) the line IP -> IN leads straight on
  // while a taught corner turns: IBVS, which looks at IN and INN, drives until the switch.
  // Measured (robotics_room, QVGA): without this the robot drove 0.5 m past a corner's IN and
  // hit a desk.
  if (past_next) return std::nullopt;
  const double v = has_command_ ? last_command_.v_m_s : options_.schedule.v_straight_m_s;
  return control::vnhv_omega(v, est->lateral_m, est->heading_rad, o, vnhv_curvature_1_m_);
}

void Navigator::check_frame(const Frame& frame) const {
  if (frame.gray.empty() || frame.gray.type() != CV_8UC1) {
    throw std::invalid_argument("Navigator::step: frame " + std::to_string(frame.index) +
                                " is not a non-empty CV_8UC1 image");
  }
  if (frame.gray.cols != map_.camera.width_px || frame.gray.rows != map_.camera.height_px) {
    std::ostringstream os;
    os << "Navigator::step: frame " << frame.index << " is " << frame.gray.cols << "x"
       << frame.gray.rows << ", the map's images are " << map_.camera.width_px << "x"
       << map_.camera.height_px;
    throw std::invalid_argument(os.str());
  }
  if (last_t_ns_ && frame.t_ns < *last_t_ns_) {
    throw std::invalid_argument("Navigator::step: t_ns " + std::to_string(frame.t_ns) +
                                " is before the previous frame's " + std::to_string(*last_t_ns_));
  }
}

void Navigator::account_commanded_motion(int64_t t_ns) {
  if (last_t_ns_ && has_command_ && !last_command_.stop) {
    // The command sent after the previous frame drove the robot until now (blind switches).
    const double dt_s = static_cast<double>(t_ns - *last_t_ns_) * 1e-9;
    segment_driven_m_ += last_command_.v_m_s * dt_s;
  }
  last_t_ns_ = t_ns;
}

features::FrameMatcher Navigator::perceive(const Frame& frame, bool for_localisation,
                                           Telemetry& tel) {
  const auto t0 = Clock::now();
  unsigned parts = features::kPartsCurrentFrame;
  // ORB keypoints: for the initial localisation now; with the ORB fallback, when a match first
  // needs them (most frames verify enough KLT points and never do).
  if (for_localisation) parts |= features::kPartWideBaseline;
  const bool orb_fallback =
      options_.matcher.orb_fallback_below_points > 0 && options_.matcher.match_points;
  features::FrameMatcher fm(extractor_.extract(frame.gray, parts), options_.matcher,
                            orb_fallback ? &extractor_ : nullptr);
  for (auto& [i, start] : klt_starts_) {
    fm.set_klt_prior(i, std::move(start.prior), std::move(start.skip));
  }
  klt_starts_.clear();
  tel.timings.extract_ms = ms_since(t0);
  return fm;
}

Navigator::SegmentEvidence Navigator::associate(features::FrameMatcher& fm, Telemetry& tel) {
  const localization::Segment seg = switcher_->segment();
  ensure_pyramids(seg);
  // IN and INN are matched on every frame (the counts below, control): as concurrent tasks
  // (FrameMatcher::compute_two_views; the same results as one after the other). IP is needed
  // on most frames too (n(IP, Ia) and the three-view counts of the lazy rules below: 1,600 of
  // 2,437 frames of a white_corridor replay, QVGA); where the tasks do run concurrently it is
  // matched with them instead of after them (on the other frames, work for nothing), held back
  // until the rules ask for it (else remember_tracks would keep priors for IP that the
  // sequential step does not keep, and the next frame's IP tracks would differ).
  if (seg.next_next) {
    const features::FrameMatcher::KeyRef keys[] = {{seg.next, &key(seg.next)},
                                                   {*seg.next_next, &key(*seg.next_next)},
                                                   {seg.prev, &key(seg.prev), true}};
    fm.compute_two_views(keys);
  }
  const features::TwoViewMatches& tv_n = fm.two_view(seg.next, key(seg.next));
  tel.n_lines_next = tv_n.n_lines();
  tel.n_points_next = tv_n.n_points();
  SegmentEvidence ev;
  localization::SwitchCounts& counts = ev.counts;
  counts.two_view_next = tv_n.total();
  counts.blind_switch_allowed = blind_switch_allowed();
  const int min_points =
      seg.next_next ? options_.min_scale_points : options_.arrival_min_scale_points;
  if (const auto ratio = scale_ratio(fm.two_view_for_control(seg.next, key(seg.next)),
                                     key(seg.next), fm.current(), min_points)) {
    counts.next_scale_ratio = *ratio;
    tel.next_scale_ratio = *ratio;
  }
  // Odometry along the taught path (when the frame and the map have it): past IN?
  std::optional<double> odom_progress;
  double past_next_m = kNaN;  // the estimate's distance along the taught path past IN
  if (odom_ && tracker_.usable()) {
    if (const auto d = tracker_.deviation()) {
      odom_progress = d->progress;
      past_next_m = d->s_m - tracker_.length_to_m(seg.next);
      // The progress ends at the final key image; past it, the estimate's coordinate along the
      // final taught pose says how far (arrival, below).
      if (!seg.next_next && seg.next == tracker_.key_count() - 1) {
        past_next_m = between(tracker_.taught(seg.next), *tracker_.estimate()).x_m;
      }
      tel.odom_past_next_m = past_next_m;
      tel.odom_along_sigma_m = along_sigma_m();
    }
  }
  if (odom_progress) tel.odom_progress = *odom_progress;
  const bool odom_passed_next = odom_progress && *odom_progress >= seg.next;
  // "Passed IN by travel" (one rule, two sources): while IN's scale is unknown, how far the robot
  // went says whether it is past IN. The odometry carried along the taught path when the frames
  // and the map have it (bit 32); otherwise the distance commanded since the switch against
  // kPassedByCommandsFactor x the segment's taught length (bit 16). The commanded distance is not
  // consulted where odometry exists: off there, the generated set kept 80/80 and its lateral RMS
  // went down (docs/method/navigator.md, session 22 ablation).
  const bool has_odometry = odom_ && tracker_.usable();
  // Where the scale ratio is known but has not said "passed" (it hardly changes over tens of
  // centimetres when IN's points are metres away), the estimate must be past IN by
  // kPassedSigmas x its sigma along the robot: P(passed) >= 0.98 (gen_room_1, VGA: the robot
  // drove 0.49 m past IN with the odometry estimate within 1 cm of the truth, then turned late).
  counts.passed_by_odometry =
      odom_passed_next && (std::isnan(counts.next_scale_ratio) ||
                           past_next_m >= kPassedSigmas * along_sigma_m());
  // The counterpart: the estimate still kPassedSigmas x its sigma before IN blocks the paper's
  // count rules. Measured (gen_room_7, QVGA, run 1): in a turn taught with key images 2-4 cm
  // apart the count rules switched 9 and 25 cm before IN (the scale ratio 0.93-0.95, above
  // the guard), and the robot turned early: 5.1 / 15.5 cm lateral RMS / max -> 3.2 / 7.5 cm.
  counts.before_by_odometry =
      has_odometry && past_next_m <= -kPassedSigmas * along_sigma_m();  // NaN: false
  if (!has_odometry && seg.next_next && segment_from_switch_ &&
      std::isnan(counts.next_scale_ratio)) {
    counts.passed_by_distance = segment_driven_m_ >= kPassedByCommandsFactor * segment_taught_m();
  }
  if (seg.next_next) {
    const int nn = *seg.next_next;
    const features::TwoViewMatches& tv_nn = fm.two_view(nn, key(nn));  // control needs it too
    tel.n_lines_next_next = tv_nn.n_lines();
    tel.n_points_next_next = tv_nn.n_points();
    counts.two_view_next_next = tv_nn.total();
    // Lazy evaluation (same decisions as computing everything, see KeyImageSwitcher): when
    // the scale guard blocks, the paper's rules do not matter; n(IP, Ia) matters only if
    // n(Ia, INN) > n(Ia, IN); the three-view counts only if the two-view rule fails.
    const auto& sw = options_.switching;
    const bool guard_blocks = counts.before_by_odometry ||
                              (sw.min_next_scale_ratio > 0.0 &&
                               counts.next_scale_ratio < sw.min_next_scale_ratio);  // NaN: false
    if (!guard_blocks) {
      bool two_view_rule = false;
      if (counts.two_view_next_next > counts.two_view_next) {
        tel.n_prev = fm.two_view(seg.prev, key(seg.prev)).total();
        counts.two_view_prev = tel.n_prev;
        two_view_rule = counts.two_view_next_next > counts.two_view_prev;
      }
      if (!two_view_rule) {
        counts.three_view_next = fm.three_view(seg.next, key(seg.next), nn, key(nn)).total();
        counts.three_view_prev =
            fm.three_view(seg.prev, key(seg.prev), seg.next, key(seg.next)).total();
        tel.n_three_view_next = counts.three_view_next;
        tel.n_three_view_prev = counts.three_view_prev;
      }
    }
  } else {
    const double ratio = counts.next_scale_ratio;
    if (final_ratio_in_ != seg.next) {
      final_ratio_in_ = seg.next;
      final_best_ratio_ = std::numeric_limits<double>::quiet_NaN();
    }
    if (!std::isnan(ratio) && !(ratio <= final_best_ratio_)) final_best_ratio_ = ratio;
    // Without odometry (map or frames), the final image that fades after it was nearly reached
    // is arrival (kArrivalFadeRatio); with odometry, the odometry says (below).
    const bool faded = !has_odometry && std::isnan(ratio) &&
                       final_best_ratio_ >= kArrivalFadeRatio;  // NaN: false
    // The odometry carried past the final image's taught pose is arrival too, where the image
    // cannot say (dead reckoning, or no scale ratio: too few points), as "passed IN by odometry"
    // is for a switch. Measured (gen_building_12, QVGA, both runs): the final view kept 3-5 lines
    // and no point, and the robot drove 0.35-0.39 m past the end before dead reckoning stopped it.
    // Where the image says "not yet", the estimate at the final pose is arrival as well: the end
    // error is symmetric (too early costs as much as too late), so the best estimate decides,
    // not a margin of sigmas as for a switch (an early switch turns early). The final view's
    // scale ratio from its 13-19 points read 0.87-0.94 (25 % quantile) and 1.00-1.04 (median)
    // within 0.1 m of the end (robotics_room furniture run 1, VGA, planar essential model),
    // the estimate 1-2 cm from the truth.
    const bool odometry_there = odom_passed_next && (state_ == NavState::kDeadReckoning ||
                                                     std::isnan(ratio) || past_next_m >= 0.0);
    ev.reached_final =
        ratio >= options_.arrival_scale_ratio || faded || odometry_there;  // NaN: false
  }
  return ev;
}

void Navigator::switch_key_images(const SegmentEvidence& ev, int64_t t_ns, StepFacts& facts,
                                  Telemetry& tel) {
  const localization::SwitchUpdate u = switcher_->update(ev.counts, ev.reached_final);
  tel.switch_streak = u.streak;
  tel.switch_criterion = u.criteria_bits;
  tel.switched = u.event == localization::SwitchEvent::kSwitched;
  if (tel.switched) correct_along_from_switch(u.criteria_bits, tel);
  facts.final_reached = u.event == localization::SwitchEvent::kTourComplete;
  facts.switched = tel.switched;
  facts.overdue = !facts.switched && segment_overdue(t_ns);
}

std::optional<double> Navigator::control(features::FrameMatcher& fm, Telemetry& tel) {
  std::optional<double> omega;
  // Teaching turned here without moving: so does the replay (v = 0 in take(), omega below).
  // Measured (gen_building_3, QVGA, run 1): on a 90-degree spot turn seen with 1-5 lines, IBVS
  // turned at the schedule's speed and drove 0.2 m past the turn, then 24 m with a 43 cm offset
  // to a wrong end.
  on_taught_spot_turn_ = false;
  if (odom_ && tracker_.usable() && tracker_.estimate()) {
    const std::optional<PathDeviation> d = tracker_.deviation();
    on_taught_spot_turn_ = d && d->in_place;
  }
  fixed_this_frame_ = false;
  if (options_.controller == ControllerKind::kVnhv) omega = vnhv_omega(fm, tel);
  if (!fixed_this_frame_ && odom_ && tracker_.usable() && tracker_.estimate() && switcher_) {
    // No VNHV fix: the lines matched with IN correct the odometry estimate, heading first.
    const int in = switcher_->segment().next;
    const auto pairs = line_pairs_with(fm, in);
    correct_heading_from_lines(pairs, in, tel);
    correct_position_from_floor_lines(pairs, in, tel);
  }
  if (!omega) {
    omega = ibvs_omega(fm, tel);  // VNHV falls back to IBVS without two-view geometry
    if (omega && options_.controller == ControllerKind::kVnhv && odometry_steers()) {
      // VNHV has no estimate on this segment but the image still has features (IBVS has a
      // demand), and a vision fix is at most odometry_steer_max_m of odometry behind: the same
      // law on the odometry's deviation from the taught path steers instead of IBVS. (No
      // usable feature at all: no demand, the transition table's dead reckoning.)
      bool on_the_spot = false;
      omega = odometry_demand(on_the_spot);
      tel.odometry_steered = true;
    }
  }
  if (omega && on_taught_spot_turn_ && !tel.odometry_steered) {
    // Neither law is made for a turn without translation (VNHV's needs v > 0; IBVS, with the
    // few features a turn's view often keeps, may see no heading error and leave the robot
    // standing: gen_building_3 run 1 stood until the segment was overdue): the odometry turns
    // to the piece's taught end heading, as in dead reckoning; vision takes over after it.
    bool on_the_spot = false;
    omega = odometry_demand(on_the_spot);
    tel.odometry_steered = true;
  }
  {  // display only; the control law above already computed (and cached) these matches
    const int in = switcher_->segment().next;
    tel.overlay = features::matched_overlay(fm.two_view_for_control(in, key(in)), fm.current(), in);
  }
  return omega;
}

void Navigator::report_arrival(int64_t t_ns, Telemetry& tel) const {
  std::optional<OdometryPose> at;
  if (final_fix_ && t_ns - final_fix_->second <= kArrivalFixMaxAgeNs) {
    at = final_fix_->first;
    tel.arrival_source = Telemetry::ArrivalSource::kVision;
  } else if (tracker_.usable() && tracker_.estimate()) {
    at = between(tracker_.taught(tracker_.key_count() - 1), *tracker_.estimate());
    tel.arrival_source = Telemetry::ArrivalSource::kOdometry;
  }
  if (!at) return;
  tel.arrival_along_m = at->x_m;
  tel.arrival_lateral_m = at->y_m;
  tel.arrival_heading_rad = at->yaw_rad;
}

Command Navigator::take(const Transition& t, int64_t t_ns, std::optional<double> demand,
                        Telemetry& tel) {
  const NavState before = state_;
  if (!t.keeps_state) state_ = t.to;
  switch (t.action) {
    case Action::kStopTourComplete:
      schedule_.reset();
      report_arrival(t_ns, tel);
      return stop_command(StopReason::kTourComplete);
    case Action::kStopOverdue:
      schedule_.reset();
      has_command_ = false;
      return stop_command(StopReason::kSegmentOverdue);
    case Action::kStopNotLocalised:
      return stop_command(StopReason::kNotLocalized);
    case Action::kStopFeaturesLost:
      return stop_command(StopReason::kFeaturesLost);
    case Action::kBeginSegment:
      if (t.phase == Phase::kLocalise) {
        begin_segment(t_ns, /*from_switch=*/false);
        final_ratio_in_ = -1;  // a new segment: no ratio seen on it yet
      } else {
        ensure_pyramids(switcher_->segment());
        begin_segment(t_ns, /*from_switch=*/true);
        tracker_.advance_to(switcher_->segment().prev);
      }
      return {};
    case Action::kContinue:
      return {};
    case Action::kDrive: {
      tel.omega_demand_rad_s = *demand;
      const control::BaseCommand b = schedule_.step(*demand, t_ns);
      Command cmd;
      cmd.v_m_s = on_taught_spot_turn_ ? 0.0 : b.v_m_s;
      cmd.omega_rad_s = b.omega_rad_s;
      cmd.stop = false;
      cmd.reason = StopReason::kNone;
      tel.turning = b.turning;
      last_command_ = cmd;
      last_good_t_ns_ = t_ns;
      has_command_ = true;
      if (before == NavState::kDeadReckoning) {
        tel.reacquired = true;
        tel.dead_reckoned_m = blind_m_;
        tel.dead_reckoned_rad = blind_rad_;
        drift_report_pending_ = true;
      }
      blind_m_ = blind_rad_ = 0.0;
      return cmd;
    }
    case Action::kDeadReckon:
      if (before != NavState::kDeadReckoning) blind_m_ = blind_rad_ = 0.0;
      drift_report_pending_ = false;
      return dead_reckon(t_ns, tel);
    case Action::kHold:
      tel.hold_elapsed_ns = t_ns - last_good_t_ns_;
      tel.turning = schedule_.turning();
      return last_command_;
    case Action::kLose:
      tel.hold_elapsed_ns = has_command_ ? t_ns - last_good_t_ns_ : 0;
      if (before == NavState::kDeadReckoning) {
        tel.dead_reckoned_m = blind_m_;
        tel.dead_reckoned_rad = blind_rad_;
      }
      blind_m_ = blind_rad_ = 0.0;
      schedule_.reset();
      has_command_ = false;
      vnhv_segment_next_ = -1;
      return stop_command(StopReason::kFeaturesLost);
  }
  return stop_command(StopReason::kFeaturesLost);
}

void Navigator::follow_odometry(const Frame& frame) {
  fix_correction_.reset();
  if (!frame.odom) {
    // A frame without odometry: no dead reckoning on it; the next reading carries the estimate
    // over the gap (odometry is a pose, not an increment).
    odom_.reset();
    return;
  }
  if (odom_) {
    const OdometryPose d = between(*odom_, *frame.odom);
    const double moved_m = std::hypot(d.x_m, d.y_m);
    odom_since_fix_m_ += moved_m;
    if (state_ == NavState::kDeadReckoning) {
      blind_m_ += moved_m;
      blind_rad_ += std::abs(d.yaw_rad);
    }
    // The odometry's heading error grows with every turn and every metre (systematic errors:
    // their bounds add up linearly).
    const double d_along = kOdometryDistanceErrorPerM * moved_m;
    const double d_lateral = heading_sigma_rad() * moved_m;
    const double d_heading =
        kOdometryYawErrorPerRad * std::abs(d.yaw_rad) + kOdometryYawErrorPerM * moved_m;
    errors_.grow({d_along, d_lateral, d_heading});
  }
  tracker_.predict(*frame.odom);
  odom_ = frame.odom;
}

bool Navigator::can_dead_reckon() const {
  return odom_ && tracker_.usable() && tracker_.estimate() && switcher_ &&
         errors_.grown()[1] <= options_.dead_reckoning_max_lateral_sigma_m;
}

double Navigator::odometry_demand(bool& on_the_spot) {
  const PathDeviation d = *tracker_.deviation();
  const double max_omega = options_.schedule.max_omega_rad_s;
  double demand = 0.0;
  on_the_spot = d.in_place;
  if (d.in_place) {
    demand = kTurnGain_1_s * d.remaining_turn_rad;
  } else if (std::abs(d.heading_rad) > kTurnFirstRad) {
    on_the_spot = true;  // facing well off the path (past a turn): turn back to it first
    demand = -kTurnGain_1_s * d.heading_rad;
  } else {
    const double v = has_command_ && last_command_.v_m_s > 0.0 ? last_command_.v_m_s
                                                               : options_.schedule.v_turn_m_s;
    const auto w =
        control::vnhv_omega(v, d.lateral_m, d.heading_rad, options_.vnhv, d.curvature_1_m);
    demand = w ? *w : -kTurnGain_1_s * d.heading_rad;
  }
  return std::clamp(demand, -max_omega, max_omega);
}

Navigator::LinePairs Navigator::line_pairs_with(features::FrameMatcher& fm, int key_index) {
  const features::ImageFeatures& k = key(key_index);
  const features::TwoViewMatches& tv = fm.two_view(key_index, k);  // cached: the switching's own
  LinePairs pairs;
  pairs.reserve(tv.lines.size());
  for (const features::LineMatch& m : tv.lines) {
    const features::LineSegment& a = k.lines[static_cast<size_t>(m.idx_a)];
    const features::LineSegment& b = fm.current().lines[static_cast<size_t>(m.idx_b)];
    pairs.push_back({{a.p0_norm, a.p1_norm}, {b.p0_norm, b.p1_norm}});
  }
  return pairs;
}

void Navigator::correct_heading_from_lines(const LinePairs& pairs, int in, Telemetry& tel) {
  const FixErrorMixture& model = errors_.model_for(FixSource::kLineYaw, in);
  // Only line structures where the room's lines are expected compete (a moved shelf's boards
  // are as horizontal as the skirting; line_yaw.hpp): the room hypothesis's expectation.
  const double estimate_in_rad =
      std::remainder(tracker_.estimate()->yaw_rad - tracker_.taught(in).yaw_rad, 2.0 * M_PI);
  const geometry::YawPrior prior{
      estimate_in_rad + model.expected()[2],
      std::max(std::sqrt(model.expected_var()[2]), kMinLineYawSigmaRad)};
  const auto yaw = geometry::estimate_line_yaw(pairs, options_.matcher.essential.camera_pitch_rad,
                                               geometry::LineYawOptions{}, &prior);
  if (!yaw) return;
  tel.line_yaw_rad = yaw->yaw_rad;
  // The update weighs the room's small shared error against a moved object's large one
  // (kLineYawErrors); a yaw less sure than the floor weighs less (its weight divides the noise).
  const double sigma_r = std::max(yaw->sigma_rad, kMinLineYawSigmaRad);
  const double weight = std::pow(kMinLineYawSigmaRad / sigma_r, 2);
  const double innovation_rad = std::remainder(yaw->yaw_rad - estimate_in_rad, 2.0 * M_PI);
  // A yaw beyond kHeadingGateSigmas of where the room's is expected is one frame's outlier (a
  // mismatched or non-horizontal line the estimator's consensus kept, often with 1-5 lines in a
  // turn), not a segment's shared error: it is not taken, and not weighed as evidence either.
  const double expected_rad = model.expected()[2];
  const double gate_var = model.expected_var()[2] + sigma_r * sigma_r;
  if (std::pow(innovation_rad - expected_rad, 2) >
      kHeadingGateSigmas * kHeadingGateSigmas * gate_var) {
    return;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double move_rad =
      errors_.update(FixSource::kLineYaw, {nan, nan, innovation_rad}, weight)[2];
  tracker_.shift(OdometryPose{0.0, 0.0, move_rad});
  tel.line_yaw_correction_rad = move_rad;
  tel.line_yaw_room_probability = model.usual_probability();
}

void Navigator::correct_position_from_floor_lines(const LinePairs& pairs, int in, Telemetry& tel) {
  if (pairs.size() < 2) return;
  // The robot in IN's taught frame; the floor frames are the optical centres', `ahead` of the
  // base's rotation axis: t_cam = t_base + (R(yaw) - I) (ahead, 0).
  const OdometryPose rel = between(tracker_.taught(in), *tracker_.estimate());
  const double pitch_rad = options_.matcher.essential.camera_pitch_rad;
  const geometry::CameraOnBase mount = geometry::pepper_top_camera(pitch_rad);
  const Eigen::Vector2d ahead(mount.forward_m, 0.0);
  const Eigen::Rotation2Dd R(rel.yaw_rad);
  const Eigen::Vector2d lever = R * ahead - ahead;
  geometry::FloorPrior prior;
  prior.t_m = Eigen::Vector2d(rel.x_m, rel.y_m) + lever;
  prior.yaw_rad = rel.yaw_rad;
  prior.yaw_sigma_rad = heading_sigma_rad();
  // The estimate's sigmas are along and across the robot, turned by rel.yaw from IN's axes.
  const Eigen::Matrix2d R_m = R.toRotationMatrix();
  const Eigen::Vector2d var(std::pow(along_sigma_m(), 2), std::pow(lateral_sigma_m(), 2));
  prior.cov_m2 = R_m * var.asDiagonal() * R_m.transpose();
  // Only floor lines where the room's are expected compete (a moved bench's foot is a floor line
  // too): the room hypothesis's expectation (kFloorErrors).
  const FixErrorMixture& model = errors_.model_for(FixSource::kFloorLines, in);
  prior.t_m.y() += model.expected()[1];
  prior.cov_m2(1, 1) += model.expected_var()[1] - var(1);
  // The lateral position only: lines along IN's view (floor-wall edges, skirtings); what lines
  // across it would say about the position along (kFloorLineMaxAngleRad) is not taken.
  geometry::FloorLineOptions lo;
  lo.max_angle_to_forward_rad = kFloorLineMaxAngleRad;
  const auto fix = geometry::estimate_floor_position(
      pairs, geometry::FloorCamera{mount.height_m, pitch_rad}, prior, lo);
  if (!fix) return;
  // What the lines alone say of IN's lateral axis (y), the along one (x) held at the prior:
  // their information and information vector (the fix is the prior and the lines together).
  const Eigen::Matrix2d& info = fix->info_1_m2;
  if (!(info(1, 1) > 0.0)) return;
  const double lines_y_m = (fix->info_vec_1_m.y() - info(1, 0) * prior.t_m.x()) / info(1, 1);
  const double lines_var_m2 = 1.0 / info(1, 1);
  tel.floor_lines = fix->inliers;
  tel.floor_lateral_before_m = rel.y_m;
  tel.floor_lateral_lines_m = lines_y_m - lever.y();
  tel.floor_lateral_lines_sigma_m = std::sqrt(lines_var_m2);
  // Against the room's or a moved object's shared error (kFloorErrors), on the robot's across
  // axis (IN's, turned by rel.yaw: small on the straight segments where floor lines are used).
  const double noise_m = kFloorErrors.noise_sigma[1];
  const double weight = std::min(1.0, noise_m * noise_m / lines_var_m2);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double innovation_m = (lines_y_m - (rel.y_m + lever.y())) * std::cos(rel.yaw_rad);
  const double move_m = errors_.update(FixSource::kFloorLines, {nan, innovation_m, nan}, weight)[1];
  tracker_.shift(OdometryPose{0.0, move_m, 0.0});
  tel.floor_lateral_after_m = between(tracker_.taught(in), *tracker_.estimate()).y_m;
  tel.floor_room_probability = model.usual_probability();
  // The room's lines located the robot across the path: the odometry may steer
  // (odometry_steers), as after a VNHV fix.
  if (lateral_sigma_m() <= kLocatedLateralSigmaM && model.usual_probability() >= 0.5) {
    odom_since_fix_m_ = 0.0;
  }
}

void Navigator::correct_along_from_switch(int criteria_bits, Telemetry& tel) {
  constexpr int kPaperRules = static_cast<int>(localization::SwitchCriterion::kBoth);
  constexpr int kByTravel =
      localization::kCriterionPassedByOdometry | localization::kCriterionPassedByDistance;
  if (!(criteria_bits & kPaperRules) || (criteria_bits & kByTravel)) return;
  if (!odom_ || !tracker_.usable() || !tracker_.estimate()) return;
  if (errors_.begun(FixSource::kSwitch)) return;  // one per placement (kSwitchErrors)
  const int in = switcher_->segment().prev;  // the IN the robot just reached
  errors_.model_for(FixSource::kSwitch, in);
  // IN's taught pose in the robot's frame: its x is how far the estimate is before IN.
  const OdometryPose rel = between(*tracker_.estimate(), tracker_.taught(in));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double move_m = errors_.update(FixSource::kSwitch, {rel.x_m, nan, nan}, 1.0)[0];
  tracker_.shift(OdometryPose{move_m, 0.0, 0.0});
  tel.switch_along_correction_m = move_m;
}

std::optional<control::PosePrior> Navigator::resection_prior(int in) const {
  if (!odom_ || !tracker_.usable() || !tracker_.estimate() || !(vnhv_m_per_unit_ > 0.0)) {
    return std::nullopt;
  }
  // Where the estimate puts the robot in IN's taught frame, in segment units; the camera's own
  // offset ahead of the base changes that by under a centimetre at the segments' yaws.
  // The next fix is expected at the estimate plus the error this segment's fixes share so far.
  const FixErrorMixture& fixes = errors_.model(FixSource::kVnhv);
  const Axes3 shared = fixes.expected();
  const OdometryPose expected =
      compose(*tracker_.estimate(), OdometryPose{shared[0], shared[1], shared[2]});
  const OdometryPose p = between(tracker_.taught(in), expected);
  control::PosePrior prior;
  prior.pose = {p.x_m / vnhv_m_per_unit_, p.y_m / vnhv_m_per_unit_, p.yaw_rad};
  // The estimate's sigmas are along and across the robot; IN's axes are turned by p.yaw_rad from
  // them (the small correlation this leaves out does not matter at a gate).
  const double c2 = std::pow(std::cos(p.yaw_rad), 2), s2 = 1.0 - c2;
  const Axes3 var = fixes.expected_var();
  const double var_along = var[0], var_lateral = var[1];
  prior.sigma_x = std::sqrt(c2 * var_along + s2 * var_lateral) / vnhv_m_per_unit_;
  prior.sigma_y = std::sqrt(s2 * var_along + c2 * var_lateral) / vnhv_m_per_unit_;
  prior.sigma_yaw_rad = std::sqrt(var[2]);
  return prior;
}

bool Navigator::odometry_steers() const {
  return odom_ && tracker_.usable() && tracker_.estimate() && switcher_ &&
         odom_since_fix_m_ < options_.odometry_steer_max_m;
}

Command Navigator::dead_reckon(int64_t t_ns, Telemetry& tel) {
  bool on_the_spot = false;
  const double demand = odometry_demand(on_the_spot);
  tel.omega_demand_rad_s = demand;
  const control::BaseCommand b = schedule_.step(demand, t_ns);
  Command cmd;
  cmd.v_m_s = on_the_spot ? 0.0 : b.v_m_s;
  cmd.omega_rad_s = b.omega_rad_s;
  cmd.stop = false;
  cmd.reason = StopReason::kNone;
  tel.turning = b.turning;
  tel.dead_reckoned_m = blind_m_;
  tel.dead_reckoned_rad = blind_rad_;
  last_command_ = cmd;
  has_command_ = true;
  return cmd;
}

// One frame: a pipeline of stages, with the decisions taken from the transition table
// (transitions.hpp) at four points. docs/method/navigator.md "One frame".
StepResult Navigator::step(const Frame& frame) {
  const auto t_start = Clock::now();
  check_frame(frame);
  account_commanded_motion(frame.t_ns);
  follow_odometry(frame);
  StepResult out;
  Telemetry& tel = out.telemetry;
  tel.t_ns = frame.t_ns;
  tel.frame_index = frame.index;
  StepFacts facts;
  auto finish = [&](const Command& c) {
    out.command = c;
    tel.state = state_;
    tel.reason = c.reason;
    if (switcher_) {
      const auto& seg = switcher_->segment();
      tel.ip = seg.prev;
      tel.in = seg.next;
      tel.inn = seg.next_next.value_or(-1);
    }
    if (odom_ && tracker_.usable() && tracker_.estimate()) {
      tel.odom_lateral_sigma_grown_m = errors_.grown()[1];
      if (std::isnan(tel.odom_lateral_sigma_m)) {
        tel.odom_lateral_sigma_m = lateral_sigma_m();
        tel.odom_heading_sigma_rad = heading_sigma_rad();
      }
    }
    tel.timings.total_ms = ms_since(t_start);
    return out;
  };
  if (const Transition* t = decide(Phase::kEntry, state_, facts)) {
    return finish(take(*t, frame.t_ns, std::nullopt, tel));
  }
  // 1. Perceive (2. and localise when there is no segment).
  const bool localising = decide(Phase::kLocalise, state_, facts) != nullptr;
  features::FrameMatcher fm = perceive(frame, localising, tel);
  // The matching split in the telemetry: whatever the FrameMatcher did by then.
  const auto split = [&] {
    const features::MatchTimings& m = fm.timings();
    tel.timings.lines_ms = m.lines_ms;
    tel.timings.klt_ms = m.klt_ms;
    tel.timings.essential_ms = m.essential_ms;
    tel.timings.three_view_ms = m.three_view_ms;
    tel.timings.wide_baseline_ms = m.wide_baseline_ms;
  };
  if (localising) {
    facts.localised = localize(fm, tel);
    const Transition& t = *decide(Phase::kLocalise, state_, facts);
    const Command c = take(t, frame.t_ns, std::nullopt, tel);
    if (t.action != Action::kBeginSegment) {
      split();
      return finish(c);
    }
  }
  // 3. Associate with the segment's key images; 4. switch key images.
  auto t0 = Clock::now();
  switch_key_images(associate(fm, tel), frame.t_ns, facts, tel);
  if (const Transition& t = *decide(Phase::kSegment, state_, facts);
      t.action != Action::kContinue) {
    const Command c = take(t, frame.t_ns, std::nullopt, tel);
    if (t.action != Action::kBeginSegment) {
      tel.timings.match_ms = ms_since(t0);
      split();
      return finish(c);
    }
  }
  // 5. Control on the (possibly new) segment; 6. speed, hold or stop.
  const std::optional<double> demand = control(fm, tel);
  tel.timings.match_ms = ms_since(t0);
  t0 = Clock::now();
  facts.has_demand = demand.has_value();
  facts.within_hold =
      has_command_ && frame.t_ns - last_good_t_ns_ <= std::llround(options_.hold_s * 1e9);
  facts.can_dead_reckon = !demand && can_dead_reckon();
  const Command cmd = take(*decide(Phase::kControl, state_, facts), frame.t_ns, demand, tel);
  tel.timings.control_ms = ms_since(t0);
  remember_tracks(fm);
  split();
  finish(cmd);
  if (state_ == NavState::kLost) {
    // Keep the last segment in telemetry for this frame, then forget it (relocalise next).
    switcher_.reset();
    klt_starts_.clear();
  }
  return out;
}

}  // namespace pepper::core::navigator
