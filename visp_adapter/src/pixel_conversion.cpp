// vpPixelMeterConversion / vpMeterPixelConversion behind plain types (see pixel_conversion.hpp).
#include "visp_adapter/pixel_conversion.hpp"

#include <visp3/core/vpMeterPixelConversion.h>
#include <visp3/core/vpPixelMeterConversion.h>

#include "visp_camera.hpp"

namespace pepper::visp_adapter {

std::pair<double, double> pixel_to_meter(const CameraCalibration& calibration, double u_px, double v_px) {
  double x = 0.0, y = 0.0;
  vpPixelMeterConversion::convertPoint(to_visp_camera(calibration), u_px, v_px, x, y);
  return {x, y};
}

std::pair<double, double> meter_to_pixel(const CameraCalibration& calibration, double x, double y) {
  double u = 0.0, v = 0.0;
  vpMeterPixelConversion::convertPoint(to_visp_camera(calibration), x, y, u, v);
  return {u, v};
}

}  // namespace pepper::visp_adapter
