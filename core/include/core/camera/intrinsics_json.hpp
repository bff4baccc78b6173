#pragma once
// The one JSON form of camera intrinsics, shared by intrinsics files, map manifests and
// recordings: {"width_px", "height_px", "fx_px", "fy_px", "cx_px", "cy_px"} (pixels, pixel
// centres at integer coordinates) and the projection model {"model", "kud", "kdu"} (ViSP's model
// name and its radial coefficients; see intrinsics.hpp). "model", "kud" and "kdu" are optional
// when read: JSON written before the model was recorded is perspectiveProjWithoutDistortion.

#include <nlohmann/json.hpp>

#include "core/camera/intrinsics.hpp"

namespace pepper::core::camera {

nlohmann::json intrinsics_to_json(const CameraIntrinsics& k);

/// Reads the form above and validates the values. Throws std::invalid_argument naming the
/// missing or non-numeric key, or the first CameraIntrinsics::validate() error; callers prefix
/// the file it came from.
CameraIntrinsics intrinsics_from_json(const nlohmann::json& j);

}  // namespace pepper::core::camera
