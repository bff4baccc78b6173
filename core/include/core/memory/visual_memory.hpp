#pragma once
// The visual memory of one taught tour (METHOD.md "Teach") and its folder format.
//
// In memory: the camera, the key images in tour order (the last one is the tour's final image,
// where replay stops), each with its source frame index, capture stamp and precomputed features
// (core/features/image_features.hpp), plus the effective configuration as JSON text.
//
// On disk, a map is a folder (docs/method/map_format.md):
//   manifest.json          format name + version, navigation mode (nav_mode.hpp; absent in
//                          maps saved before it: forward), camera intrinsics (with the
//                          projection model, intrinsics_json.hpp), parameters, key images in
//                          order (source frame index, t_ns, optional travelled_m and odom,
//                          file names, byte sizes, CRC-32s, feature counts), final image
//                          index, and the manifest's own CRC-32
//   key_NNNN.png           the key image, 8-bit grey PNG
//   key_NNNN.feat          its features, little binary format with a version and a trailing
//                          CRC-32 (lines + LBD descriptors, corners, ORB keypoints + descriptors)
// Loading needs no recomputation except the derived KLT pyramids (build_klt_pyramid).
//
// Saving is atomic: everything goes into a sibling temporary folder, each file and the folder
// are fsync'ed, the manifest is written last, then the folder is renamed into place (an existing
// map is first renamed aside, then removed). A crash leaves either the old map, the new map, or
// no map plus a temporary folder that does not load (no manifest, or checksums that disagree).
//
// Errors: every problem with a map on disk (missing or extra-short file, bad checksum, wrong
// version, malformed manifest, intrinsics or mode mismatch, I/O failure) throws MapError naming
// the offending file. Loading never crashes on corrupt input: every length is bounded by the bytes
// present before anything is allocated. Not thread-safe for concurrent saves to one path.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/camera/intrinsics.hpp"
#include "core/features/image_features.hpp"
#include "core/nav_mode.hpp"
#include "core/odometry.hpp"

namespace pepper::core::memory {

inline constexpr int kMapFormatVersion = 1;
inline constexpr int kFeatureFileVersion = 1;

struct KeyImage {
  int64_t source_frame_index = -1;   ///< index of the frame in the teach sequence
  int64_t t_ns = 0;                  ///< its capture stamp
  /// Distance the base drove from the tour's first frame to this image, m, from the robot's
  /// odometry, or the speeds commanded during teach where frames had none
  /// (mapping/drive_odometer.hpp); NaN when unknown (a map taught from
  /// plain images, or saved before the field existed). Never decreases along the tour.
  double travelled_m = std::numeric_limits<double>::quiet_NaN();
  /// The robot's odometry when the image was taken (core/odometry.hpp, teach's odometry frame);
  /// nullopt when unknown (a map taught without odometry, or saved before the field existed).
  std::optional<OdometryPose> odom;
  features::ImageFeatures features;  ///< includes the grey image
};

struct VisualMemory {
  NavMode mode = NavMode::kForward;    ///< the view it was taught by (forward: the key images)
  CameraIntrinsics camera;             ///< intrinsics at the key images' size
  std::vector<KeyImage> key_images;    ///< tour order; back() is the final image
  std::string parameters_json = "{}";  ///< effective configuration (JSON object text)

  int final_index() const { return static_cast<int>(key_images.size()) - 1; }
};

class MapError : public std::runtime_error {
 public:
  enum class Kind {
    kIo,                  ///< cannot read/write/rename (OS error)
    kMissingFile,         ///< manifest, image or features file absent
    kSizeMismatch,        ///< file size differs from the manifest (truncated / appended)
    kChecksumMismatch,    ///< CRC-32 differs (bit flips)
    kMalformed,           ///< parse error / impossible value inside a file
    kWrongVersion,        ///< format version not supported
    kIntrinsicsMismatch,  ///< map camera differs from the expected one
    kInvalidMap,          ///< a map object that cannot be saved (e.g. fewer than 2 key images)
    kModeMismatch,        ///< map taught in another navigation mode than the expected one
  };
  MapError(Kind kind, std::filesystem::path path, const std::string& what);
  Kind kind() const { return kind_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  Kind kind_;
  std::filesystem::path path_;
};

const char* to_string(MapError::Kind kind);

/// Writes `map` atomically to folder `dir` (replacing an existing map there). Throws MapError.
/// `write_extra`, when given, writes the mode's own files (the ceiling mosaic and tour) into the
/// temporary folder it is passed, before that folder is renamed into place: all of the map's files
/// replace the previous map together or not at all. What it throws is rethrown, the previous map
/// untouched and the temporary folder removed.
void save_map(const VisualMemory& map, const std::filesystem::path& dir,
              const std::function<void(const std::filesystem::path& tmp_dir)>& write_extra = {});

struct LoadOptions {
  /// When set, the map's camera must equal this one scaled to the map's image size (relative
  /// tolerance 1e-6 on focal lengths and principal point), else kIntrinsicsMismatch.
  std::optional<CameraIntrinsics> expected_camera;
  bool build_klt_pyramids = false;  ///< rebuild derived pyramids (else leave them empty)
  /// When set, the map must have been taught in this mode, else kModeMismatch naming both.
  std::optional<NavMode> expected_mode;
};

/// Loads and checks a map folder. Throws MapError naming the offending file.
VisualMemory load_map(const std::filesystem::path& dir, const LoadOptions& options = {});

/// "map info": what a map holds, from a loaded map.
struct MapSummary {
  NavMode mode = NavMode::kForward;
  int key_image_count = 0;
  int final_index = -1;
  double taught_duration_s = 0.0;  ///< t_ns of the final image minus that of the first
  int64_t first_frame_index = -1;
  int64_t last_frame_index = -1;
  CameraIntrinsics camera;
  struct PerKeyImage {
    int64_t source_frame_index = -1;
    int64_t t_ns = 0;
    int lines = 0;
    int corners = 0;
    int keypoints = 0;
    double travelled_m = std::numeric_limits<double>::quiet_NaN();  ///< KeyImage::travelled_m
    std::optional<OdometryPose> odom;                               ///< KeyImage::odom
  };
  std::vector<PerKeyImage> key_images;

  /// Human-readable multi-line text (one line per key image).
  std::string to_text() const;
};

MapSummary summarize(const VisualMemory& map);

/// Summary read from the manifest only (fast; checks the manifest's version and CRC but not the
/// key image files). Throws MapError.
MapSummary read_map_info(const std::filesystem::path& dir);

}  // namespace pepper::core::memory
