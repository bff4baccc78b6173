#pragma once
// Where the real-image test data lives and the cameras that took it, shared by the perception
// tests on real images (test_matching_data.cpp, test_illumination.cpp).
#include <string>

#include "core/camera/intrinsics.hpp"

namespace pepper::core::features::test_data {

/// Debian's visp-images-data: a hand-held sequence of a cube, 640x480 grey.
inline const std::string kVispCube = "/usr/share/visp-images-data/ViSP-images/mbt/cube/";
/// Pepper's own key images (shared/data/pepper_qut_tmap, 320x240 colour).
inline const std::string kPepper = std::string(PEPPER_SHARED_DIR) + "/data/pepper_qut_tmap/";

/// Intrinsics of the mbt/cube sequence (ViSP-images/mbt/cube.xml: px 547.74, py 542.07,
/// u0 338.70, v0 234.51).
inline CameraIntrinsics cube_camera() {
  CameraIntrinsics k;
  k.width_px = 640;
  k.height_px = 480;
  k.fx_px = 547.7367575;
  k.fy_px = 542.0744058;
  k.cx_px = 338.7036994;
  k.cy_px = 234.5083345;
  return k;
}

/// Pepper's top camera at QVGA as calibrated for pepper_qut_tmap (shared/data/README.md).
inline CameraIntrinsics pepper_qvga() {
  CameraIntrinsics k;
  k.width_px = 320;
  k.height_px = 240;
  k.fx_px = 298.13;
  k.fy_px = 298.72;
  k.cx_px = 159.15;
  k.cy_px = 118.91;
  return k;
}

}  // namespace pepper::core::features::test_data
