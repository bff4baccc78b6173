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
  /// With a PosePrior: the rigid structures found in the matches (each >= min_points inliers)
  /// and the chosen one's squared Mahalanobis distance to the prior; 1 and 0 without.
  int structures = 1;
  double prior_d2 = 0.0;
  /// False when no structure was within the prior's gate: then this is the largest one, and
  /// not the room as far as the odometry can tell (the caller should not use it as a fix).
  bool within_prior = true;
};

/// Where the robot's odometry estimate puts the current camera in IN's floor frame (segment
/// units), with the sigma of the difference between that prediction and a correct fix (the
/// prediction's and the fix's own, combined) per axis of IN's floor frame.
///
/// Why: the resection's largest consensus is the most textured rigid structure in view, and a
/// moved shelf is as rigid as the room. Measured (room_corridor_room, VGA, furniture, run 1):
/// in room B the moved book shelf (15 cm, 7 degrees) outnumbered the walls, every fix put the
/// robot 15-35 cm to the wrong side, and it drove into the moved bench. Each structure found in
/// the matches is a hypothesis; the one the odometry predicts is the room (docs/method/navigator.md
/// "Moved objects").
struct PosePrior {
  PlanarPose pose;
  double sigma_x = 1.0;        ///< along IN's optical axis, segment units, > 0
  double sigma_y = 1.0;        ///< across it, segment units, > 0
  double sigma_yaw_rad = 1.0;  ///< > 0
  /// Squared Mahalanobis distance beyond which a structure is not the room: chi-square, 3 dof,
  /// 99.9 %.
  double gate_chi2 = 16.27;
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
/// prior: see planar_resection.
std::optional<PlanarFix> locate_in_segment(const SegmentModel& model,
                                           const std::vector<CornerObservation>& matches,
                                           double focal_px, const SegmentPoseOptions& options,
                                           const PosePrior* prior = nullptr);

/// Resection of step 2 on explicit 3D points (IN's camera frame) and their normalised images.
/// Without a prior: the pose of the largest consensus. With one: RANSAC again on what each
/// structure leaves (sequential RANSAC, up to kMaxStructures), and the fix is the structure with
/// the most inliers among those within the prior's gate; when none is (every structure in view
/// has moved, as far as the odometry can tell), the largest with within_prior false.
std::optional<PlanarFix> planar_resection(const std::vector<cv::Vec3d>& X_next,
                                          const std::vector<cv::Point2d>& x_cur, double focal_px,
                                          const SegmentPoseOptions& options,
                                          const PosePrior* prior = nullptr);

/// Structures planar_resection looks for when given a prior.
constexpr int kMaxStructures = 3;

}  // namespace pepper::core::control
