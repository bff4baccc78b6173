// Intrinsics files: ViSP camera XML (through visp_adapter, i.e. ViSP's vpXmlParserCamera) and the
// plain YAML/JSON form (see intrinsics_io.hpp).
#include "core/camera/intrinsics_io.hpp"
#include "core/camera/intrinsics_json.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <cctype>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "visp_adapter/camera_xml.hpp"

namespace pepper::core::camera {
namespace {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

void require_readable(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw IntrinsicsFileError(path, "no such file");
  }
  std::ifstream in(path);
  if (!in) throw IntrinsicsFileError(path, "cannot open for reading");
}

void require_valid(const std::string& path, const CameraIntrinsics& k) {
  const auto errors = k.validate();
  if (errors.empty()) return;
  std::string msg = "invalid intrinsics:";
  for (const auto& e : errors) msg += " " + e + ";";
  throw IntrinsicsFileError(path, msg);
}

visp_adapter::CameraModel to_adapter(ProjectionModel m) {
  return m == ProjectionModel::kWithDistortion ? visp_adapter::CameraModel::kPerspectiveWithDistortion
                                               : visp_adapter::CameraModel::kPerspectiveWithoutDistortion;
}

bool has_model(const visp_adapter::CameraEntry& e, ProjectionModel m) {
  for (const visp_adapter::CameraModel held : e.models)
    if (held == to_adapter(m)) return true;
  return false;
}

}  // namespace

IntrinsicsFileError::IntrinsicsFileError(const std::string& path, const std::string& cause)
    : std::runtime_error(path + ": " + cause), path_(path) {}

CameraIntrinsics load_visp_camera_xml(const std::string& path, const std::string& camera_name,
                                      int width_px, int height_px,
                                      std::optional<ProjectionModel> model) {
  if (width_px < 0 || height_px < 0) {
    throw IntrinsicsFileError(path, "requested image size must be >= 0");
  }
  try {
    // The camera: the first whose name and image size match the request (a camera without a
    // size matches any); ViSP's parser needs its name, so the file's cameras are listed first.
    const std::vector<visp_adapter::CameraEntry> entries = visp_adapter::list_camera_xml(path);
    const bool size_requested = width_px > 0 && height_px > 0;
    bool saw_name = false;
    for (const visp_adapter::CameraEntry& e : entries) {
      if (!camera_name.empty() && e.name != camera_name) continue;
      saw_name = true;
      const bool sized = e.width_px > 0 && e.height_px > 0;
      if (size_requested && sized && (e.width_px != width_px || e.height_px != height_px)) continue;
      // The model: the one asked for; else the model with distortion when the camera has it
      // (the features are undistorted through it, core/camera/distortion.hpp, so the fuller
      // calibration is the better one); else the pinhole.
      ProjectionModel chosen = ProjectionModel::kWithDistortion;
      if (model) {
        chosen = *model;
      } else if (!has_model(e, ProjectionModel::kWithDistortion)) {
        chosen = ProjectionModel::kWithoutDistortion;
      }
      if (!has_model(e, chosen)) continue;
      const visp_adapter::CameraCalibration c =
          visp_adapter::read_camera_xml(path, e.name, to_adapter(chosen), e.width_px, e.height_px);
      CameraIntrinsics k;
      k.width_px = size_requested ? width_px : c.width_px;
      k.height_px = size_requested ? height_px : c.height_px;
      k.fx_px = c.px;
      k.fy_px = c.py;
      k.cx_px = c.u0;
      k.cy_px = c.v0;
      k.model = chosen;
      k.kud = c.kud;
      k.kdu = c.kdu;
      if (k.width_px <= 0 || k.height_px <= 0) {
        throw IntrinsicsFileError(path, "camera '" + e.name +
                                            "' has no <image_width>/<image_height> and none was requested");
      }
      require_valid(path, k);
      return k;
    }
    std::ostringstream os;
    if (!saw_name) {
      os << "no camera named '" << camera_name << "'";
    } else {
      os << "no camera";
      if (!camera_name.empty()) os << " '" << camera_name << "'";
      if (size_requested) os << " of image size " << width_px << "x" << height_px;
      os << " has a <model> of type "
         << (model ? to_string(*model)
                   : "perspectiveProjWithoutDistortion or perspectiveProjWithDistortion");
    }
    throw IntrinsicsFileError(path, os.str());
  } catch (const visp_adapter::CameraXmlError& e) {
    throw IntrinsicsFileError(path, e.cause());
  }
}

void save_visp_camera_xml(const CameraIntrinsics& k, const std::string& path,
                          const std::string& camera_name) {
  require_valid(path, k);
  visp_adapter::CameraCalibration c;
  c.name = camera_name;
  c.width_px = k.width_px;
  c.height_px = k.height_px;
  c.model = to_adapter(k.model);
  c.px = k.fx_px;
  c.py = k.fy_px;
  c.u0 = k.cx_px;
  c.v0 = k.cy_px;
  c.kud = k.kud;
  c.kdu = k.kdu;
  try {
    visp_adapter::write_camera_xml(path, c);
  } catch (const visp_adapter::CameraXmlError& e) {
    throw IntrinsicsFileError(path, e.cause());
  }
}

CameraIntrinsics load_intrinsics_plain(const std::string& path) {
  require_readable(path);
  const std::string ext = lower_extension(path);
  CameraIntrinsics k;
  if (ext == ".json") {
    std::ifstream in(path);
    nlohmann::json j;
    try {
      in >> j;
    } catch (const std::exception& e) {
      throw IntrinsicsFileError(path, std::string("not valid JSON: ") + e.what());
    }
    try {
      k = intrinsics_from_json(j);
    } catch (const std::invalid_argument& e) {
      throw IntrinsicsFileError(path, e.what());
    }
  } else if (ext == ".yaml" || ext == ".yml") {
    YAML::Node root;
    try {
      root = YAML::LoadFile(path);
    } catch (const std::exception& e) {
      throw IntrinsicsFileError(path, std::string("not valid YAML: ") + e.what());
    }
    auto get = [&](const char* key) -> double {
      if (!root.IsMap() || !root[key]) {
        throw IntrinsicsFileError(path, std::string("missing key '") + key + "'");
      }
      try {
        return root[key].as<double>();
      } catch (const std::exception&) {
        throw IntrinsicsFileError(path, std::string("non-numeric key '") + key + "'");
      }
    };
    k = intrinsics_from_keys(get);
  } else {
    throw IntrinsicsFileError(path, "unknown extension '" + ext + "' (expected .yaml, .yml, .json)");
  }
  require_valid(path, k);
  return k;
}

CameraIntrinsics load_intrinsics(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".xml") return load_visp_camera_xml(path);
  return load_intrinsics_plain(path);
}

void save_intrinsics_plain(const CameraIntrinsics& k, const std::string& path) {
  const std::string ext = lower_extension(path);
  std::ostringstream os;
  os.precision(17);
  if (ext == ".yaml" || ext == ".yml") {
    // The YAML form is the pinhole only: writing a model with distortion there would lose it.
    if (k.model != ProjectionModel::kWithoutDistortion) {
      throw IntrinsicsFileError(path, std::string("the YAML form holds no distortion (model ") +
                                          to_string(k.model) + "): write .json or ViSP .xml");
    }
    os << "width_px: " << k.width_px << "\nheight_px: " << k.height_px << "\nfx_px: " << k.fx_px
       << "\nfy_px: " << k.fy_px << "\ncx_px: " << k.cx_px << "\ncy_px: " << k.cy_px << "\n";
  } else {
    os << intrinsics_to_json(k).dump(2) << "\n";
  }
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw IntrinsicsFileError(path, "cannot open for writing");
    out << os.str();
    if (!out) throw IntrinsicsFileError(path, "write failed");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw IntrinsicsFileError(path, "rename failed: " + ec.message());
}

}  // namespace pepper::core::camera
