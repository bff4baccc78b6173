#pragma once
// ViSP's pixel <-> normalised ("meter") conversions under a camera's projection model
// (vpPixelMeterConversion, vpMeterPixelConversion), behind plain types; the formulas are in
// camera_xml.hpp. The reference for core/camera/distortion.hpp. Pure, thread-safe.

#include <utility>

#include "visp_adapter/camera_xml.hpp"

namespace pepper::visp_adapter {

/// vpPixelMeterConversion::convertPoint: normalised {x, y} of pixel (u_px, v_px).
std::pair<double, double> pixel_to_meter(const CameraCalibration& calibration, double u_px, double v_px);

/// vpMeterPixelConversion::convertPoint: pixel {u, v} of the normalised point (x, y).
std::pair<double, double> meter_to_pixel(const CameraCalibration& calibration, double x, double y);

}  // namespace pepper::visp_adapter
