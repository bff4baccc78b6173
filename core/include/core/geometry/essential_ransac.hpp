#pragma once
// Two-view point verification: essential-matrix RANSAC on normalised image coordinates
// (METHOD.md "Features and verification": a point match counts only if it passes essential
// RANSAC). Models:
//  - five-point (default, `planar = false`): the general 5-DOF model (cv::findEssentialMat,
//    Nister's solver) on all matches.
//  - planar then general (`planar = true`, issue 22): the camera moves on the floor with a
//    known pitch (2 DOF), so 2-point RANSAC (planar_essential.hpp) at `planar_threshold_factor`
//    x the threshold finds the candidates cheaply (~20 samples at 50 % outliers instead of ~150
//    five-point ones, and it gives up after its adaptive count on views that share no scene);
//    with `general_refit` the general five-point model is then fitted by RANSAC on those
//    candidates only (nearly all inliers: at most `general_refit_max_iterations` samples) and
//    classifies every match at the threshold, with the linear local optimisation. Why the
//    general model at the end: between real Pepper key images the camera also pitches and
//    rolls by 0.2-6 deg (the base sways); the planar model with only a linear refinement
//    (`general_refit = false`) verified 95 % of the five-point model's points between
//    neighbouring key images and 83 % two apart, with the refit 98-100 % and 97 %
//    (bench_essential_real, docs/perception.md "Two-view verification"). Not the default yet:
//    three core tests change (docs/method/navigator.md "Speed", issue 22). With
//    `five_point_fallback` the five-point model also runs where the planar model finds no
//    support (off: on views that share no scene it only adds time and the 5-DOF model's chance
//    fits).
//
// Inputs: matched points in normalised coordinates of view a and view b (same length); the
// threshold is given in pixels and converted with `focal_px` (threshold_norm = threshold_px /
// focal_px). With `ranked`, the matches are ordered best first (e.g. by KLT patch error) and the
// sampling is PROSAC (OpenCV's USAC), which tries the best ones first: far fewer samples on the
// navigator's tracks (docs/perception.md "KLT from the previous frame's tracks"); plain RANSAC
// when PROSAC finds no model, and without ranking. Output: inlier indices into the inputs, and E
// with x_b^T E x_a = 0. Fewer than 5 (or `min_inliers`) matches, or no model: found = false, no
// inliers (a value, not an exception). Deterministic: both samplers use a fixed-seed RNG.

#include <string>
#include <vector>

#include <opencv2/core/matx.hpp>
#include <opencv2/core/types.hpp>

namespace pepper::core::geometry {

struct EssentialRansacOptions {
  double threshold_px = 1.0;   ///< Sampson distance threshold, px (OpenCV's point-to-epiline)
  double confidence = 0.999;   ///< RANSAC confidence, (0, 1)
  int max_iterations = 1000;   ///< RANSAC cap (five-point samples; planar: 2-point samples)
  int min_inliers = 8;         ///< below this, the result is "not found" (5..)
  bool planar = false;         ///< planar 2-point candidates first (then general); false: five-point only
  double camera_pitch_rad = 0.0;  ///< planar model: camera pitch (> 0 looks down)
  double planar_threshold_factor = 5.0;  ///< planar model's threshold: this x threshold_px (the
                                         ///< base sways; a general refinement follows)
  /// planar model: the general five-point model refitted on its candidates (false: a linear
  /// refinement only; header comment)
  bool general_refit = true;
  int general_refit_max_iterations = 25;  ///< five-point samples on the planar candidates
  bool five_point_fallback = false;  ///< planar model found nothing: try the five-point model
                                     ///< (off: on views that share no scene it only adds time
                                     ///< and the 5-DOF model's chance fits)
  std::vector<std::string> validate() const;
};

struct EssentialResult {
  bool found = false;
  cv::Matx33d E_b_a = cv::Matx33d::zeros();  ///< x_b^T E x_a = 0 (normalised homogeneous points)
  std::vector<int> inliers;                   ///< indices into the input arrays, increasing
};

/// Throws std::invalid_argument if sizes differ, focal_px <= 0 or options are invalid.
EssentialResult verify_essential(const std::vector<cv::Point2d>& a_norm,
                                 const std::vector<cv::Point2d>& b_norm, double focal_px,
                                 const EssentialRansacOptions& options = {}, bool ranked = false);

/// Relative pose X_b = R_b_a X_a + t_b_a (|t_b_a| = 1) of the one of E's four decompositions
/// that puts the most correspondences in front of both cameras (cheirality).
struct RelativePose {
  cv::Matx33d R_b_a = cv::Matx33d::eye();
  cv::Vec3d t_b_a{0.0, 0.0, 0.0};
  int in_front = 0;            ///< correspondences in front of both cameras under this pose
  int in_front_runner_up = 0;  ///< the same count for the second-best decomposition
};

/// Decomposes E (x_b^T E x_a = 0) by cheirality on the given correspondences (normalised
/// coordinates, typically the verified inliers). Throws std::invalid_argument if sizes differ.
RelativePose recover_relative_pose(const cv::Matx33d& E_b_a, const std::vector<cv::Point2d>& a_norm,
                                   const std::vector<cv::Point2d>& b_norm);

}  // namespace pepper::core::geometry
