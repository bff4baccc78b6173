#pragma once
// Camera calibration files in ViSP's XML format, read and written by ViSP's own
// vpXmlParserCamera, behind plain structs (no ViSP type: callers compile as C++20, ViSP 3.5 only
// as C++17; visp_adapter/CMakeLists.txt).
//
// The format: <root><camera><name/><image_width/><image_height/><model><type/><px/><py/><u0/><v0/>
// [<kud/><kdu/>]</model>...</camera>...</root>; one camera (name, image size) may hold one <model>
// per projection type. ViSP's two perspective models:
//   perspectiveProjWithoutDistortion  u = u0 + px x, v = v0 + py y
//   perspectiveProjWithDistortion     u = u0 + px x (1 + kud r^2), v = v0 + py y (1 + kud r^2),
//                                     r^2 = x^2 + y^2 (undistorted normalised coordinates); kdu the
//                                     coefficient of the inverse map, r^2 from the distorted ones.
// (ViSP's third, Kannala-Brandt, is not read: no Pepper calibration uses it.)
//
// vpXmlParserCamera can only fetch a camera it is given by name, and says nothing about why a
// read failed, so list_camera_xml() reads the file's structure with libxml2 (ViSP's own XML
// dependency) to choose a default camera and to name what the file does hold in errors.
//
// Errors: every failure (missing, unreadable or malformed file, no such camera or model, a write
// ViSP refuses) throws CameraXmlError, whose what() starts with the file path.
// Thread-safety: ViSP prints "Found camera with name ..." on std::cout while it parses or saves;
// these functions silence std::cout for the duration of the ViSP call (under a mutex), so call
// them while no other thread writes to std::cout (the project reads cameras at start-up).

#include <stdexcept>
#include <string>
#include <vector>

namespace pepper::visp_adapter {

enum class CameraModel { kPerspectiveWithoutDistortion, kPerspectiveWithDistortion };

/// ViSP's name of the model ("perspectiveProjWithoutDistortion", "perspectiveProjWithDistortion").
const char* to_string(CameraModel model);

/// One camera model as ViSP stores it; pixels, kud/kdu in normalised units (0 without distortion).
struct CameraCalibration {
  std::string name;
  int width_px = 0;   ///< image size the calibration is for; 0 when the file gives none
  int height_px = 0;
  CameraModel model = CameraModel::kPerspectiveWithoutDistortion;
  double px = 0.0;
  double py = 0.0;
  double u0 = 0.0;
  double v0 = 0.0;
  double kud = 0.0;
  double kdu = 0.0;
};

/// What a file holds: one entry per <camera>, in file order, with its models' types (types ViSP
/// does not know are left out).
struct CameraEntry {
  std::string name;
  int width_px = 0;
  int height_px = 0;
  std::vector<CameraModel> models;
};

/// A camera file that cannot be read or written; what() is "<path>: <cause>".
class CameraXmlError : public std::runtime_error {
 public:
  CameraXmlError(const std::string& path, const std::string& cause);
  const std::string& path() const { return path_; }
  const std::string& cause() const { return cause_; }

 private:
  std::string path_;
  std::string cause_;
};

/// The cameras of a ViSP camera file. Throws CameraXmlError for a missing or malformed file
/// (libxml2's message and line) or a file with no <camera> under <root>.
std::vector<CameraEntry> list_camera_xml(const std::string& path);

/// vpXmlParserCamera::parse: the first camera named `name` that has `model`, among those of
/// image size width_px x height_px (both 0: any size). Throws CameraXmlError naming the request
/// and listing what the file holds when there is none.
CameraCalibration read_camera_xml(const std::string& path, const std::string& name, CameraModel model,
                                  int width_px = 0, int height_px = 0);

/// vpXmlParserCamera::save: adds `calibration` to the file (created when missing; ViSP keeps the
/// file's other cameras and models). Throws CameraXmlError when the file already holds that
/// model for that camera name and size (ViSP does not overwrite one), or cannot be written.
void write_camera_xml(const std::string& path, const CameraCalibration& calibration);

}  // namespace pepper::visp_adapter
