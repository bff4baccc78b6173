#pragma once
// Localisation and key-image switching of the replay (METHOD.md "Replay: initial localisation"
// and "Replay: key-image switching") as pure functions and a small state machine over counts of
// verified correspondences, so they are testable on scripted count sequences. The navigator
// computes the counts with core/features (matching.hpp) and feeds them here.
//
// Key images are indexed 0..n-1 in tour order; the last one is the tour's final image.
// Segment: IP (prev) < IN (next) = prev + 1 and INN (next_next) = next + 1 when it exists.
//
// Initial localisation: i = argmax_k n(Ia, Ik) (ties: lowest k); j = the neighbour i-1 or i+1
// with the larger count (ties: i+1, the direction of travel; a missing neighbour never wins);
// IP = min(i, j), IN = max(i, j), INN = IN + 1 if it exists.
//
// Switching: at each frame a switch is "wanted" if at least one holds
//   three views: nL(Ia,IN,INN) + nP(Ia,IN,INN) > nL(IP,Ia,IN) + nP(IP,Ia,IN)
//   two views:   n(Ia,INN) > n(Ia,IN)  and  n(Ia,INN) > n(IP,Ia);
// after `consecutive_frames` (paper: 2) consecutive wanting frames, IP <- IN <- INN <- next.
// When IN is the final image (no INN) switching is over; the tour ends after
// `consecutive_frames` consecutive frames on which the caller reports the final image reached
// (see reached_by_scale()). Key-image indices only increase.
//
// Not thread-safe (one state machine per replay). Contract violations throw std::invalid_argument.

#include <cstdint>
#include <limits>
#include <opencv2/core/types.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace pepper::core::localization {

struct Segment {
  int prev = 0;                  ///< IP
  int next = 1;                  ///< IN
  std::optional<int> next_next;  ///< INN; nullopt when IN is the final image
  bool operator==(const Segment&) const = default;
};

/// The segment for IN = next in a map of key_image_count images. Throws if out of range.
Segment segment_ending_at(int next, int key_image_count);

struct InitialLocalizationOptions {
  int min_best_count = 15;  ///< n(Ia, Ii) below this: not localised (values; >= 1)
  std::vector<std::string> validate() const;
};

struct InitialLocalizationResult {
  std::optional<Segment> segment;  ///< nullopt: not localised
  int best = -1;                   ///< i (argmax), -1 when no key image was evaluated
  int best_count = 0;              ///< n(Ia, Ii)
  int neighbour = -1;              ///< j
};

/// counts[k] = n(Ia, Ik), or a negative value when key image k was not evaluated (pruned by a
/// prefilter; it then never wins). Needs at least 2 key images.
InitialLocalizationResult localize_from_counts(std::span<const int> counts,
                                               const InitialLocalizationOptions& options = {});

/// Counts of one frame for the switching criteria (all verified counts, lines + points).
struct SwitchCounts {
  int three_view_next = 0;     ///< nL(Ia, IN, INN) + nP(Ia, IN, INN)
  int three_view_prev = 0;     ///< nL(IP, Ia, IN) + nP(IP, Ia, IN)
  int two_view_next_next = 0;  ///< n(Ia, INN)
  int two_view_next = 0;       ///< n(Ia, IN)
  int two_view_prev = 0;       ///< n(IP, Ia)
  /// Apparent scale of IN's verified points in Ia (median_scale_ratio), NaN when unknown.
  double next_scale_ratio = std::numeric_limits<double>::quiet_NaN();
  /// With an unknown next_scale_ratio the guard cannot judge; this is the caller's verdict
  /// instead (the navigator: the commands drove enough of the segment, NavigatorOptions::
  /// blind_switch_min_driven_fraction). true: the paper's rules decide alone.
  bool blind_switch_allowed = true;
  /// The caller's verdict, where it has no odometry, that the commands drove well past IN while
  /// the scale ratio is unknown (the navigator: twice the segment's taught length): a switch is
  /// wanted (criterion bit 16).
  bool passed_by_distance = false;
  /// The caller's verdict that the robot's odometry, carried along the taught path, is past IN
  /// (the navigator: navigator/path_tracker.hpp; at once while the scale ratio is unknown, by 2
  /// sigmas of the estimate along the robot while it is known): a switch is wanted (bit 32).
  bool passed_by_odometry = false;
  /// The caller's verdict that the robot's odometry, carried along the taught path, is still
  /// before IN (the navigator: by 2 sigmas of the estimate along the robot): it blocks the
  /// paper's rules as the scale guard does (bit 8). A count rule that fires there would turn
  /// the robot onto the next segment early.
  bool before_by_odometry = false;
};

/// Bit set of the criteria that held: 1 three-view rule, 2 two-view rule (paper), 8 blocked by
/// the guard (min_next_scale_ratio), 16 and 32 passed IN by travel (commands, odometry). Bit 4
/// was "passed IN" by scale, removed in session 29 (docs/method/navigator.md, ablations).
enum class SwitchCriterion : uint8_t { kNone = 0, kThreeView = 1, kTwoView = 2, kBoth = 3 };
inline constexpr int kCriterionPassedByDistance = 16;
inline constexpr int kCriterionPassedByOdometry = 32;
inline constexpr int kCriterionGuardBlocked = 8;

/// Which criteria hold for one frame (pure; the paper's two rules, no guard).
SwitchCriterion switch_criterion(const SwitchCounts& counts);

struct SwitcherOptions {
  int consecutive_frames = 2;  ///< frames in a row a switch (or arrival) must be seen; paper: 2
  /// The guard added to the paper's rule (docs/method/localization.md), from the apparent
  /// scale of IN's points in the current image (SwitchCounts::next_scale_ratio,
  /// median_scale_ratio; ~ depth from IN / depth from Ia: < 1 before IN, 1 at IN, > 1 past it):
  /// a switch is wanted only when next_scale_ratio >= min_next_scale_ratio. Without
  ///   it, a short next segment (dense key images in a turn) makes the three-view rule fire as
  ///   soon as the robot leaves IP, and the robot turns early. 0 disables (paper's rule).
  ///   An unknown ratio (NaN: too few points) blocks only when the caller says so
  ///   (SwitchCounts::blind_switch_allowed); otherwise the paper's rules decide.
  double min_next_scale_ratio = 0.9;
  std::vector<std::string> validate() const;
};

/// One rule of the switcher's "wanted" decision while INN exists, as a table row. A switch is
/// wanted when a paper rule holds and no guard blocks, or when an addition holds.
struct SwitchRule {
  enum class Kind { kPaper, kGuard, kAddition };
  const char* name;
  Kind kind;
  const char* option;  ///< the option(s) behind it ("" for the paper's rules)
  int criterion_bit;   ///< Telemetry::switch_criterion bit set when it holds (guard: blocked)
  bool (*holds)(const SwitchCounts&, const SwitcherOptions&);
  const char* why;
};

/// The rules KeyImageSwitcher::update applies, in order (docs/method/navigator.md prints them).
std::span<const SwitchRule> switch_rules();
const char* to_string(SwitchRule::Kind k);

enum class SwitchEvent { kNone, kSwitched, kTourComplete };

const char* to_string(SwitchEvent e);

struct SwitchUpdate {
  SwitchEvent event = SwitchEvent::kNone;
  SwitchCriterion criterion = SwitchCriterion::kNone;  ///< the paper's rules this frame
  int criteria_bits = 0;                               ///< see SwitchCriterion
  int streak = 0;                                      ///< consecutive wanting frames so far
};

class KeyImageSwitcher {
 public:
  /// Starts on `segment` of a map with key_image_count key images. Throws on invalid input.
  KeyImageSwitcher(Segment segment, int key_image_count, const SwitcherOptions& options = {});

  /// One frame. `counts` are used while INN exists; `reached_final` while IN is the final image.
  SwitchUpdate update(const SwitchCounts& counts, bool reached_final);

  const Segment& segment() const { return segment_; }
  bool tour_complete() const { return complete_; }
  int key_image_count() const { return count_; }

 private:
  Segment segment_;
  int count_;
  SwitcherOptions options_;
  int streak_ = 0;
  bool complete_ = false;
};

/// Arrival at a key image from the apparent scale of verified point matches: the median, over
/// pairs of matches, of |b_i - b_j| / |a_i - a_j| (a: key image, b: current image, normalised).
/// Moving towards the key pose the scene grows: the ratio rises to ~1 at the key pose.
/// Returns nullopt with fewer than 3 matches or no pair farther apart than min_separation.
std::optional<double> median_scale_ratio(std::span<const cv::Point2d> key_norm,
                                         std::span<const cv::Point2d> current_norm,
                                         double min_separation_norm = 0.05);

/// The per-pair ratios behind median_scale_ratio, appended to `ratios` (capped at 4000 pairs,
/// deterministic subsampling). Throws std::invalid_argument when the sizes differ.
void append_point_scale_ratios(std::span<const cv::Point2d> key_norm,
                               std::span<const cv::Point2d> current_norm,
                               double min_separation_norm, std::vector<double>& ratios);

/// A matched line segment: endpoints in normalised coordinates, key image (a) and current (b).
struct LineCorrespondence {
  cv::Point2d a0_norm, a1_norm;
  cv::Point2d b0_norm, b1_norm;
};

/// Apparent scale from line matches, for when points are too few (facing a wall with posters and
/// door frames): for every pair of matched lines that are nearly parallel in both views (angle
/// below max_angle_rad), the ratio current / key of their perpendicular separation (the mean
/// distance of each segment's midpoint from the other's supporting line). A separation
/// perpendicular to the lines does not depend on where a detector cuts the segments, so
/// fragmented or shortened segments do not bias it. Appended to `ratios`; pairs closer than
/// min_separation_norm in either view are skipped.
void append_line_scale_ratios(std::span<const LineCorrespondence> lines, double max_angle_rad,
                              double min_separation_norm, std::vector<double>& ratios);

/// Median of `ratios` (reordered), nullopt when empty.
std::optional<double> median_ratio(std::vector<double>& ratios);
/// The q-quantile (0 <= q <= 1, lower element) of `ratios` (reordered), nullopt when empty.
std::optional<double> quantile_ratio(std::vector<double>& ratios, double q);

}  // namespace pepper::core::localization
