#pragma once
// Map management for the operator (issue 25): find the maps under a folder (`map list`), judge
// where a taught tour is weak (`map show`), and cut key images off its start or end (`map
// trim`) without teaching again. Reading and writing go through core/memory (load_map,
// read_map_info, save_map: atomic), so a trimmed map is checked like any other.

#include <cstdint>
#include <ctime>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/memory/visual_memory.hpp"
#include "session/taught_path.hpp"

namespace pepper::app {

/// One map found by find_maps: what `map list` prints.
struct MapListing {
  std::filesystem::path dir;
  std::string name;  ///< `dir` relative to the searched folder ("." is the folder's own name)
  bool readable = false;
  std::string problem;  ///< why not readable (the MapError's text)
  int key_images = 0;
  double length_m = std::numeric_limits<double>::quiet_NaN();  ///< taught length; NaN: unknown
  std::time_t saved = 0;     ///< manifest.json's modification time (when the map was saved)
  std::uintmax_t bytes = 0;  ///< all files of the folder
};

/// Every folder under `root` (itself included, at most `max_depth` levels down) holding a
/// manifest.json, in name order; map folders are not searched further (a map holds no maps).
/// Reads manifests only (read_map_info). Throws std::runtime_error when `root` is not a folder.
std::vector<MapListing> find_maps(const std::filesystem::path& root, int max_depth = 3);

/// "lab/tour  10 key images  4.51 m  2026-11-26 12:20  1.2 MB" (or "NAME  unreadable: ...").
std::string to_text(const MapListing& m);

/// A place where the tour is weak, with what to do about it.
struct TourWarning {
  int key_index = -1;  ///< the key image concerned (a gap: the one after it)
  std::string text;
};

struct TourCheckOptions {
  /// A key image with fewer lines + points may not be matched in replay (the teach UI's "weak"
  /// key images: TeachSessionOptions::min_key_features).
  int min_features = 40;
  /// A gap between key images is long when it is more than this many times the map's median gap
  /// and more than min_long_gap_m: the replay then servoes on one key image for a long way, and
  /// a long gap usually means a view with little to share (a blank wall ahead).
  double long_gap_factor = 3.0;
  double min_long_gap_m = 1.5;
  /// The same in taught time, for maps without distances (plain image folders).
  double min_long_gap_s = 15.0;
};

/// Weak places of a tour (summary: read_map_info or summarize), in tour order. Gaps are measured
/// with the map's distances (KeyImage::travelled_m), else with the taught time.
std::vector<TourWarning> check_tour(const core::memory::MapSummary& summary,
                                    const TourCheckOptions& options = {});

/// Throws std::invalid_argument naming the allowed range unless 0 <= from < to <= final_index
/// (a map keeps at least two key images).
void check_trim_range(int from, int to, int final_index);

/// The key images from..to (inclusive, tour indices) as a map of their own: distances start at
/// 0 at the new first key image; stamps, odometry and features are kept. Throws as
/// check_trim_range.
core::memory::VisualMemory trim_map(const core::memory::VisualMemory& map, int from, int to);

/// The taught path of the trimmed map: the key images' positions from..to, and the frames'
/// positions between their source frames when the path has them (else the key positions).
TaughtPath trim_taught_path(const TaughtPath& path, const core::memory::VisualMemory& map, int from,
                            int to);

}  // namespace pepper::app
