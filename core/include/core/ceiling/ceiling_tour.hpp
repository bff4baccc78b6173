#pragma once
// What a ceiling-mode teach recorded besides the mosaic (issue 24): the relay images' poses in
// the mosaic frame and the mosaic landmarks each one sees (the replay's targets), the breaks of
// the relay chain (relay_images.hpp) and the tour's drift indicators. A ceiling-mode map folder
// holds it next to the mosaic (MAP/ceiling_tour.json, MAP/mosaic.json); the relay images
// themselves are the map's key images, in the same order (docs/method/map_format.md).
//
// Frames and units: poses T_mosaic_base of the base in the mosaic frame (mosaic.hpp: metres,
// radians counter-clockwise seen from above).
//
// File: {"format": "pepper-ceiling-tour", "format_version": 3, "frames", "unlocalised_frames",
// "relay_images": [{"frame", "x_m", "y_m", "theta_rad", "landmark_ids": [...]}], "breaks": [...],
// "odometry_disagreement_m" (null when the robot gave no odometry), "driven_m", "ceiling":
// {"height_m", "above_camera_m"}, "height_check": {"status", "configured_height_m",
// "configured_above_camera_m", "windows", "windows_rejected", "windows_turning", "odometry_m",
// "scale_ratio", "scale_ratio_spread", "scale_ratio_sigma", "estimated_above_camera_m",
// "estimated_height_m", "estimated_sigma_m", "disagrees"} (height_check.hpp; null when not
// checked), "crc32"}: CRC-32 of the JSON dump without that field. Versions 1 (before the ceiling
// was recorded: no "ceiling", a replay cannot check it) and 2 (before the height check: no
// "height_check") are still read. Saved atomically (sibling temporary file, fsync, rename,
// folder fsync); loading validates everything and every problem throws CeilingTourError whose
// message starts with the file's path.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/ceiling/height_check.hpp"
#include "core/ceiling/planar_rigid.hpp"

namespace pepper::core::ceiling {

inline constexpr int kCeilingTourFormatVersion = 3;  ///< written; 1 and 2 are still read

/// The ceiling the teach saw: its distance above the camera sets the scale of every metre in the
/// mosaic and the tour, so a replay must see the same ceiling (ceiling_replay.hpp checks it).
struct TaughtCeiling {
  double height_m = 0.0;        ///< above the floor (robot.ceiling_height_m or the mock's world)
  double above_camera_m = 0.0;  ///< above the optical centre at the teach's head pitch, > 0
};

struct RelayImageRecord {
  int64_t frame = -1;                 ///< teach frame index (0 = the tour's first), >= 0
  PlanarPose T_mosaic_base;           ///< the builder's pose of that frame
  std::vector<int64_t> landmark_ids;  ///< kept mosaic landmarks it saw
};

struct CeilingTour {
  int64_t frames = 0;                          ///< frames given to the builder
  int64_t unlocalised_frames = 0;              ///< of them, frames the builder found no pose for
  std::vector<RelayImageRecord> relay_images;  ///< increasing frames, >= 2
  /// i: relay i -> i + 1 violates the conditions (relay_images.hpp) and the teach's chain was
  /// cut between them (no odometry carried it; ceiling_teach.cpp)
  std::vector<int64_t> breaks;
  /// Distance between the chained pose and the robot's odometry at the last localised frame,
  /// both relative to the first frame, m; nullopt without odometry. Either may have drifted.
  std::optional<double> odometry_disagreement_m;
  double driven_m = 0.0;  ///< the tour's length (the map's measure), >= 0
  /// The teach's ceiling; nullopt only in files of format version 1.
  std::optional<TaughtCeiling> ceiling;
  /// The teach's ceiling height checked against the odometry (height_check.hpp); nullopt in
  /// files of format versions 1 and 2.
  std::optional<HeightCheck> height_check;

  /// Messages naming each invalid field; empty when valid.
  std::vector<std::string> validate() const;
};

/// A tour file that cannot be written, read or validated; what() starts with the file's path.
class CeilingTourError : public std::runtime_error {
 public:
  CeilingTourError(std::filesystem::path path, const std::string& what);
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// A height check as the file's "height_check" object (the fields above; NaN: null). The teach's
/// `ceiling_height_check` event carries the same object.
nlohmann::json height_check_to_json(const HeightCheck& h);

/// Writes `tour` atomically to `file`. Throws CeilingTourError (an invalid tour is not written).
void save_ceiling_tour(const CeilingTour& tour, const std::filesystem::path& file);

/// Reads and validates a tour file. Throws CeilingTourError.
CeilingTour load_ceiling_tour(const std::filesystem::path& file);

}  // namespace pepper::core::ceiling
