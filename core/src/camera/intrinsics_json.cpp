#include "core/camera/intrinsics_json.hpp"

#include <stdexcept>
#include <string>

namespace pepper::core::camera {

nlohmann::json intrinsics_to_json(const CameraIntrinsics& k) {
  return {{"width_px", k.width_px}, {"height_px", k.height_px}, {"fx_px", k.fx_px},
          {"fy_px", k.fy_px},       {"cx_px", k.cx_px},         {"cy_px", k.cy_px},
          {"model", to_string(k.model)}, {"kud", k.kud},         {"kdu", k.kdu}};
}

CameraIntrinsics intrinsics_from_json(const nlohmann::json& j) {
  auto get = [&](const char* key) -> double {
    if (!j.is_object() || !j.contains(key) || !j[key].is_number()) {
      throw std::invalid_argument(std::string("missing or non-numeric key '") + key + "'");
    }
    return j[key].get<double>();
  };
  CameraIntrinsics k = intrinsics_from_keys(get);
  // Files, maps and recordings written before issue 31 have no "model": they were pinhole.
  if (j.contains("model")) {
    const std::optional<ProjectionModel> model =
        j["model"].is_string() ? projection_model_from_string(j["model"].get<std::string>())
                               : std::nullopt;
    if (!model) {
      throw std::invalid_argument("key 'model' = " + j["model"].dump() + " must be \"" +
                                  to_string(ProjectionModel::kWithoutDistortion) + "\" or \"" +
                                  to_string(ProjectionModel::kWithDistortion) + "\"");
    }
    k.model = *model;
  }
  if (j.contains("kud")) k.kud = get("kud");
  if (j.contains("kdu")) k.kdu = get("kdu");
  if (const auto errors = k.validate(); !errors.empty()) throw std::invalid_argument(errors.front());
  return k;
}

}  // namespace pepper::core::camera
