#pragma once
// Where the robot is along the taught path, from its odometry and the key images' taught poses,
// and the path-following demand that drives the taught path while vision sees too little
// (issue 29: blank walls in turns).
//
// The taught path is the polyline through the key images' odometry poses (KeyImage::odom, the
// teach run's odometry frame): piece i joins key image i to i + 1. A piece shorter than
// kInPlaceLengthM whose heading changes with a turning radius below kInPlaceMaxRadiusM is a turn
// on the spot; a short piece of a wider arc is a chord, followed by its projection like any
// other. (A chord taken for a turn on the spot was followed by heading: a robot a little ahead
// in heading skipped a dozen of them at once.)
//
// The estimate X (T_teach_base, the robot's pose in the teach run's odometry frame) moves with
// the replay's odometry: X <- X (+) (O_prev^-1 (+) O_now), which needs no alignment of the two
// runs' odometry frames, only the replay odometry's short-term accuracy. Vision sets it where it
// can (a located VNHV fix: IN's taught pose (+) the robot's pose in IN's frame; or, after a
// (re)localisation, IP's taught pose) and odometry carries it where it cannot.
//
// Progress is a key-image coordinate u = i + f on piece i (f in [0, 1]: the projection along a
// straight piece, or the fraction of the heading change done on a turn on the spot); "IN
// passed" is u >= IN. The piece only moves forward (from the segment's IP), so a wrong
// projection cannot send the robot back along the tour. Nor can it send it far ahead: the
// progress advances along the path by at most the distance the estimate moved since the last
// deviation (odometry and fixes) plus kAdvanceSlackM. Why: where the teach took key images a
// few centimetres apart (feature-poor arcs), a few centimetres of drift put the estimate past
// the end of every short chord in turn; in a generated room (`world generate --seed 7`) the
// progress jumped 12 key images (0.6 m of arc) in one frame and the replay steered to a piece of
// the turn it had not reached.
//
// Frames and signs: docs/conventions.md (x forward, y left, yaw counter-clockwise). Pure and
// deterministic; not thread-safe.

#include <optional>
#include <vector>

#include "core/odometry.hpp"

namespace pepper::core::navigator {

/// a (+) b: pose b, given in a's frame, expressed in a's parent frame.
OdometryPose compose(const OdometryPose& a, const OdometryPose& b);
/// a^-1 (+) b: pose b expressed in a's frame (both given in one frame).
OdometryPose between(const OdometryPose& a, const OdometryPose& b);

/// The robot's deviation from the taught path at its progress, and the path's own turn there.
struct PathDeviation {
  double progress = 0.0;      ///< u = piece + fraction, in key-image indices
  double s_m = 0.0;           ///< the progress as a distance along the taught path from key 0
  int piece = 0;              ///< i: the robot is between key images i and i + 1
  bool in_place = false;      ///< piece i is a turn on the spot
  double lateral_m = 0.0;     ///< > 0 left of the piece, seen along the direction of travel
  double heading_rad = 0.0;   ///< robot heading - taught heading at the projection, (-pi, pi]
  double curvature_1_m = 0.0; ///< taught turn per metre on the piece (> 0 left); 0 in place
  double remaining_turn_rad = 0.0;  ///< in place: the piece's end heading - robot heading
};

class TaughtPathTracker {
 public:
  /// Pieces shorter than this are turns on the spot (m).
  static constexpr double kInPlaceLengthM = 0.03;
  /// Progress may run ahead of the estimate's own motion by this much (m): the projection of a
  /// point beside a straight piece moves a little faster than the point near its ends.
  static constexpr double kAdvanceSlackM = 0.1;
  /// A short piece is a turn on the spot when its turning radius (length / turn) is below this
  /// (m); a short piece of a wider arc is a chord of it.
  static constexpr double kInPlaceMaxRadiusM = 0.1;
  /// A piece shorter than this (m) that is no turn on the spot (two key images at one pose)
  /// takes its direction from the taught heading, not from its endpoints.
  static constexpr double kMinDirectionLengthM = 1e-6;

  /// `taught`: every key image's odometry pose, in tour order. usable() is false when any is
  /// missing or there are fewer than 2.
  explicit TaughtPathTracker(const std::vector<std::optional<OdometryPose>>& taught);

  bool usable() const { return usable_; }
  /// Forget the estimate (and the odometry reading it moved with).
  void reset();
  /// Sets the estimate X (teach frame) at the current odometry reading `odom`; the progress
  /// starts on piece `from_piece` (clamped to the path).
  void set(const OdometryPose& X_teach_base, const OdometryPose& odom, int from_piece);
  /// Moves X by the odometry's motion since the previous reading; first reading: remembered.
  void predict(const OdometryPose& odom);
  /// Takes a vision fix (teach frame) as X. Returns the distance (m) and |heading| (rad)
  /// between the prediction and the fix. (Partial corrections, weighed per axis, are shift().)
  std::pair<double, double> correct(const OdometryPose& X_fix);
  /// Moves X by `delta`, given in X's own frame (x along the robot, y across, yaw), e.g. a
  /// correction computed per axis. No estimate: nothing happens.
  void shift(const OdometryPose& delta);
  const std::optional<OdometryPose>& estimate() const { return X_; }

  /// The deviation at the current estimate, advancing the piece while the robot is past its
  /// end; nullopt without an estimate. Never moves back before the piece it was last on and
  /// never beyond the final key image (u <= final index).
  std::optional<PathDeviation> deviation();
  /// Moves the progress forward to at least piece `piece` (a key-image switch happened).
  void advance_to(int piece);

  int key_count() const { return static_cast<int>(taught_.size()); }
  /// Distance along the taught path from key image 0 to key image `i` (turns on the spot: 0).
  double length_to_m(int i) const { return length_to_m_.at(static_cast<size_t>(i)); }
  const OdometryPose& taught(int i) const { return taught_.at(static_cast<size_t>(i)); }

 private:
  bool piece_short(int i) const;  ///< shorter than kInPlaceLengthM
  bool piece_in_place(int i) const;
  /// Fraction along piece i of the current estimate (may lie outside [0, 1]).
  double fraction_on(int i) const;

  std::vector<OdometryPose> taught_;
  bool usable_ = false;
  std::optional<OdometryPose> X_;
  std::optional<OdometryPose> last_odom_;
  int piece_ = 0;
  /// Path length (m) from key image 0 to key image i (turns on the spot add nothing).
  std::vector<double> length_to_m_;
  /// Path coordinate of the last deviation (m); nullopt: no bound (after set/reset).
  std::optional<double> last_s_m_;
  double moved_since_m_ = 0.0;  ///< distance the estimate moved since then
};

}  // namespace pepper::core::navigator
