#pragma once
// The ground-truth path of a tour taught on the mock robot, kept next to the map so that a later
// standalone replay on the same mock world can draw the taught and the replayed paths in the
// teach UI's top view. A real robot has no ground truth, so its maps have no such file.
//
// File MAP_DIR/taught_path.json (written after the map: save_map replaces the whole folder, so
// re-teaching or `map build` into the folder drops a stale path):
//   {"format":"pepper-taught-path","version":1,"world":"robotics_room",
//    "path_m":[[x,y],...],"key_images_m":[[x,y],...]}
// Positions are the base's (x, y) in the mock world frame, metres, one per recorded frame and
// one per key image. `world` is the mock world's name: a replay in another world ignores it.

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace pepper::app {

inline constexpr const char* kTaughtPathFile = "taught_path.json";

struct TaughtPath {
  std::string world;
  std::vector<Eigen::Vector2d> path_m;
  std::vector<Eigen::Vector2d> key_images_m;
};

/// Writes MAP_DIR/taught_path.json (temp file + rename). Throws std::runtime_error naming it.
void save_taught_path(const std::filesystem::path& map_dir, const TaughtPath& path);

/// Reads MAP_DIR/taught_path.json; nullopt when there is none. Throws std::runtime_error naming
/// the file when it is not a valid taught path.
std::optional<TaughtPath> load_taught_path(const std::filesystem::path& map_dir);

/// Distance (m) from `p_m` to the polyline `path_m` (a single point: the distance to it);
/// NaN for an empty path. The replay's lateral error against ground truth on the mock robot.
double distance_to_path_m(const std::vector<Eigen::Vector2d>& path_m, const Eigen::Vector2d& p_m);

}  // namespace pepper::app
