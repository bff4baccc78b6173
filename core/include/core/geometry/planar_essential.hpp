#pragma once
// Two-view point verification under planar motion: a 2-point minimal solver for the essential
// matrix inside RANSAC (issue 22). The five-point solver (essential_ransac.hpp) fits 5 DOF; the
// robot's camera has 2: Pepper's head is locked, the base turns about the vertical axis and moves
// on the floor, so between two views the camera yaws about the vertical and translates in the
// horizontal plane (direction only: 1 DOF), and a minimal sample is 2 correspondences instead of
// 5 (RANSAC needs ~17 samples instead of ~146 for 99 % confidence at 50 % outliers).
//
// Level frame. The camera is pitched by `pitch_rad` (> 0 looks down, docs/conventions.md); its
// bearings are rotated into a level frame (x right, y down = gravity, z forward horizontal):
// x_level = R_x(-pitch) x_cam. There X_b = R_y(yaw) X_a + t, t = (sin phi, 0, cos phi) (unit),
// R_y(a) = [[cos a, 0, sin a], [0, 1, 0], [-sin a, 0, cos a]] (as planar_trifocal.hpp), and
//   E_level = [t]x R_y(yaw) = [[0, -cos phi, 0], [cos psi, 0, -sin psi], [0, sin phi, 0]],
// psi = phi - yaw. x_b^T E x_a = 0 is linear in v = (cos phi, sin phi, cos psi, sin psi): two
// correspondences leave a 2-D null space of v, and |v[0:2]| = |v[2:4]| picks at most two
// solutions (a quadratic). E in camera coordinates is R_x(-pitch)^T E_level R_x(-pitch).
//
// Estimator: RANSAC over 2-point samples (fixed-seed RNG, adaptive stopping for `confidence`,
// at least `min_samples`), MSAC score on the Sampson distance in the camera's normalised
// coordinates (threshold_px / focal_px, as the five-point path), then a local refinement of
// (phi, psi) by Gauss-Newton on the inliers' Sampson residuals, reclassifying until the inlier set
// stops growing. The sign of t (which E leaves free) is the one that puts most inliers in front
// of both cameras.
//
// Failures are values: fewer than max(2, min_inliers) correspondences, every sample degenerate
// (e.g. all points identical: the sample's two equations are dependent) or no model with
// `min_inliers` support give found = false. Near-zero baseline (median parallax after derotation
// below `min_parallax_px`) leaves the yaw and the inliers valid but the translation direction
// undetermined: translation_found = false and t_dir_xz = (0, 0), never an arbitrary direction.
// Broken contracts (sizes differ, focal_px <= 0, invalid options) throw std::invalid_argument.

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core/matx.hpp>
#include <opencv2/core/types.hpp>

namespace pepper::core::geometry {

struct PlanarEssentialOptions {
  double threshold_px = 1.0;     ///< Sampson distance threshold, px
  double confidence = 0.999;     ///< adaptive stopping, (0, 1)
  int max_samples = 1000;        ///< 2-point samples drawn at most
  int min_samples = 10;          ///< drawn at least (adaptive stopping is optimistic with noise)
  int min_inliers = 8;           ///< fewer: found = false (2..)
  double pitch_rad = 0.0;        ///< camera pitch w.r.t. the floor (> 0 looks down)
  double min_parallax_px = 1.0;  ///< median parallax after derotation below: translation unknown
  uint64_t seed = 1;             ///< RNG seed (deterministic)
  std::vector<std::string> validate() const;
};

struct PlanarEssentialResult {
  bool found = false;
  cv::Matx33d E_b_a = cv::Matx33d::zeros();  ///< x_b^T E x_a = 0, camera normalised coordinates
  double yaw_rad = 0.0;                       ///< X_b = R_y(yaw) X_a + t in the level frame
  bool translation_found = false;             ///< false under (near) zero baseline
  cv::Vec2d t_dir_xz{0.0, 0.0};               ///< unit (t_x, t_z) in the level frame, sign by
                                              ///< cheirality; (0, 0) when not found
  std::vector<int> inliers;                   ///< indices into the inputs, increasing
  int samples = 0;                            ///< minimal samples drawn
};

/// See file comment. a_norm, b_norm: normalised camera coordinates of views a and b.
PlanarEssentialResult estimate_planar_essential(const std::vector<cv::Point2d>& a_norm,
                                                const std::vector<cv::Point2d>& b_norm,
                                                double focal_px,
                                                const PlanarEssentialOptions& options = {});

/// E (camera coordinates) of the planar motion (yaw, t = (tx, 0, tz)) of a camera pitched by
/// pitch_rad; exposed for tests and for callers that hold a planar pose.
cv::Matx33d planar_essential_matrix(double yaw_rad, const cv::Vec2d& t_xz, double pitch_rad);

}  // namespace pepper::core::geometry
