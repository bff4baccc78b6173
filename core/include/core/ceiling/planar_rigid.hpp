#pragma once
// Planar rigid transforms and their robust fit (issue 24): the mosaic builder chains each frame's
// pose from the landmarks already in the mosaic, and the localiser finds the robot's pose in the
// mosaic, both by fitting a rotation + translation (no scale: the canonical view is metric)
// between two point sets on the ceiling plane.
//
// Units and frames: metres and radians; PlanarPose T_a_b maps points of frame b into frame a
// (docs/conventions.md), theta_rad counter-clockwise in the (x, y) coordinates of frame a.
// Failure: too few points or no consensus is a value (found = false); bad options or point sets
// of different sizes throw std::invalid_argument naming the field. Deterministic: the RANSAC
// sampler is seeded from the options, so one input gives one answer. Pure, no state.

#include <cstdint>
#include <opencv2/core/types.hpp>
#include <vector>

#include "core/odometry.hpp"

namespace pepper::core::ceiling {

/// A planar rigid transform T_a_b: p_a = R(theta_rad) p_b + (x_m, y_m).
struct PlanarPose {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;

  cv::Point2d apply(const cv::Point2d& p_b) const;
  PlanarPose inverse() const;
  /// T_a_c = T_a_b * T_b_c.
  PlanarPose operator*(const PlanarPose& T_b_c) const;
};

/// Angle wrapped to (-pi, pi].
double wrap_angle_rad(double angle_rad);

/// An odometry reading as the planar pose T_odom_base.
inline PlanarPose from_odometry(const OdometryPose& p) { return {p.x_m, p.y_m, p.yaw_rad}; }

/// The base's motion from reading `from` to reading `to`, in the base frame at `from`.
inline PlanarPose odometry_motion(const OdometryPose& from, const OdometryPose& to) {
  return from_odometry(from).inverse() * from_odometry(to);
}

/// Least-squares rigid transform T_dst_src from >= 2 corresponding points (closed form: centroids
/// and the angle of the cross-covariance). Throws std::invalid_argument for fewer than 2 points or
/// sets of different sizes.
PlanarPose fit_rigid(const std::vector<cv::Point2d>& src, const std::vector<cv::Point2d>& dst);

struct RigidRansacOptions {
  double inlier_threshold_m = 0.03;  ///< residual |T src - dst| of an inlier, > 0
  int min_inliers = 8;               ///< fewer: not found, >= 2
  int iterations = 400;              ///< two-point hypotheses drawn, > 0
  uint32_t seed = 1;                 ///< of the hypothesis sampler

  /// Throws std::invalid_argument naming the first invalid field.
  void check() const;
};

struct RigidFit {
  bool found = false;
  PlanarPose T_dst_src;         ///< least squares on the inliers
  std::vector<uint8_t> inlier;  ///< per pair, 1 = inlier (empty when not found)
  int inliers = 0;
  double rms_m = 0.0;  ///< of the inliers' residuals
};

/// RANSAC over two-point hypotheses, then least squares on the consensus, repeated until the
/// consensus stops growing (at most 3 times).
RigidFit ransac_rigid(const std::vector<cv::Point2d>& src, const std::vector<cv::Point2d>& dst,
                      const RigidRansacOptions& options = {});

}  // namespace pepper::core::ceiling
