#pragma once
// Canonical ceiling view (issue 24; Blanc et al. 2004, "the homography of the ceiling plane between
// the real and the canonical image"): the image a virtual camera at the same optical centre would
// see looking straight up, at a fixed metric scale. The ceiling-mode landmarks and mosaic are
// built on this view, so that a robot translation is a pure image translation in it and a robot
// rotation a pure image rotation (docs/method/ceiling.md).
//
// Frames and signs (docs/conventions.md): camera x right, y down, z forward; head pitch > 0 looks
// DOWN (URDF and NAOqi: HeadPitch -0.7068 rad is fully up); head yaw is taken as 0. The ceiling
// is a horizontal plane ceiling_above_cam_m above the optical centre (not above the floor: the
// centre moves with the pitch, sim::CameraMount::T_base_cam).
// Ceiling coordinates: (forward_m, left_m), the horizontal offset of a ceiling point from the
// optical centre along the base's forward (x) and left (y) axes.
// Canonical image: a true camera image seen from below (not a map seen from above), with the
// robot's forward direction UP: u_canon = u0 + px_per_m (left_m - center_left_m),
// v_canon = v0 - px_per_m (forward_m - center_forward_m), (u0, v0) the centre of the canonical
// image. So image right is the robot's LEFT (the view is mirrored with respect to a map seen from
// above), and a left turn of the base (omega > 0) turns the ceiling content counter-clockwise on
// the canonical image (a point straight ahead moves towards the image's left edge).
//
// Model: the homography H_img_ceil = K R_cam_level M (pinhole, pixel centres at integer
// coordinates), H_canon_img = A_canon_ceil H_img_ceil^-1. Intrinsics with ViSP's distortion model
// (core/camera/intrinsics.hpp) are handled exactly in the point maps (pixel_to_norm /
// norm_to_pixel) and in warp() (cv::remap through the lens instead of cv::warpPerspective);
// homography() is then the map of UNDISTORTED (pinhole) pixels.
//
// Errors: the constructor throws CeilingViewError naming the field and the allowed range for bad
// intrinsics, a non-positive or non-finite height, a pitch at which no image row sees above the
// horizon, and a canonical frame that reaches ceiling points behind the camera's image plane.
// Pure and immutable after construction: thread-safe to share.

#include <opencv2/core/mat.hpp>
#include <opencv2/core/matx.hpp>
#include <opencv2/core/types.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/camera/intrinsics.hpp"

namespace pepper::core::ceiling {

/// Bad geometry or frame for a canonical ceiling view; what() names the field and its range.
class CeilingViewError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// The real camera looking at the ceiling.
struct CeilingCamera {
  CameraIntrinsics intrinsics = CameraIntrinsics::pepper_top_vga();
  double head_pitch_rad = -0.7;       ///< > 0 looks down; must let the top image row see up
  double ceiling_above_cam_m = 1.45;  ///< ceiling height above the optical centre, > 0
};

/// The canonical image: size, metric scale and which ceiling point is at its centre.
struct CanonicalFrame {
  int width_px = 320;
  int height_px = 320;
  double px_per_m = 80.0;
  double center_forward_m = 2.0;  ///< ceiling point at the image centre, ahead of the camera
  double center_left_m = 0.0;

  /// Messages naming each invalid field and its range; empty when valid.
  std::vector<std::string> validate() const;
};

/// The highest head pitch (rad, > 0 looks down) at which the top image row still looks above the
/// horizon: atan(cy / fy). A pitch must be below it for the camera to see any ceiling.
double max_ceiling_pitch_rad(const CameraIntrinsics& intrinsics);

/// A frame at `px_per_m` whose rectangle bounds the ceiling footprint of the whole image, with the
/// far side cut at `max_forward_m` ahead of the camera (rows near the horizon see the ceiling
/// arbitrarily far away). Throws CeilingViewError for the same reasons as CanonicalView, or when
/// max_forward_m leaves no footprint.
CanonicalFrame fit_frame(const CeilingCamera& camera, double px_per_m, double max_forward_m);

class CanonicalView {
 public:
  /// Throws CeilingViewError (see above).
  CanonicalView(const CeilingCamera& camera, const CanonicalFrame& frame);

  const CeilingCamera& camera() const { return camera_; }
  const CanonicalFrame& frame() const { return frame_; }

  /// 3x3 CV_64F homography mapping (undistorted) camera pixels to canonical pixels.
  cv::Mat homography() const { return cv::Mat(H_canon_img_, true); }
  const cv::Matx33d& H_canon_img() const { return H_canon_img_; }
  const cv::Matx33d& H_img_canon() const { return H_img_canon_; }

  /// Ceiling point (forward_m, left_m) seen at camera pixel p_px; nullopt when the pixel's ray
  /// does not go up (at or below the horizon).
  std::optional<cv::Point2d> ceiling_of_pixel(const cv::Point2d& p_px) const;
  /// Camera pixel of ceiling point (forward_m, left_m); nullopt when it is behind the image plane.
  std::optional<cv::Point2d> pixel_of_ceiling(const cv::Point2d& forward_left_m) const;

  /// Canonical pixel of ceiling point (forward_m, left_m), and back (affine: always defined).
  cv::Point2d canonical_of_ceiling(const cv::Point2d& forward_left_m) const;
  cv::Point2d ceiling_of_canonical(const cv::Point2d& p_canon_px) const;

  /// Camera pixel -> canonical pixel (nullopt at or below the horizon), and back (nullopt for a
  /// canonical pixel whose ceiling point is behind the image plane).
  std::optional<cv::Point2d> to_canonical(const cv::Point2d& p_px) const;
  std::optional<cv::Point2d> to_image(const cv::Point2d& p_canon_px) const;

  /// Warps a camera image (the intrinsics' size, any OpenCV type) to the canonical view, bilinear;
  /// canonical pixels the camera does not see are 0 and, when `seen` is given, 0 in it (255
  /// elsewhere, CV_8UC1). Throws CeilingViewError for an image of another size.
  cv::Mat warp(const cv::Mat& image, cv::Mat* seen = nullptr) const;

 private:
  CeilingCamera camera_;
  CanonicalFrame frame_;
  cv::Matx33d R_level_cam_;   // camera axes in the level camera frame (x right, y down, z fwd)
  cv::Matx33d H_img_ceil_;    // (forward_m, left_m, 1) -> undistorted pixel
  cv::Matx33d A_canon_ceil_;  // (forward_m, left_m, 1) -> canonical pixel
  cv::Matx33d H_canon_img_;
  cv::Matx33d H_img_canon_;
  cv::Mat lens_map_x_, lens_map_y_;  // distortion model only: canonical -> distorted pixel
};

}  // namespace pepper::core::ceiling
