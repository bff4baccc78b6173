#pragma once
// Initial localisation (and relocalisation) against a whole map, fast on long tours
// (METHOD.md "Replay: initial localisation"; budget: <= 300 ms for 150 key images on one core).
//
// Two stages:
//  1. Prefilter (cheap, no geometry): a wide-baseline descriptor vote. For every key image, the
//     strongest ORB descriptors of the current image are matched to the key image's strongest
//     (Hamming, 2-NN ratio test); the number of surviving matches is the key image's vote.
//  2. Geometric verification (the paper's n(Ia, Ik), verified lines + points through
//     FrameMatcher::wide_baseline) for the `top_k` best-voted key images only, then for the
//     neighbours i-1, i+1 of the best verified one (the rule needs their counts).
// The paper's rule (key_image_logic.hpp, localize_from_counts) runs on these counts; key images
// not verified count as "not evaluated".
//
// Requirements: the current image was extracted with kPartWideBaseline (ORB); key images carry
// their ORB keypoints (they do in maps built by the Teacher). Deterministic (no randomness in
// the vote; the verification's RANSAC is seeded). Not thread-safe (uses the caller's
// FrameMatcher cache). Invalid options throw std::invalid_argument.

#include <span>
#include <string>
#include <vector>

#include "core/features/matching.hpp"
#include "core/localization/key_image_logic.hpp"
#include "core/memory/visual_memory.hpp"

namespace pepper::core::localization {

struct InitialLocalizerOptions {
  InitialLocalizationOptions rule;
  int top_k = 6;              ///< key images verified geometrically after the vote, >= 1
  double vote_ratio = 0.8;    ///< 2-NN ratio test of the vote, (0, 1]
  int vote_max_hamming = 64;  ///< ORB distance above which a match does not vote, 0..256
  /// The vote uses only the strongest (ORB response) descriptors: this many of the current
  /// image and of each key image (>= 1). 150 x 200 instead of 500 x 500 cuts the vote ~8x
  /// (docs/method/localization.md).
  int vote_current_features = 150;
  int vote_key_features = 200;
  std::vector<std::string> validate() const;
};

struct InitialLocalizationReport {
  InitialLocalizationResult result;  ///< the rule's outcome (segment or not localised)
  /// Prefilter vote per key image; empty when the expected key images decided (from_prior):
  /// the vote is then not computed.
  std::vector<int> votes;
  std::vector<int> counts;           ///< verified n(Ia, Ik), -1 when not verified
  int verified = 0;                  ///< key images verified geometrically
  bool from_prior = false;           ///< decided among the expected key images (see below)
};

/// Localises the matcher's current image in `map`. Key-image ids used with the matcher are the
/// key image indices.
/// `expected`: key images to verify whatever the vote says (the navigator: the tour's first key
/// images when the replay starts, where odometry along the taught path puts the robot after a
/// loss; indices outside the map are ignored). They are a prior: when one of them reaches the
/// rule's min_best_count, the decision is made among them and their neighbours, whatever
/// count a look-alike key image elsewhere reached; they are verified first, and the vote and
/// its top_k verifications run only when none of them decides (same outcome, less work).
InitialLocalizationReport localize_in_map(features::FrameMatcher& matcher,
                                          const memory::VisualMemory& map,
                                          const InitialLocalizerOptions& options = {},
                                          std::span<const int> expected = {});

/// Stage 1 alone (exposed for tests and benchmarks).
std::vector<int> prefilter_votes(const features::ImageFeatures& current,
                                 const memory::VisualMemory& map,
                                 const InitialLocalizerOptions& options = {});

}  // namespace pepper::core::localization
