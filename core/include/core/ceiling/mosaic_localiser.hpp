#pragma once
// Localisation against the ceiling mosaic (issue 24; Blanc et al. 2004, section 2.1): the robot's
// base pose T_mosaic_base from the landmarks seen in ONE canonical view, with no prior (a replay
// may start anywhere on the tour) or with one (the previous pose, to match fewer landmarks).
//
// Where the paper averages the poses given by each tracked 2D model, weighted by the tracker's
// quality, this localiser fits one rigid transform to many point landmarks robustly:
// 1. matching: each frame landmark's nearest mosaic descriptor (Hamming <= max_hamming; with a
//    prior, only among the mosaic landmarks within prior_radius_m of where the prior puts it),
//    each mosaic landmark used once;
// 2. RANSAC over two-point rigid hypotheses (planar_rigid.hpp), which also rejects landmarks that
//    are hidden or moved (a person under the camera, a lamp switched off) and repeated patterns;
// 3. refinement: guided re-matching around the RANSAC pose (refine_radius_m), then least squares
//    on the inliers, twice.
// A fix needs min_inliers inliers AND, after refinement, inliers >= min_inlier_ratio times the
// first step's matches, so that a view of an unmapped ceiling with a few chance agreements is
// refused.
//
// Frames and units as in mosaic_builder.hpp (the mosaic frame, metres, radians).
// Failure: no fix is a value (found = false, with the counts to say why); bad options or a mosaic
// without landmarks throw std::invalid_argument. Immutable after construction: thread-safe.

#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <optional>
#include <vector>

#include "core/ceiling/mosaic.hpp"
#include "core/ceiling/observation.hpp"
#include "core/ceiling/planar_rigid.hpp"

namespace pepper::core::ceiling {

struct LocaliserOptions {
  int max_hamming = 64;           ///< of a descriptor match, bits in [1, 256]
  double prior_radius_m = 0.5;    ///< search radius around a prior's prediction, > 0
  double refine_radius_m = 0.06;  ///< search radius of the guided re-matching, > 0
  double min_inlier_ratio = 0.1;  ///< final inliers / first-step matches, in [0, 1]
  RigidRansacOptions ransac{0.04, 12, 2000, 1};

  /// Throws std::invalid_argument naming the first invalid field.
  void check() const;
};

struct MosaicFix {
  bool found = false;
  PlanarPose T_mosaic_base;
  int matches = 0;  ///< descriptor matches of the first step
  int inliers = 0;  ///< after refinement
  double rms_m = 0.0;
  /// The observation's landmarks the fit's inliers came from (indices into the observation;
  /// also where the fit was refused, empty when none was found): what a display draws.
  std::vector<int> inlier_observations;
};

class MosaicLocaliser {
 public:
  /// Throws std::invalid_argument for bad options or an invalid or empty mosaic.
  explicit MosaicLocaliser(Mosaic mosaic, LocaliserOptions options = {});

  MosaicFix localise(const CeilingObservation& observation,
                     const std::optional<PlanarPose>& prior = std::nullopt) const;

  const Mosaic& mosaic() const { return mosaic_; }

 private:
  // (observation index, mosaic index) pairs: nearest descriptor among `candidates(i)`.
  template <typename Candidates>
  void match(const CeilingObservation& obs, Candidates candidates, std::vector<size_t>& obs_index,
             std::vector<size_t>& mosaic_index) const;
  std::vector<size_t> within(const cv::Point2d& p_m, double radius_m) const;

  Mosaic mosaic_;
  LocaliserOptions options_;
  cv::Mat descriptors_;  // one row per mosaic landmark
  // Landmark indices sorted by x, for radius queries.
  std::vector<size_t> by_x_;
  std::vector<double> xs_;
};

}  // namespace pepper::core::ceiling
