#include "core/camera/intrinsics.hpp"

#include <cmath>
#include <sstream>

namespace pepper::core {

const char* to_string(ProjectionModel model) {
  switch (model) {
    case ProjectionModel::kWithoutDistortion:
      return "perspectiveProjWithoutDistortion";
    case ProjectionModel::kWithDistortion:
      return "perspectiveProjWithDistortion";
  }
  return "unknown";
}

std::optional<ProjectionModel> projection_model_from_string(const std::string& name) {
  for (const ProjectionModel m : {ProjectionModel::kWithoutDistortion, ProjectionModel::kWithDistortion}) {
    if (name == to_string(m)) return m;
  }
  return std::nullopt;
}

CameraIntrinsics CameraIntrinsics::pepper_top_vga() {
  // QVGA calibration (PEPPER.md, qcr/pepper_navigation camera.xml) scaled to VGA.
  CameraIntrinsics qvga;
  qvga.width_px = 320;
  qvga.height_px = 240;
  qvga.fx_px = 298.13;
  qvga.fy_px = 298.72;
  qvga.cx_px = 159.15;
  qvga.cy_px = 118.91;
  return qvga.scaled_to(640, 480);
}

CameraIntrinsics CameraIntrinsics::pepper_top_vga_with_distortion() {
  // The same calibration's perspectiveProjWithDistortion model (cameras/pepper_top.xml, rounded
  // as there) scaled to VGA; kud and kdu are in normalised units and do not scale.
  CameraIntrinsics qvga;
  qvga.width_px = 320;
  qvga.height_px = 240;
  qvga.fx_px = 300.0232;
  qvga.fy_px = 300.9510;
  qvga.cx_px = 159.2219;
  qvga.cy_px = 119.5549;
  qvga.model = ProjectionModel::kWithDistortion;
  qvga.kud = 0.0275116;
  qvga.kdu = -0.0273748;
  return qvga.scaled_to(640, 480);
}

CameraIntrinsics CameraIntrinsics::scaled_to(int new_width_px, int new_height_px) const {
  CameraIntrinsics k = *this;
  const double sx = static_cast<double>(new_width_px) / width_px;
  const double sy = static_cast<double>(new_height_px) / height_px;
  k.width_px = new_width_px;
  k.height_px = new_height_px;
  k.fx_px = fx_px * sx;
  k.fy_px = fy_px * sy;
  // Pixel centres: u' + 0.5 = (u + 0.5) * s.
  k.cx_px = (cx_px + 0.5) * sx - 0.5;
  k.cy_px = (cy_px + 0.5) * sy - 0.5;
  return k;
}

std::vector<std::string> CameraIntrinsics::validate() const {
  std::vector<std::string> errors;
  auto positive = [&](const char* name, double value) {
    if (!(std::isfinite(value) && value > 0.0)) {
      std::ostringstream os;
      os << name << " = " << value << " must be finite and > 0";
      errors.push_back(os.str());
    }
  };
  auto finite = [&](const char* name, double value) {
    if (!std::isfinite(value)) {
      std::ostringstream os;
      os << name << " = " << value << " must be finite";
      errors.push_back(os.str());
    }
  };
  positive("width_px", width_px);
  positive("height_px", height_px);
  positive("fx_px", fx_px);
  positive("fy_px", fy_px);
  finite("cx_px", cx_px);
  finite("cy_px", cy_px);
  finite("kud", kud);
  finite("kdu", kdu);
  if (model == ProjectionModel::kWithoutDistortion && (kud != 0.0 || kdu != 0.0)) {
    std::ostringstream os;
    os << "kud = " << kud << ", kdu = " << kdu << " must be 0 for model "
       << to_string(ProjectionModel::kWithoutDistortion);
    errors.push_back(os.str());
  }
  return errors;
}

}  // namespace pepper::core
