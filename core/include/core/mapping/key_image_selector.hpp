#pragma once
// Key-image selection of the teach phase (METHOD.md "Teach: key-image selection"), as a state
// machine over counts so it can be driven by a synthetic count model in tests; the Teacher
// (teacher.hpp) feeds it counts computed from images.
//
// Frames are numbered 0, 1, 2, ... Frame 0 is the first key image. For each new frame c >= 1
// the caller computes, against the current key image k = key():
//     count = nL(Ik, Ic-1, Ic) + nP(Ik, Ic)
// and calls on_frame(c, count). When count < threshold (and c-1 is at least min_frame_gap frames
// after the key image), frame c-1 becomes the new key image
// (tracking restarts from it at frame c+1). Special case: if c-1 is the key image itself (the
// scene changed completely within one frame), frame c becomes the key image instead, so the
// tour is never left without a reference. finish(last) marks the last frame as the final key
// image (unless it already is the key image).
//
// Heading rule (not in the paper, issue 29): when the caller also gives the heading change of
// frame c since the key image (from the robot's odometry) and it exceeds max_heading_change_rad,
// frame c-1 becomes the key image as well (same gap rule), so that a turn is never covered by one
// key image at each end only: in a turn towards a blank wall the counts may stay high on a few
// close features, or fall too late, while the view itself has swung away.
//
// threshold = epsilon (the paper), or with `relative` > 0
// min(max(epsilon, relative * ref_k), max_fraction * ref_k) with ref_k the count at frame k + 2
// of the current key image k: see the options and docs/method/teach.md.
// Key-image indices strictly increase. Not thread-safe. Invalid options or frame numbers that
// do not increase by one throw std::invalid_argument.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace pepper::core::mapping {

struct KeyImageSelectorOptions {
  /// epsilon of METHOD.md: verified lines (three views) + points (two views) below which a new
  /// key image is taken. >= 1. With `relative` on (default) it is the floor of the threshold:
  /// the absolute rule alone does not transfer between image sizes and textures (100 gave 16 key
  /// images per metre on rendered QVGA tours whose counts never exceed ~140: docs/method/teach.md).
  int epsilon = 30;
  /// Minimum frame gap between a key image and the next (not in the paper; >= 1, 1 = paper).
  /// Replay needs `consecutive_frames` (2) frames per switch, so key images closer than about
  /// three frames cannot be switched through in time and the robot lags in turns
  /// (docs/method/teach.md). A count below epsilon earlier than this is ignored.
  int min_frame_gap = 3;
  /// Relative threshold (not in the paper; 0 = off, the paper's absolute rule). When > 0 the
  /// threshold for key image k is max(epsilon, relative * reference_k), where reference_k is the
  /// count at frame k + 2 (the first frame that has three distinct views Ik, Ic-1, Ic). The
  /// threshold then follows the image size and the texture of each place. Default 0.5
  /// (measured in closed loop: docs/method/teach.md).
  double relative = 0.5;
  /// Relative rule only: the threshold never exceeds max_fraction * reference_k, so a key image
  /// is taken only once at least (1 - max_fraction) of the reference features are gone. Where
  /// the reference itself is near epsilon (feature-poor stretches) the epsilon floor would fire
  /// at once and take a key image every min_frame_gap frames: measured in
  /// worlds/window_corridor.yaml, 20 key images 5 cm apart in the last 1.3 m, more than replay
  /// could switch through (docs/method/teach.md). In (relative, 1]; 1 = no cap.
  double max_fraction = 0.7;
  /// Heading rule (not in the paper; 0 = off): a key image is also taken when the robot's
  /// odometry heading has changed by more than this since the current key image. Default 0.35
  /// rad (20 degrees), a third of the top camera's horizontal field of view (56 degrees:
  /// 2 atan(160 / 298) at QVGA), so that successive key images of a turn still share about two
  /// thirds of their view even where the feature counts do not fall (a corner facing a blank
  /// wall); a 90-degree turn gets at least four key images. Needs frames with odometry; without
  /// it only the count rule applies.
  double max_heading_change_rad = 0.35;
  std::vector<std::string> validate() const;
};

/// Which rule took a key image.
enum class KeyImageRule {
  kFirst,     ///< frame 0
  kFeatures,  ///< the verified count fell below the threshold (the paper's rule)
  kHeading,   ///< the odometry heading changed by more than max_heading_change_rad
  kLast,      ///< the end of the tour (finish())
};
const char* to_string(KeyImageRule rule);

class KeyImageSelector {
 public:
  explicit KeyImageSelector(const KeyImageSelectorOptions& options = {});

  /// The current key image's frame number (frame 0 after construction).
  int64_t key() const { return key_; }
  /// Frame c (must be previous + 1, starting at 1) with its count against key() and, when the
  /// robot's odometry is known for both, |heading(c) - heading(key())| wrapped to [0, pi].
  /// Returns the frame number of a new key image when one is taken (last_rule() says why).
  std::optional<int64_t> on_frame(int64_t c, int count,
                                  std::optional<double> heading_change_rad = std::nullopt);
  /// End of the sequence at frame `last` (the last frame passed to on_frame, or 0). Returns the
  /// final key image's frame number when it is new.
  std::optional<int64_t> finish();

  /// The threshold currently in force (epsilon until the reference count is known).
  double threshold() const { return threshold_; }
  /// The reference count of the current key image (-1 until known, or when relative is off).
  int reference() const { return reference_; }
  /// Threshold and reference that the last on_frame compared its count with.
  double last_threshold() const { return last_threshold_; }
  int last_reference() const { return last_reference_; }

  /// The rule that took the latest key image.
  KeyImageRule last_rule() const { return last_rule_; }

  /// All key image frame numbers so far, increasing.
  const std::vector<int64_t>& key_images() const { return keys_; }

 private:
  KeyImageSelectorOptions options_;
  int64_t key_ = 0;
  int64_t last_ = 0;
  bool finished_ = false;
  int reference_ = -1;
  double threshold_ = 0.0;
  double last_threshold_ = 0.0;
  int last_reference_ = -1;
  KeyImageRule last_rule_ = KeyImageRule::kFirst;
  std::vector<int64_t> keys_{0};
};

}  // namespace pepper::core::mapping
