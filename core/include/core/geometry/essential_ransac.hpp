#pragma once
// Two-view point verification: essential-matrix RANSAC on normalised image coordinates
// (METHOD.md "Features and verification": a point match counts only if it passes essential
// RANSAC). Models:
//  - five-point (`planar = false`, the default until session 31): the general 5-DOF model
//    (cv::findEssentialMat, Nister's solver) on all matches.
//  - planar, refined to the general model (`planar = true`, the default; issue 22): the camera
//    moves on the floor with a known pitch (2 DOF), so 2-point RANSAC (planar_essential.hpp) at
//    `planar_threshold_factor` x the threshold finds the motion cheaply (~20 samples at 50 %
//    outliers instead of ~150 five-point ones, and it gives up after its adaptive count on
//    views that share no scene). The base sways (between real Pepper key images the camera also
//    pitches and rolls by 0.2-6 deg), so with `general_refit` the planar model only seeds the
//    general 5-DOF model, two hypotheses of it: the planar model itself, refined on the Sampson
//    distances of the matches within a threshold shrinking to the verification one
//    (Levenberg-Marquardt over the rotation and the direction of t); and the five-point model
//    fitted by RANSAC on the planar model's candidates (at most `general_refit_max_iterations`
//    samples, nearly all inliers), refined the same way. The one with the lower MSAC cost at
//    the verification threshold decides. Each alone falls short: the refinement can settle in
//    the basin of a wrong yaw that the wide threshold admitted, and 25 five-point samples miss
//    the precise model (on the closed loop's own calls the five-point refit alone verified
//    0.1-1.6 % fewer matches than the five-point model, and half as many on some calls).
//    Without `general_refit` the planar model gets a linear 8-point refinement only.
//    With `five_point_fallback` the five-point model also runs where the planar model finds no
//    support (off: on views that share no scene it only adds time and the 5-DOF model's chance
//    fits). docs/perception.md "Two-view verification" has the measurements.
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
  bool planar = true;          ///< planar 2-point model seeds the general one (false: five-point)
  double camera_pitch_rad = 0.0;  ///< planar model: camera pitch (> 0 looks down)
  double planar_threshold_factor = 5.0;  ///< planar model's threshold: this x threshold_px (the
                                         ///< base sways; a general refinement follows)
  /// planar model: seeds the general model, refined and five-point refitted (false: a linear
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
