#pragma once
// CameraCalibration -> vpCameraParameters, for the adapter's sources only.

#include <visp3/core/vpCameraParameters.h>

#include "visp_adapter/camera_xml.hpp"

namespace pepper::visp_adapter {

inline vpCameraParameters to_visp_camera(const CameraCalibration& c) {
  vpCameraParameters cam;
  if (c.model == CameraModel::kPerspectiveWithDistortion) {
    cam.initPersProjWithDistortion(c.px, c.py, c.u0, c.v0, c.kud, c.kdu);
  } else {
    cam.initPersProjWithoutDistortion(c.px, c.py, c.u0, c.v0);
  }
  return cam;
}

}  // namespace pepper::visp_adapter
