#pragma once
// Three-view line verification under planar motion (METHOD.md "Features and verification":
// a line match counts only if it is consistent over three views; trifocal RANSAC).
//
// Model. Pepper's camera moves on a plane with a horizontal optical axis at fixed height, so each
// view has 3 DOF (yaw about the camera y axis, translation in the camera x-z plane). View 0 is
// the reference: X_i = R_y(yaw_i) X_0 + t_i for i = 1, 2, with t_i = (tx_i, 0, tz_i) and
// R_y(a) = [[cos a, 0, sin a], [0, 1, 0], [-sin a, 0, cos a]]. The translations are known up to
// one common scale (|t_1|^2 + |t_2|^2 = 1): 5 DOF in all.
// The three back-projected planes of an image-line triplet (n_i = R_i^T l_i, d_i = l_i . t_i) must
// meet in one 3D line: rank [pi_0 pi_1 pi_2] <= 2. This splits into
//   (a) det [l_0, R_1^T l_1, R_2^T l_2] = 0, which involves the yaws only and is bilinear in
//       (cos yaw_1, sin yaw_1, 1) x (cos yaw_2, sin yaw_2, 1); vertical 3D lines satisfy it for
//       any yaw (no rotation information), other lines give one equation each;
//   (b) given the yaws, one equation linear in (tx_1, tz_1, tx_2, tz_2).
// Minimal sample: 3 triplets. Two non-vertical triplets give the yaws (1D scan of yaw_1 over
// [-max_yaw, max_yaw] for the roots of the resultant, refined by bisection; each root one
// hypothesis), then the three triplets give the translation as the null vector of a 3x4 system.
// Score (MSAC): for each triplet the 3D line is triangulated from each pair of views and
// reprojected into the third; the residual is the smallest of the three transfers (larger endpoint
// distance, pixels = normalised x focal_px). One local optimisation (Levenberg-Marquardt on all
// transfers weighted by their conditioning), adaptive stopping for `confidence`, at least
// `min_iterations` samples, a final LM. Final inliers: best transfer <= 2 x threshold_px, RMS
// endpoint distance after an optimal per-triplet line fit <= optimal_threshold_px, and the
// segments of views 0-1 and 0-2 overlapping along epipolar lines (check_overlap).
// Measured behaviour: docs/perception.md.
//
// Deterministic for a given seed. Expected outcomes are values (found = false with fewer than
// `min_inliers` inliers or fewer than 3 triplets); broken contracts throw std::invalid_argument.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core/matx.hpp>
#include <opencv2/core/types.hpp>

namespace pepper::core::geometry {

/// An image line segment in normalised coordinates (endpoints; the infinite line through them
/// is the constraint, the endpoints measure the residual).
struct NormSegment {
  cv::Point2d p0;
  cv::Point2d p1;
};

/// One line observed in views 0, 1, 2.
struct LineTriplet {
  std::array<NormSegment, 3> view;
};

/// Poses of views 1 and 2 relative to view 0 (see file comment). yaw_rad[0] = 0, t[0] = 0.
struct PlanarMotion3 {
  std::array<double, 3> yaw_rad{0.0, 0.0, 0.0};
  std::array<cv::Vec2d, 3> t_xz{cv::Vec2d(0, 0), cv::Vec2d(0, 0), cv::Vec2d(0, 0)};
};

struct PlanarTrifocalOptions {
  double threshold_px = 2.0;        ///< max reprojection distance of a segment endpoint, px
  double confidence = 0.99;         ///< adaptive stopping, (0, 1)
  int max_iterations = 500;         ///< samples drawn at most
  int min_iterations = 30;          ///< samples drawn at least (adaptive stopping is optimistic
                                    ///< here: noisy minimal models under-count the inliers)
  int min_inliers = 3;              ///< fewer: found = false
  double max_yaw_rad = 1.0472;      ///< |yaw| searched (60 deg); views of one tour turn less
  double min_rotation_leverage = 0.1;  ///< |normal_y| a triplet needs in all views to fix yaws
  int yaw_scan_steps = 48;          ///< samples of the yaw scan before bisection
  int lo_iterations = 5;            ///< LM iterations of each local optimisation (0: none)
  int max_lo_runs = 1;              ///< local optimisations during sampling (then one at the end)
  double optimal_threshold_px = 1.5;  ///< final check: RMS endpoint distance after optimal
                                      ///< triangulation of the line under the model, px
  bool check_overlap = true;        ///< final inliers must overlap along epipolars, in front
  double overlap_margin_px = 10.0;  ///< extra margin of that overlap check, px
  uint64_t seed = 1;                ///< RNG seed (deterministic)
  std::vector<std::string> validate() const;
};

struct PlanarTrifocalResult {
  bool found = false;
  PlanarMotion3 motion;             ///< best model (when found)
  std::vector<int> inliers;         ///< indices into the input triplets, increasing
  int iterations = 0;               ///< samples drawn
  int hypotheses = 0;               ///< models scored (a sample can give several yaw roots)
};

/// Verifies line triplets; see file comment. `focal_px` converts the pixel threshold.
/// Throws std::invalid_argument if focal_px <= 0 or the options are invalid.
PlanarTrifocalResult verify_line_triplets(const std::vector<LineTriplet>& triplets,
                                          double focal_px,
                                          const PlanarTrifocalOptions& options = {});

/// Residual (px) of one triplet under a model, as used for scoring (exposed for tests).
double line_triplet_residual_px(const LineTriplet& triplet, const PlanarMotion3& motion,
                                double focal_px);

}  // namespace pepper::core::geometry
