#pragma once
// Pixel <-> normalised coordinates through the camera's projection model, ViSP's conventions
// (intrinsics.hpp; ViSP's vpPixelMeterConversion / vpMeterPixelConversion, against which
// tests/core/camera/test_distortion.cpp checks them through visp_adapter):
//   kWithoutDistortion  the pinhole: CameraIntrinsics::normalize() / denormalize().
//   kWithDistortion     pixel -> normalised  x = (u - cx)/fx (1 + kdu r_d^2), y likewise,
//                                             r_d^2 = ((u - cx)/fx)^2 + ((v - cy)/fy)^2;
//                       normalised -> pixel  u = cx + fx x (1 + kud r^2), r^2 = x^2 + y^2.
// kud and kdu are two fits of one lens (ViSP's calibration estimates both), not exact inverses:
// a round trip is off by O(k^2 r^5) (~1e-4 normalised units at the corner of Pepper's image for
// kud ~ 0.03).
//
// pixel_to_norm() is where every feature's pixel coordinates become normalised coordinates (the
// extractor's line endpoints, ImageFeatures::corners_norm(), the matcher's point matches), so
// teach, replay, replay-log and map build undistort the same way through the camera's model
// (issue 31; docs/perception.md "Lens distortion"). For kWithoutDistortion it returns
// normalize() itself, bit for bit. Pure, thread-safe.

#include <opencv2/core/types.hpp>

#include "core/camera/intrinsics.hpp"

namespace pepper::core::camera {

/// Undistorted normalised coordinates of pixel p_px (ViSP's pixel -> meter conversion).
cv::Point2d pixel_to_norm(const CameraIntrinsics& k, const cv::Point2d& p_px);

/// Pixel of the undistorted normalised point p_norm (ViSP's meter -> pixel conversion).
cv::Point2d norm_to_pixel(const CameraIntrinsics& k, const cv::Point2d& p_norm);

}  // namespace pepper::core::camera
