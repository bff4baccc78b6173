#pragma once
// Pinhole intrinsics of the camera, in pixels, for one image size.
//
// Normalised coordinates (METHOD.md, "Setting"): x_norm = (u_px - cx_px) / fx_px,
// y_norm = (v_px - cy_px) / fy_px. Camera axes: x right, y down, z forward (docs/conventions.md).
// Projection model: ViSP's two perspective models (vpCameraParameters), recorded with the
// parameters so that a calibration written with distortion is not silently read as one without:
//   kWithoutDistortion  perspectiveProjWithoutDistortion: the pinhole above; kud = kdu = 0.
//   kWithDistortion     perspectiveProjWithDistortion: one radial coefficient each way, in
//                       normalised units (so scaled_to() keeps them):
//                         undistorted -> distorted  u = cx + fx x (1 + kud r^2), r^2 = x^2 + y^2
//                         distorted -> undistorted  x = (u - cx)/fx (1 + kdu r_d^2), r_d^2 from
//                         the distorted normalised coordinates.
// Pepper's top camera has kud ~ 0.03 (PEPPER.md). normalize()/denormalize() are the pinhole maps
// and do not apply the distortion: features become normalised coordinates through
// camera::pixel_to_norm() (core/camera/distortion.hpp), which applies the model, and nothing
// that handles features calls normalize() directly.
//
// Invariant (checked by validate()): width_px, height_px > 0; fx_px, fy_px > 0 and finite;
// cx_px, cy_px, kud, kdu finite; kud = kdu = 0 for kWithoutDistortion.

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/types.hpp>

namespace pepper::core {

/// ViSP's perspective projection models (see above).
enum class ProjectionModel { kWithoutDistortion, kWithDistortion };

/// ViSP's names, "perspectiveProjWithoutDistortion" / "perspectiveProjWithDistortion", as
/// written in camera XML files, maps and messages.
const char* to_string(ProjectionModel model);
/// The inverse of to_string; std::nullopt for any other text.
std::optional<ProjectionModel> projection_model_from_string(const std::string& name);

struct CameraIntrinsics {
  int width_px = 0;
  int height_px = 0;
  double fx_px = 0.0;
  double fy_px = 0.0;
  double cx_px = 0.0;
  double cy_px = 0.0;
  ProjectionModel model = ProjectionModel::kWithoutDistortion;
  double kud = 0.0;  ///< radial, undistorted -> distorted (ViSP's kud); 0 without distortion
  double kdu = 0.0;  ///< radial, distorted -> undistorted (ViSP's kdu); 0 without distortion

  /// Pepper's top head camera at VGA (640x480). Source: the public QVGA calibration of a Pepper
  /// top camera (fx 298.13, fy 298.72, cx 159.15, cy 118.91; PEPPER.md) scaled to VGA with
  /// scaled_to(): fx 596.26, fy 597.44, cx 318.8, cy 238.32.
  static CameraIntrinsics pepper_top_vga();

  /// The same camera's calibration with ViSP's distortion model (cameras/pepper_top.xml, model
  /// perspectiveProjWithDistortion: QVGA fx 300.0232, fy 300.9510, cx 159.2219, cy 119.5549,
  /// kud 0.0275116, kdu -0.0273748) scaled to VGA. Its focal lengths differ from
  /// pepper_top_vga()'s because a pinhole fit of a lens absorbs part of the distortion.
  static CameraIntrinsics pepper_top_vga_with_distortion();

  /// Same camera for another image size: focal lengths and principal point scale with the size
  /// (assumes the sensor is binned or scaled, not cropped, as ALVideoDevice does). Pixel centres
  /// are at integer coordinates, so c' = (c + 0.5) * s - 0.5.
  CameraIntrinsics scaled_to(int new_width_px, int new_height_px) const;

  /// Messages naming each invalid field and its allowed range; empty when valid.
  std::vector<std::string> validate() const;

  cv::Point2d normalize(const cv::Point2d& p_px) const {
    return {(p_px.x - cx_px) / fx_px, (p_px.y - cy_px) / fy_px};
  }
  cv::Point2d denormalize(const cv::Point2d& p_norm) const {
    return {p_norm.x * fx_px + cx_px, p_norm.y * fy_px + cy_px};
  }

  bool operator==(const CameraIntrinsics&) const = default;
};

/// The six pinhole fields read by their key names in intrinsics files (width_px, height_px, fx_px,
/// fy_px, cx_px, cy_px) through get(key) -> double, which throws for a missing or non-numeric
/// key (JSON and YAML readers share this); the model stays kWithoutDistortion. Not validated.
template <class Get>
CameraIntrinsics intrinsics_from_keys(Get&& get) {
  CameraIntrinsics k;
  k.width_px = static_cast<int>(get("width_px"));
  k.height_px = static_cast<int>(get("height_px"));
  k.fx_px = get("fx_px");
  k.fy_px = get("fy_px");
  k.cx_px = get("cx_px");
  k.cy_px = get("cy_px");
  return k;
}

}  // namespace pepper::core
