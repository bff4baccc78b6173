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
#include <vector>

#include "core/ceiling/mosaic_builder.hpp"

namespace pepper::core::ceiling {

struct RelayOptions {
  int min_shared_landmarks = 8;             ///< condition (1), >= 1 (the paper: 1)
  double max_orientation_change_rad = 0.3;  ///< condition (2), in (0, pi)

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

}  // namespace pepper::core::ceiling
