#pragma once
// The ceiling mosaic's data (issue 24; Blanc et al. 2004): the 2D landmarks lying on the ceiling
// plane, each with its planar pose in the mosaic frame and its descriptor, and the file that
// holds them. MosaicBuilder (mosaic_builder.hpp) builds one from teach frames; `teach --mode
// ceiling` saves it as MAP/mosaic.json (docs/method/ceiling.md, map_format.md).
//
// Frame and units: the mosaic frame is the robot's base frame at the first teach frame, projected
// on the ceiling plane: x forward, y left, metres, angles in radians counter-clockwise seen from
// ABOVE (as the base frame and the odometry, docs/conventions.md). A landmark's orientation is
// its ORB orientation expressed in those axes (observation.hpp).
//
// File (one JSON file, e.g. MAP/mosaic.json): {"format": "pepper-ceiling-mosaic",
// "format_version": 1, "px_per_m": the canonical scale the landmarks were seen at, "landmarks":
// [{"id", "x_m", "y_m", "orientation_rad", "observations", "descriptor": 64 hex digits}],
// "crc32": CRC-32 of the JSON dump without that field}. Saving is atomic (a sibling temporary
// file, fsync'ed, renamed into place, the folder fsync'ed); an invalid mosaic is refused before
// anything is written. Loading validates everything; every problem throws MosaicError whose
// message starts with the file's path.

#include <cstdint>
#include <filesystem>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace pepper::core::ceiling {

inline constexpr int kMosaicFormatVersion = 1;
inline constexpr int kMosaicDescriptorBytes = 32;  ///< ORB (landmarks.hpp)

struct MosaicLandmark {
  int64_t id = -1;               ///< unique in the mosaic, >= 0
  cv::Point2d position_m;        ///< in the mosaic frame
  double orientation_rad = 0.0;  ///< the landmark's orientation in the mosaic frame
  cv::Mat descriptor;            ///< 1 x kMosaicDescriptorBytes, CV_8U
  int observations = 1;          ///< frames it was matched in, >= 1
};

struct Mosaic {
  double px_per_m = 80.0;  ///< scale of the canonical view the landmarks come from, > 0
  std::vector<MosaicLandmark> landmarks;

  /// Messages naming each invalid field (landmark index and id); empty when valid.
  std::vector<std::string> validate() const;
};

/// A mosaic file that cannot be written, read or validated; what() starts with the file's path.
class MosaicError : public std::runtime_error {
 public:
  MosaicError(std::filesystem::path path, const std::string& what);
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// Writes `mosaic` atomically to `file` (replacing it). Throws MosaicError.
void save_mosaic(const Mosaic& mosaic, const std::filesystem::path& file);

/// Reads and validates a mosaic file. Throws MosaicError.
Mosaic load_mosaic(const std::filesystem::path& file);

}  // namespace pepper::core::ceiling
