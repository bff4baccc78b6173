#pragma once
// Scale-consistent planar pose of the current camera with respect to a segment IP -> IN, for
// the VNHV law (vnhv_law.hpp). Two-view translations have no scale, so a pose of the current
// image from E(cur, IN) alone cannot be compared with the pose of IP from E(IP, IN). Here both
// come from one reconstruction:
//  1. once per segment, IP's planar pose w.r.t. IN is fitted (fit_arc_segment), its position
//     scaled to |p| = 1 ("segment unit"), and IN's corners matched into IP are triangulated in
//     IN's camera frame (build_segment_model);
//  2. each frame, the current camera is located from its matches to those IN corners by a planar
//     3-DOF resection (x, y, yaw in IN's floor frame; the camera height is fixed), so its position
//     is in segment units too.
//
// Model (docs/conventions.md; planar_trifocal.hpp): camera x right, y down, z forward, optical
// axis horizontal at a fixed height. Floor frame of a camera: x forward (cam z), y left (-cam x),
// yaw CCW seen from above. A camera C at PlanarPose (px, py, yaw) in reference camera R's floor
// frame sees the point X_R = (X, Y, Z) of R's camera frame at
//   X_C = s (Z - px) + c (X + py),  Y_C = Y,  Z_C = c (Z - px) - s (X + py),  c, s = cos, sin yaw,
// i.e. X_C = R_y(yaw) X_R + t with R_y as in planar_trifocal.hpp.
//
// Resection: linear in (c, s, t_x, t_z) from two equations per point (u Z_C = X_C, v Z_C = Y),
// minimal sample 2 points, RANSAC on reprojection error with a fixed seed (deterministic), then
// Gauss-Newton on the inliers' reprojection errors in (px, py, yaw).
//
// Pure functions, thread-safe. Expected failures (too few points, degenerate geometry) return
// nullopt; invalid options or inputs throw std::invalid_argument.

#include <opencv2/core/matx.hpp>
#include <opencv2/core/types.hpp>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/control/planar_pose.hpp"

namespace pepper::core::control {

struct SegmentPoseOptions {
  /// Triangulation: smallest angle between the two viewing rays, rad, > 0. The segment is a
  /// mostly forward motion: points near the epipole have no depth.
  double min_parallax_rad = 0.02;
  /// Triangulation check (both views) and resection inlier threshold, px, > 0.
  double max_reprojection_px = 2.0;
  /// Triangulated points needed for a segment model, and resection inliers for a pose, >= 3.
  int min_points = 12;
  int ransac_iterations = 64;       ///< resection RANSAC samples, >= 1
  int gauss_newton_iterations = 6;  ///< resection refinement steps, >= 1
  /// Arc fit (fit_arc_segment): |yaw of IP w.r.t. IN| searched up to this, rad, in (0, pi).
  double max_segment_yaw_rad = 0.8;
  std::vector<std::string> validate() const;
};

/// A point seen in IN and in another image (IP or the current one), normalised coordinates.
/// corner: index into IN's corners_px (the KLT tracks start at IN's corners).
struct CornerObservation {
  int corner = -1;
  cv::Point2d next_norm;
  cv::Point2d other_norm;
};

/// IN-referenced geometry of one segment, lengths in segment units (|IP - IN| = 1).
struct SegmentModel {
  PlanarPose prev_in_next;                             ///< IP in IN's floor frame, hypot(x, y) = 1
  std::unordered_map<int, cv::Vec3d> point_by_corner;  ///< IN's camera frame
};

/// Planar pose of the current camera in IN's floor frame with its fit quality.
struct PlanarFix {
  PlanarPose pose;
  int inliers = 0;
  double rms_px = 0.0;
};

/// Camera-frame coordinates in C of a point given in R's camera frame (model above).
cv::Vec3d to_camera(const PlanarPose& c_in_r, const cv::Vec3d& X_r);

/// IP's planar pose in IN's floor frame, unit distance, when the teach drive moved forward along
/// a circular arc or a straight line from IP to IN (a unicycle: the heading is the path tangent,
/// so the chord IP -> IN points along the mean of the two headings). One DOF, IP's yaw psi; the
/// position is -(cos(psi / 2), sin(psi / 2)). psi minimises a robust sum (Cauchy, scale
/// max_reprojection_px) of the Sampson distances of matches (IN corners tracked into IP) over
/// |psi| <= max_segment_yaw_rad (grid, then golden section). Why not the 2-DOF planar motion from
/// E: with mostly distant points a small yaw and a sideways translation look alike, and the free
/// fit traded one for the other (measured in robotics_room: heading error RMS 0.15 rad with it,
/// 0.03 rad with this; docs/method/control.md). nullopt with fewer than min_points matches.
std::optional<PlanarPose> fit_arc_segment(const std::vector<CornerObservation>& matches,
                                          double focal_px, const SegmentPoseOptions& options);

/// Step 1. prev_in_next: IP's planar pose in IN's floor frame in any length unit (e.g. from the
/// essential matrix of IN and IP, geometry::planar_view_prior); its position is rescaled to
/// unit length. matches: IN corners tracked into IP (other_norm = IP). nullopt when the position
/// vanishes or fewer than min_points points pass the checks (positive depth in both views,
/// parallax, reprojection).
std::optional<SegmentModel> build_segment_model(const PlanarPose& prev_in_next,
                                                const std::vector<CornerObservation>& matches,
                                                double focal_px, const SegmentPoseOptions& options);

/// Step 2. matches: IN corners tracked into the current image (other_norm = current); those
/// without a triangulated point are ignored. nullopt with fewer than min_points inliers.
std::optional<PlanarFix> locate_in_segment(const SegmentModel& model,
                                           const std::vector<CornerObservation>& matches,
                                           double focal_px, const SegmentPoseOptions& options);

/// Resection of step 2 on explicit 3D points (IN's camera frame) and their normalised images.
std::optional<PlanarFix> planar_resection(const std::vector<cv::Vec3d>& X_next,
                                          const std::vector<cv::Point2d>& x_cur, double focal_px,
                                          const SegmentPoseOptions& options);

}  // namespace pepper::core::control
