#pragma once
// Relay (key) images of a ceiling-mode tour (issue 24; Blanc et al. 2004, section 2.3): chosen
// among the teach frames so that
//   (1) two successive relay images share at least `min_shared_landmarks` mosaic landmarks, and
//   (2) the orientation of a landmark changes by less than `max_orientation_change_rad` between
//       them (the paper: a large change admits several different paths between the two poses).
// Greedy, as far as possible: from the last relay image, the next one is the last frame of the
// run of frames that all satisfy both conditions with it (frames are consecutive teach frames).
// The first and the last frame are always relay images.
//
// Condition (2) is measured robustly: ORB orientations of single corners are noisy (a few
// degrees), and all ceiling landmarks turn together (the ceiling is rigid), so the change is the
// MEDIAN over the shared landmarks of the wrapped orientation differences. The paper's condition
// (1) is "at least one"; a replay that fits a rigid transform between two relay images needs at
// least two, and a few more for a robust fit, hence the default.
//
// When no frame after a relay image satisfies the conditions with it (the tour lost the ceiling,
// or turned too fast between two frames), the next frame becomes a relay image anyway and the
// pair is reported in `breaks`: the replay cannot servo across it. Input: per frame the sightings
// of mosaic landmarks (mosaic_builder.hpp, kept_sightings()). Pure; bad options throw
// std::invalid_argument naming the field.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/ceiling/mosaic_builder.hpp"

namespace pepper::core::ceiling {

struct RelayOptions {
  int min_shared_landmarks = 8;             ///< condition (1), >= 1 (the paper: 1)
  double max_orientation_change_rad = 0.3;  ///< condition (2), in (0, pi)
  /// thin_linked_relays' spacing in runs only the chain links, >= 0: relay images there at least
  /// this far apart or turned this much (an arc over 0.2 rad: above the replay's 0.1 rad arc
  /// threshold, so its curvature is fed forward)
  double linked_step_m = 0.3;
  double linked_step_rad = 0.2;

  /// Throws std::invalid_argument naming the first invalid field.
  void check() const;
};

/// How two frames relate under the two conditions.
struct RelayPairCheck {
  int shared_landmarks = 0;
  double orientation_change_rad = 0.0;  ///< median over the shared landmarks, wrapped, >= 0
  bool ok = false;                      ///< both conditions hold
};

RelayPairCheck check_relay_pair(const std::vector<LandmarkSighting>& a,
                                const std::vector<LandmarkSighting>& b,
                                const RelayOptions& options);

struct RelaySelection {
  std::vector<size_t> relay_frames;  ///< increasing frame indices, first and last included
  /// Indices i into relay_frames such that relay_frames[i] -> relay_frames[i + 1] violates the
  /// conditions (no frame in between satisfied them).
  std::vector<size_t> breaks;
};

RelaySelection select_relay_images(const std::vector<std::vector<LandmarkSighting>>& frames,
                                   const RelayOptions& options = {});

/// Where the teach's chain links two relay images that fail the conditions (every frame between
/// them posed, by a fit or by the odometry: mosaic_builder.hpp), the selection above has taken
/// every frame as a relay image (none satisfied the conditions with the previous one): in a turn
/// posed by the odometry, relay images a centimetre apart, each turning less than the replay's
/// arc threshold, so the replay follows chords and feeds no curvature forward. Within a run of
/// such linked pairs (`linked[i]`: relay i -> i + 1), a relay image is kept only where the pose
/// moved at least `min_step_m` or turned at least `min_step_rad` since the last kept one; the
/// run's ends are kept. Returns the kept indices into `relay_poses` (increasing, the first and
/// the last included). Pure; throws std::invalid_argument when `linked` does not have one entry
/// per pair or a step is negative.
std::vector<size_t> thin_linked_relays(const std::vector<PlanarPose>& relay_poses,
                                       const std::vector<uint8_t>& linked, double min_step_m,
                                       double min_step_rad);

}  // namespace pepper::core::ceiling
