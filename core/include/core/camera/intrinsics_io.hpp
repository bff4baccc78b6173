#pragma once
// Camera intrinsics files: ViSP camera XML, read and written by ViSP's own vpXmlParserCamera
// through visp_adapter (the core calls it through plain structs; ViSP's headers are C++17 only),
// both perspective models; and a plain YAML or JSON form (pinhole only).
//
// Plain form (YAML or JSON, same keys; pixels, pixel centres at integer coordinates):
//   { "width_px": 640, "height_px": 480, "fx_px": 596.26, "fy_px": 597.44,
//     "cx_px": 318.8, "cy_px": 238.32 }
// ViSP XML: <root><camera><name>..</name><image_width>..</image_width><image_height>..
//   <model><type>perspectiveProjWithoutDistortion</type><px/><py/><u0/><v0/></model>
//   <model><type>perspectiveProjWithDistortion</type><px/><py/><u0/><v0/><kud/><kdu/></model>
//   </camera></root>; px -> fx_px, py -> fy_px, u0 -> cx_px, v0 -> cy_px, kud -> kud, kdu -> kdu,
//   the <type> -> CameraIntrinsics::model (ViSP's convention is the same pinhole, intrinsics.hpp).
//
// Errors: every failure (missing file, malformed file, missing key, no matching camera or model,
// invalid values per CameraIntrinsics::validate()) throws IntrinsicsFileError whose message starts
// with the file path. Nothing is cached. The XML functions silence std::cout while ViSP runs
// (visp_adapter/camera_xml.hpp): call them before starting threads that print.

#include <optional>
#include <stdexcept>
#include <string>

#include "core/camera/intrinsics.hpp"

namespace pepper::core::camera {

/// Environment failure while reading an intrinsics file; what() names the file and the cause.
class IntrinsicsFileError : public std::runtime_error {
 public:
  IntrinsicsFileError(const std::string& path, const std::string& cause);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// Reads a ViSP camera XML file. `camera_name` empty: the first camera of the file. When
/// `width_px`/`height_px` are > 0 the camera with that image size is selected (as ViSP does);
/// when the file gives no image size and none is requested, IntrinsicsFileError. `model`: the
/// projection model to read; std::nullopt takes the camera's perspectiveProjWithDistortion model
/// when it has one (the features are undistorted through it, core/camera/distortion.hpp), else
/// its perspectiveProjWithoutDistortion model. The result records the model read.
CameraIntrinsics load_visp_camera_xml(const std::string& path, const std::string& camera_name = "",
                                      int width_px = 0, int height_px = 0,
                                      std::optional<ProjectionModel> model = std::nullopt);

/// Adds `k` (its model and parameters, its image size) as camera `camera_name` to a ViSP camera
/// XML file through vpXmlParserCamera (the file is created when missing; its other cameras and
/// models are kept). IntrinsicsFileError when k is invalid, the file already holds this model
/// for this camera and size (ViSP does not overwrite one), or the file cannot be written.
void save_visp_camera_xml(const CameraIntrinsics& k, const std::string& path,
                          const std::string& camera_name);

/// Reads the plain YAML (.yaml/.yml) or JSON (.json) form described above.
CameraIntrinsics load_intrinsics_plain(const std::string& path);

/// Dispatch on the extension: .xml -> ViSP XML, .yaml/.yml/.json -> plain form.
CameraIntrinsics load_intrinsics(const std::string& path);

/// Writes the plain form (YAML when the extension is .yaml/.yml, else JSON). Throws
/// IntrinsicsFileError when the file cannot be written.
void save_intrinsics_plain(const CameraIntrinsics& k, const std::string& path);

}  // namespace pepper::core::camera
