#include "core/camera/intrinsics_json.hpp"

#include <stdexcept>
#include <string>

namespace pepper::core::camera {

nlohmann::json intrinsics_to_json(const CameraIntrinsics& k) {
  return {{"width_px", k.width_px}, {"height_px", k.height_px}, {"fx_px", k.fx_px},
          {"fy_px", k.fy_px},       {"cx_px", k.cx_px},         {"cy_px", k.cy_px}};
}

CameraIntrinsics intrinsics_from_json(const nlohmann::json& j) {
  auto get = [&](const char* key) -> double {
    if (!j.is_object() || !j.contains(key) || !j[key].is_number()) {
      throw std::invalid_argument(std::string("missing or non-numeric key '") + key + "'");
    }
    return j[key].get<double>();
  };
  const CameraIntrinsics k = intrinsics_from_keys(get);
  if (const auto errors = k.validate(); !errors.empty()) throw std::invalid_argument(errors.front());
  return k;
}

}  // namespace pepper::core::camera
