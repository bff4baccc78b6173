#pragma once
// Loading camera intrinsics from files: ViSP camera XML (the format written by ViSP's
// vpXmlParserCamera; model `perspectiveProjWithoutDistortion`) and a plain YAML or JSON form.
// The XML is read by our own small reader: ViSP 3.5's headers do not compile as C++20 with GCC 12
// (vpArray2D constructor declarations), see intrinsics_io.cpp. Subsampling fields are ignored.
//
// Plain form (YAML or JSON, same keys; pixels, pixel centres at integer coordinates):
//   { "width_px": 640, "height_px": 480, "fx_px": 596.26, "fy_px": 597.44,
//     "cx_px": 318.8, "cy_px": 238.32 }
// ViSP XML: <root><camera><name>..</name><image_width>..</image_width><image_height>..
//   <model><type>perspectiveProjWithoutDistortion</type><px/><py/><u0/><v0/></model></camera>
//   px -> fx_px, py -> fy_px, u0 -> cx_px, v0 -> cy_px (ViSP's convention is the same pinhole).
//
// Errors: every failure (missing file, unparsable file, missing key, no matching camera, invalid
// values per CameraIntrinsics::validate()) throws IntrinsicsFileError whose message starts with
// the file path. Nothing is cached; functions are thread-safe.

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
/// when the file gives no image size and none is requested, IntrinsicsFileError.
CameraIntrinsics load_visp_camera_xml(const std::string& path, const std::string& camera_name = "",
                                      int width_px = 0, int height_px = 0);

/// Reads the plain YAML (.yaml/.yml) or JSON (.json) form described above.
CameraIntrinsics load_intrinsics_plain(const std::string& path);

/// Dispatch on the extension: .xml -> ViSP XML, .yaml/.yml/.json -> plain form.
CameraIntrinsics load_intrinsics(const std::string& path);

/// Writes the plain form (YAML when the extension is .yaml/.yml, else JSON). Throws
/// IntrinsicsFileError when the file cannot be written.
void save_intrinsics_plain(const CameraIntrinsics& k, const std::string& path);

}  // namespace pepper::core::camera
