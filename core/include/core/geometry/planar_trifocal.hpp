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
// distance, pixels = normalised x focal_px). One local optimisation, adaptive stopping for
// `confidence`, at least `min_iterations` samples, a final LM. The local optimisation is
// Levenberg-Marquardt (Cauchy loss) on all three transfers weighted by their conditioning, over
// the "consistent" triplets only: all transfers small and, where the 3D line is defined, segments
// overlapping on one side of the cameras (outliers in the LM set hold it at a wrong fixed point).
// Final inliers: best transfer <= 2 x threshold_px, RMS endpoint distance after an optimal
// per-triplet line fit <= optimal_threshold_px, and (check_overlap) the segment check on the 3D
// line: every endpoint is mapped onto the line triangulated from the best-conditioned pair of
// planes, the three segments must overlap along it and lie in front of their cameras. The sign of
// t, which the line constraints leave free, is the one that puts most lines in front; the
// returned motion carries it. This check catches the wrong segment the transfers cannot: when two
// views' planes coincide (a 3D line in an epipolar plane of that pair; for every line when two
// views are a few cm apart), any line in the third view is consistent with some 3D line in that
// plane, but rarely with one the other segments overlap in front of the cameras. Triplets whose
// best pair of planes is within `overlap_min_plane_sine` of parallel are not judged.
//
// Seeded by a prior (verify_line_triplets with a PlanarMotionPrior). The point branch has already
// verified KLT points view 1 -> view 0 and view 2 -> view 0 with five-point RANSAC; under planar
// motion each essential matrix gives the yaw and the direction of t_i, sign included
// (planar_view_prior: decomposition chosen by cheirality on those points, then a 2-DOF planar
// refinement on their Sampson distances). Only the split of the common scale between t_1 and t_2
// is unknown: t_1 = cos(phi) d_1, t_2 = sin(phi) d_2 with phi in [0, pi/2], and the translation
// equation (b) of ONE triplet gives phi. Samples are single triplets (adaptive stopping with
// P(clean) = w, at least `prior_min_samples`), scored as above; the best one gets the local
// optimisation over all 5 DOF. Then up to `prior_max_challengers` unseeded 3-triplet samples try
// to beat it (adaptive stopping from its support); a challenger with a lower MSAC cost replaces
// the prior's model only if it verifies `prior_replace_ratio` times as many triplets (the prior
// has the verified points behind it, a wrong model can tie on lines when many are
// ill-conditioned). Without a prior (an E missing or degenerate) the estimator is the unseeded one.
// Measured behaviour: docs/perception.md.
//
// Deterministic for a given seed. Expected outcomes are values (found = false with fewer than
// `min_inliers` inliers or fewer than 3 triplets); broken contracts throw std::invalid_argument.

#include <array>
#include <cstdint>
#include <optional>
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
  bool check_overlap = true;        ///< final inliers: segments overlap on the 3D line, in front
  double overlap_margin_px = 10.0;  ///< extra margin of that overlap check, px
  double overlap_min_plane_sine = 0.1;  ///< that check judges a triplet only if its best pair of
                                        ///< back-projected planes is at least this far from
                                        ///< parallel (sine); below, the 3D line is undetermined
  uint64_t seed = 1;                ///< RNG seed (deterministic)
  // Prior from the point branch (planar_view_prior, verify_line_triplets with a prior).
  bool prior_from_points = true;    ///< features::verify_three_view seeds from its two E
  int prior_min_points = 12;        ///< verified point pairs an essential matrix needs
  double prior_max_tilt_rad = 0.0873;  ///< rotation off the vertical axis at most (5 deg)
  double prior_max_t_y = 0.25;      ///< |t_y| / |t| at most (translation in the floor plane)
  double prior_min_parallax_px = 1.0;  ///< median parallax after derotation at least (else the
                                       ///< direction of t is noise: near-pure rotation)
  double prior_min_cheirality = 0.9;  ///< fraction of the points in front under the chosen pose
  int prior_min_samples = 10;       ///< single-triplet samples drawn at least
  int prior_max_challengers = 20;   ///< unseeded 3-triplet samples drawn at most after a prior
  double prior_replace_ratio = 1.2; ///< a challenger replaces the prior's model only if it
                                    ///< verifies at least this many times as many triplets
  std::vector<std::string> validate() const;
};

/// Planar motion of view i w.r.t. view 0 from two-view point geometry: the yaw and the direction
/// of t_i = (tx, 0, tz), sign included; the length of t_i is unknown.
struct PlanarViewPrior {
  double yaw_rad = 0.0;
  cv::Vec2d t_dir_xz{0.0, 0.0};  ///< unit vector
};

/// Priors of views 1 and 2 (the search with a prior needs both).
struct PlanarMotionPrior {
  PlanarViewPrior view1;
  PlanarViewPrior view2;
};

struct PlanarTrifocalResult {
  bool found = false;
  PlanarMotion3 motion;             ///< best model (when found)
  std::vector<int> inliers;         ///< indices into the input triplets, increasing
  int iterations = 0;               ///< samples drawn
  int hypotheses = 0;               ///< models scored (a sample can give several yaw roots)
  bool from_prior = false;          ///< the returned model came from the prior (not a challenger)
};

/// Verifies line triplets; see file comment. `focal_px` converts the pixel threshold.
/// Throws std::invalid_argument if focal_px <= 0 or the options are invalid.
PlanarTrifocalResult verify_line_triplets(const std::vector<LineTriplet>& triplets,
                                          double focal_px,
                                          const PlanarTrifocalOptions& options = {});

/// The same seeded by a prior from the point branch (see file comment).
PlanarTrifocalResult verify_line_triplets(const std::vector<LineTriplet>& triplets,
                                          double focal_px, const PlanarTrifocalOptions& options,
                                          const PlanarMotionPrior& prior);

/// Seed of view i from the essential matrix E_0_i of view i -> view 0 (x_0^T E x_i = 0, as
/// verify_essential returns it for a = view i, b = view 0) and its verified correspondences
/// (normalised coordinates in view i and in view 0). std::nullopt when the prior would be
/// unreliable: fewer than `prior_min_points` pairs, cheirality not decisive, rotation off the
/// vertical axis, translation out of the floor plane, or too little parallax (near-pure
/// rotation). Throws std::invalid_argument if the sizes differ, focal_px <= 0 or the options
/// are invalid.
std::optional<PlanarViewPrior> planar_view_prior(const cv::Matx33d& E_0_i,
                                                 const std::vector<cv::Point2d>& view_i_norm,
                                                 const std::vector<cv::Point2d>& view_0_norm,
                                                 double focal_px,
                                                 const PlanarTrifocalOptions& options = {});

/// Residual (px) of one triplet under a model, as used for scoring (exposed for tests).
double line_triplet_residual_px(const LineTriplet& triplet, const PlanarMotion3& motion,
                                double focal_px);

}  // namespace pepper::core::geometry
