#pragma once
// The per-frame replay state machine: one call per frame, returning the base command and a
// telemetry record (ARCHITECTURE.md: frames with timestamps in, commands and telemetry out).
// It ties together features (core/features), localisation and switching (core/localization)
// and the control laws (core/control); METHOD.md "Replay".
//
// States:
//   kNotLocalized  no segment yet: every frame runs initial localisation (initial_localizer.hpp);
//                  command: stop (reason kNotLocalized) until it succeeds.
//   kNavigating    segment (IP, IN, INN) known: counts for switching, control law, command.
//   kHolding       the control law has no usable feature (too few verified matches with IN):
//                  the last command is held for at most `hold_s` (measured with frame stamps).
//   kDeadReckoning no usable feature either, but the frame carries odometry (Frame::odom), the
//                  map its key images' taught poses (KeyImage::odom) and the robot's place on
//                  the taught path is known: the taught path is driven on odometry
//                  (path_tracker.hpp) while matching goes on every frame; vision takes over
//                  again as soon as the control law has features, and the switcher advances
//                  when odometry passes IN. Bounded by dead_reckoning_max_lateral_sigma_m.
//   kLost          the hold (or the dead reckoning) expired: command stop (reason kFeaturesLost) and relocalise over the
//                  whole map on each frame; back to kNavigating when that succeeds.
//   kTourComplete  IN was the final image and arrival was seen (key_image_logic.hpp): stop
//                  (reason kTourComplete) on every further frame.
//   kOverdue       the robot stayed on one segment (IP, IN) much longer than the teach took
//                  between IP and IN (segment_overdue_*): the navigator is unsure where it is
//                  (typically the end of the tour cannot be seen: a blank wall) and stops for
//                  good (reason kSegmentOverdue) until reset(); the operator decides.
// Per frame in kNavigating: with a FrameMatcher on the current frame: n(Ia, IN), n(Ia, INN),
// and, only when they can change the decision (lazy, same outcome), n(IP, Ia) and the
// three-view counts (IP, Ia, IN), (Ia, IN, INN) -> KeyImageSwitcher; then, on the (new)
// segment, the line and point features of Ia vs IN and INN -> IBVS (or VNHV) law -> velocity
// schedule (turn-dependent speed, saturation and rate limit on omega by frame stamps).
//
// Determinism: the command is a function of the frames (pixels, t_ns) and the options only
// (seeded RANSAC, no wall clock). Wall-clock (std::chrono::steady_clock) durations appear in
// the telemetry's timings only. Units and signs: docs/conventions.md.
// Errors: a frame that is empty, not CV_8UC1, of another size than the map's images, or with
// t_ns before the previous frame's throws std::invalid_argument (the app stops the robot);
// invalid options throw at construction. Not thread-safe: one Navigator per replay.

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/control/ibvs_law.hpp"
#include "core/control/velocity_schedule.hpp"
#include "core/control/vnhv_law.hpp"
#include "core/features/image_features.hpp"
#include "core/features/matching.hpp"
#include "core/frame.hpp"
#include "core/geometry/planar_trifocal.hpp"  // NormSegment
#include "core/localization/initial_localizer.hpp"
#include "core/localization/key_image_logic.hpp"
#include "core/memory/visual_memory.hpp"
#include "core/navigator/path_tracker.hpp"
#include "core/navigator/estimate_errors.hpp"
#include "core/navigator/telemetry.hpp"
#include "core/navigator/transitions.hpp"

namespace pepper::core::navigator {

enum class ControllerKind { kIbvs, kVnhv };
const char* to_string(ControllerKind k);

/// `base` restricted to the kinds of feature of `mode` (MatcherOptions::match_lines,
/// match_points). Teach with the same restriction to build a single-modality map.
features::MatcherOptions matcher_for(control::FeatureMode mode, features::MatcherOptions base);

struct NavigatorOptions {
  /// VNHV (Blanc et al. 2004) by default: the measured configuration (docs/evaluation.md; with
  /// IBVS, room_corridor_room succeeded in 1 of 5 replays at VGA, issue 28). IBVS steers where
  /// VNHV has no segment model.
  ControllerKind controller = ControllerKind::kVnhv;
  /// Lines, points or both (METHOD.md; the paper's comparison): the Navigator matches only these
  /// (matcher_for), so localisation, switching, both control laws and the scale ratio see only
  /// them; it also sets ibvs.mode to this.
  control::FeatureMode features = control::FeatureMode::kLinesAndPoints;
  control::IbvsOptions ibvs;
  control::VnhvOptions vnhv;
  control::VelocityScheduleOptions schedule;
  localization::InitialLocalizerOptions initial;
  localization::SwitcherOptions switching;
  features::FeatureExtractorOptions extractor;
  features::MatcherOptions matcher;
  /// How long the last command is held when features vanish, ns of frame time, >= 0.
  double hold_s = 1.0;
  /// Fewer verified line matches with IN than this: the line modality is absent. >= 1.
  int min_line_matches = 3;
  /// Fewer verified point matches with IN than this: the point modality is absent. >= 1.
  int min_point_matches = 8;
  /// Point matches whose location in the current image has a structure-tensor minimum
  /// eigenvalue (7x7 window, grey levels^2 / px^2) below this are not used by the control law:
  /// guards against KLT "tracks" into textureless images (measured: 0 on a uniform image, ~4 on
  /// pure sensor-like noise sigma 3, 5th percentile ~20 on textured scenes). >= 0.
  double min_point_texture = 10.0;
  /// The apparent-scale ratio vs IN (switch guard, "passed IN", arrival) is computed only from
  /// at least this many verified point matches (fewer: unknown). Measured: with ~15 matches far
  /// from IN the ratio read 1.1..1.2 and fired "passed IN" spuriously. >= 3.
  int min_scale_points = 20;
  /// Which quantile of the pairwise ratios is "the" apparent scale (0.5: the median). Pairs of
  /// far features change little as the robot moves, near ones a lot: in a corner the median,
  /// dominated by the far side of the room, read 0.9-0.95 with IN still 0.3 m ahead and let
  /// the switch into the turn through early. A low quantile follows the near features.
  /// Measured (evaluate, robotics_room, QVGA, 2 starts): median lateral RMS 17.1 / 15.1 cm,
  /// max 43 / 37 cm; 0.25: 13.3 / 13.5 cm, 35 / 33 cm; 0.1: 13.4 / 12.3 cm, 35 / 30 cm; the
  /// other three worlds unchanged in outcome. In (0, 1).
  double scale_quantile = 0.25;
  /// With fewer points than min_scale_points the ratio comes from the matched lines alone
  /// (pairs nearly parallel in both views, key_image_logic.hpp append_line_scale_ratios) when
  /// there are at least min_scale_lines of them and at least min_scale_pairs ratios; 0: points
  /// only. Why: facing the wall at the end of a tour the points with the final image drop below
  /// 20 while 10-25 lines remain, and arrival was never seen (measured: the demo drove 1 m past
  /// the final image, docs/method/localization.md). The few points are not pooled in: 10 points
  /// read a ratio of 4.5 in a turn and fired "passed IN" 0.6 m early (same document). >= 0.
  int min_scale_lines = 8;
  int min_scale_pairs = 6;  ///< >= 1
  double scale_line_max_angle_rad = 0.05;  ///< "nearly parallel" for line pairs, (0, 0.5]
  /// Arrival at the final image: median scale ratio (key -> current) of the point matches with
  /// IN at least this (1 = exactly the key image's apparent scale), in (0, 2).
  double arrival_scale_ratio = 0.98;
  /// On the final segment the point ratio needs only this many points (instead of
  /// min_scale_points). Missing the arrival drives the robot on towards whatever ends the tour,
  /// while an early arrival only stops it short, so a noisier estimate is the safer side there.
  /// Measured: white_corridor at VGA kept 12-13 points and 4-9 lines with the final image and
  /// drove 1 m past it with 20 (docs/method/localization.md). >= 3.
  int arrival_min_scale_points = 10;
  /// Overdue segment: stop for good when no switch happened for longer than
  /// max(segment_overdue_min_s, segment_overdue_factor * (t_ns of IN - t_ns of IP in the map)),
  /// frame time. Why: with too few features to switch or to see arrival (measured: the end of
  /// worlds/white_corridor.yaml before it got an end door) the robot drove on with the last
  /// segment's command, towards the wall 5 m further, until the evaluation cut it off.
  /// Replay runs at 0.15 m/s, slower than most teach drives (0.25 m/s in the shipped worlds),
  /// and switches come early or late by up to a metre, so one replayed segment took up to 4x
  /// its taught time and 9.7 s (white_corridor); 10 s / 4x stopped good runs there. 20 s / 6x
  /// leaves twice that margin (3 m at replay speed). factor 0: off. factor >= 0, min_ns >= 0.
  /// Blind switches: while the scale ratio with IN is unknown (too few points), a switch is
  /// allowed only once the commanded forward speed, integrated over the frame stamps since the
  /// segment began, has covered this fraction of the segment's taught length (taught IP -> IN
  /// length, segment_taught_m()), on a segment that began with a switch (not after a
  /// (re)localisation, where the robot may start anywhere on it). Why: in feature-poor
  /// stretches the paper's count rules fire on noise. Measured in white_corridor (VGA, seed 1):
  /// run 10 of session 8, three switches 4-6 frames apart; run 7 with the light change of
  /// session 10, seven blind switches in a row, each after 0.1-0.37 m of 0.3-0.9 m segments, left
  /// the robot 1.6 m behind IP and the overdue rule stopped it. The earlier rule (0.3 of the
  /// taught time) let a switch through after 0.18 of the taught length at replay's 0.15 m/s
  /// (teach drives run at 0.2-0.25 m/s) and after 0.1 in turns (0.08 m/s): replay speed
  /// decides, so the guard counts distance. 0: off, else in (0, 1].
  double blind_switch_min_driven_fraction = 0.6;
  double segment_overdue_factor = 6.0;
  double segment_overdue_min_s = 20.0;
  /// Dead reckoning (issues 29, 26): the robot drives the taught path on odometry alone while
  /// the error that driving added to the estimate across the path, since the estimate's lateral
  /// position was last measured (a VNHV fix, the floor lines) or placed, stays within this (m,
  /// > 0): the estimate's modelled lateral sigma grown by the odometry's error bounds
  /// (core/odometry.hpp: 3 % of the distance, 0.05 rad per radian turned and 0.01 rad per metre
  /// of heading, the heading error carried over the distance), EstimateErrors::grown(). Beyond
  /// it the robot stops and says it is lost. One bound for distance and turns together, in the
  /// unit that matters (how far off the path the robot may be), and not reset by a frame that
  /// merely sees a few lines (no measurement). Why 0.3 m: docs/method/navigator.md "Dead
  /// reckoning through blind stretches".
  double dead_reckoning_max_lateral_sigma_m = 0.3;
  /// Odometry steering (issue 26): where VNHV has no estimate but the image still has features,
  /// VNHV's law on the odometry's deviation from the taught path steers instead of IBVS while
  /// the last vision fix is at most this far behind (m of odometry, > 0). Not the blind bound:
  /// here IBVS would steer on what it still sees, often a few lines. Measured (gen_building_15,
  /// QVGA, run 2): 8 m of a corridor with lines and no verified point, 3 m after the last fix;
  /// IBVS on the lines drifted to 71 cm (lateral RMS 23.2 cm), odometry up to 9 m gave 2.8 cm
  /// RMS, 9.9 cm max; the generated-world set: docs/method/navigator.md.
  double odometry_steer_max_m = 9.0;
  std::vector<std::string> validate() const;
};

struct StepResult {
  Command command;
  Telemetry telemetry;
};

class Navigator {
 public:
  /// Takes the map (moved in). Builds the key images' KLT pyramids once (tracking from key
  /// images every frame). Throws std::invalid_argument on invalid options or a map with fewer
  /// than 2 key images.
  Navigator(memory::VisualMemory map, const NavigatorOptions& options = {});

  StepResult step(const Frame& frame);
  /// Forget the segment and the command history (next frame relocalises from scratch).
  void reset();

  NavState state() const { return state_; }
  const memory::VisualMemory& map() const { return map_; }
  const NavigatorOptions& options() const { return options_; }

 private:
  // step()'s stages, in order (docs/method/navigator.md "One frame").
  void check_frame(const Frame& frame) const;
  /// The command in force since the previous frame drove the segment's distance and yaw.
  void account_commanded_motion(int64_t t_ns);
  /// Features of the frame (with ORB keypoints when localising or with the ORB fallback).
  features::FrameMatcher perceive(const Frame& frame, bool for_localisation, Telemetry& tel);
  /// A localisation attempt; true when a segment was found (the switcher then starts on it).
  bool localize(features::FrameMatcher& fm, Telemetry& tel);
  /// This frame's verified counts against the segment's key images, for the switcher.
  struct SegmentEvidence {
    localization::SwitchCounts counts;
    bool reached_final = false;  ///< arrival at the final image seen on this frame
  };
  SegmentEvidence associate(features::FrameMatcher& fm, Telemetry& tel);
  /// The switcher's update, and whether the segment is overdue: facts for the table.
  void switch_key_images(const SegmentEvidence& ev, int64_t t_ns, StepFacts& facts,
                         Telemetry& tel);
  /// The controller's yaw-rate demand on the current segment; nullopt: no usable feature.
  std::optional<double> control(features::FrameMatcher& fm, Telemetry& tel);
  /// Carries out a row of the transition table; the command for this frame.
  Command take(const Transition& t, int64_t t_ns, std::optional<double> demand, Telemetry& tel);
  /// Fills the arrival fields of the telemetry (tour complete).
  void report_arrival(int64_t t_ns, Telemetry& tel) const;
  /// True when the current segment has lasted longer than segment_overdue_* allow at t_ns.
  bool segment_overdue(int64_t t_ns) const;
  /// blind_switch_min_driven_fraction: whether a switch without a scale ratio is allowed now.
  bool blind_switch_allowed() const;
  /// A segment starts at t_ns (by a switch, or by a (re)localisation): its clock and distance.
  void begin_segment(int64_t t_ns, bool from_switch);
  /// Teach time between IP and IN of the current segment (map t_ns), ns; needs a segment.
  double segment_taught_ns() const;
  /// Taught length of the current segment, m; needs a segment. The distance driven between IP
  /// and IN during teach (KeyImage::travelled_m) when the map has it and it is at least
  /// 1 cm; else the taught time x vnhv.teach_speed_m_s (maps without
  /// odometry, turns on the spot).
  double segment_taught_m() const;
  /// Apparent scale of key_image in current (1: at the key pose), NaN-free; nullopt: unknown.
  /// min_points: points needed for the ratio from points (min_scale_points, or
  /// arrival_min_scale_points on the final segment).
  std::optional<double> scale_ratio(const features::TwoViewMatches& m,
                                    const features::ImageFeatures& key_image,
                                    const features::ImageFeatures& current, int min_points) const;
  std::optional<double> ibvs_omega(features::FrameMatcher& fm, Telemetry& tel);
  void ensure_pyramids(const localization::Segment& seg);
  std::optional<double> vnhv_omega(features::FrameMatcher& fm, Telemetry& tel);
  /// VNHV: whether IN's corners tracked into IP (a = IN, b = IP) show a reliable planar motion.
  bool vnhv_planar_motion_ok(const features::TwoViewMatches& next_prev, double focal_px) const;
  void remember_tracks(const features::FrameMatcher& fm);
  /// The frame's odometry moves the estimate on the taught path (and, while dead reckoning,
  /// adds to the distance and turn driven blind).
  void follow_odometry(const Frame& frame);
  /// The dead-reckoning command: the VNHV path-following law on the odometry's deviation from
  /// the taught path (a turn on the spot: turn to the taught heading).
  Command dead_reckon(int64_t t_ns, Telemetry& tel);
  /// The VNHV law on the odometry's deviation from the taught path (a turn on the spot, or
  /// facing well off it: turn towards the taught heading; on_the_spot says so).
  double odometry_demand(bool& on_the_spot);
  /// Whether odometry may steer where VNHV has no estimate: a vision fix is recent enough.
  bool odometry_steers() const;
  /// The odometry estimate as the VNHV resection's prior for segment IN (control::PosePrior);
  /// nullopt without odometry or a segment scale.
  std::optional<control::PosePrior> resection_prior(int in) const;
  /// Without a VNHV fix this frame: the heading relative to IN from the lines matched with it
  /// corrects the odometry estimate's heading (errors_, FixSource::kLineYaw; telemetry line_yaw_*).
  /// The verified line matches with key image `key_index` as normalised segment pairs (key,
  /// current).
  using LinePairs = std::vector<std::pair<geometry::NormSegment, geometry::NormSegment>>;
  LinePairs line_pairs_with(features::FrameMatcher& fm, int key_index);
  /// Both need the odometry estimate and a segment (IN = `in`); `pairs`: line_pairs_with(IN).
  void correct_heading_from_lines(const LinePairs& pairs, int in, Telemetry& tel);
  /// The matched lines on the floor give the robot's position relative to IN across them
  /// (geometry/floor_lines.hpp): a Kalman update of the odometry estimate's position.
  void correct_position_from_floor_lines(const LinePairs& pairs, int in, Telemetry& tel);
  /// The first switch the image decides after a placement (`criteria_bits`:
  /// Telemetry::switch_criterion; a paper rule and no "passed IN by travel") measures the
  /// estimate along the path: the robot is at the IN it left (errors_, FixSource::kSwitch;
  /// telemetry switch_along_correction_m).
  void correct_along_from_switch(int criteria_bits, Telemetry& tel);
  /// Whether dead reckoning can drive this frame (StepFacts::can_dead_reckon).
  bool can_dead_reckon() const;
  const features::ImageFeatures& key(int i) const { return map_.key_images[i].features; }

  memory::VisualMemory map_;
  NavigatorOptions options_;
  features::FeatureExtractor extractor_;
  control::VelocitySchedule schedule_;
  std::optional<localization::KeyImageSwitcher> switcher_;
  NavState state_ = NavState::kNotLocalized;
  Command last_command_;
  bool has_command_ = false;
  int64_t last_good_t_ns_ = 0;
  std::optional<int64_t> segment_start_t_ns_;  ///< frame time when the current segment began
  bool segment_from_switch_ = false;  ///< the current segment began with a switch
  /// Forward distance commanded since the current segment began (command v x frame interval), m.
  double segment_driven_m_ = 0.0;
  std::optional<int64_t> last_t_ns_;
  // Highest scale ratio with the final image seen on the final segment (kArrivalFadeRatio);
  // NaN until measured, reset whenever IN changes (final_ratio_in_: the IN it belongs to).
  double final_best_ratio_ = std::numeric_limits<double>::quiet_NaN();
  int final_ratio_in_ = -1;
  // False until the first localisation of this replay: the tour's first key images are then
  // expected (the robot was placed at the start).
  bool ever_localised_ = false;
  // VNHV, per segment (IN = vnhv_segment_next_): its reconstruction (built when the segment
  // starts; nullopt when that failed: IBVS drives), its metric scale and taught curvature, the
  // deviation filter.
  int vnhv_segment_next_ = -1;
  std::optional<control::SegmentModel> vnhv_model_;
  double vnhv_m_per_unit_ = 0.0;  ///< metres per segment unit (the chord IP -> IN)
  double vnhv_curvature_1_m_ = 0.0;  ///< the segment's taught arc; 0: the chord IP -> IN
  control::SegmentPoseOptions vnhv_pose_;  ///< the segment's reconstruction and resection settings
  control::DeviationFilter vnhv_filter_;
  /// This frame, a VNHV fix corrected the odometry estimate.
  bool fixed_this_frame_ = false;
  /// The odometry estimate's sigmas (along and across the robot's heading, m; the heading, rad)
  /// and the room-or-moved models of the VNHV fixes, the heading from lines and the floor lines
  /// that correct it (estimate_errors.hpp). The sigmas grow with the odometry's error model
  /// (navigator.cpp, kOdometryYawErrorPerRad: across times the heading's sigma) and shrink with
  /// each correction; they are the prior that tells the room from a moved object in the
  /// resection (control::PosePrior).
  EstimateErrors errors_;
  double along_sigma_m() const { return errors_.sigma()[0]; }
  double lateral_sigma_m() const { return errors_.sigma()[1]; }
  double heading_sigma_rad() const { return errors_.sigma()[2]; }
  /// This frame, odometry places the robot on a piece of the taught path that teaching turned on
  /// the spot (the path tracker, advanced by odometry and by every key-image switch): the drive
  /// command keeps v = 0 there, whichever law gives omega, as the dead-reckoning command does.
  bool on_taught_spot_turn_ = false;
  // Speed: where this frame's KLT starts per key image of the segment (the previous frame's
  // verified point matches, features::match_two_view's prior, and the corners it does not track
  // from scratch, klt_corners_to_skip). Cleared whenever the segment is forgotten, so it depends
  // on the frames only. remembered_frames_: how many frames remember_tracks saw (the retry
  // schedule's clock).
  std::unordered_map<int, features::KltStart> klt_starts_;
  int64_t remembered_frames_ = 0;
  // Odometry (issue 29): the estimate on the taught path, the frame's reading, the distance and
  // turn driven on odometry alone since vision was last usable, and this frame's vision fix's
  // correction of the estimate (distance m, |heading| rad).
  TaughtPathTracker tracker_;
  std::optional<OdometryPose> odom_;
  double blind_m_ = 0.0, blind_rad_ = 0.0;
  /// Odometry distance since the last vision fix of the estimate (VNHV located the robot).
  double odom_since_fix_m_ = 1e9;
  /// Vision took over after dead reckoning and no VNHV fix has measured the drift yet.
  bool drift_report_pending_ = false;
  std::optional<std::pair<double, double>> fix_correction_;
  // The last VNHV fix on the final segment: the robot's pose in the final key image's taught
  // frame (m, rad) and its frame time (arrival telemetry).
  std::optional<std::pair<OdometryPose, int64_t>> final_fix_;
};

}  // namespace pepper::core::navigator
