#pragma once
// A ceiling-mode map folder (issue 24; docs/method/map_format.md): the map (manifest.json and
// key images, core/memory/visual_memory.hpp, mode "ceiling", key images = the relay images),
// plus MAP/mosaic.json (core/ceiling/mosaic.hpp) and MAP/ceiling_tour.json
// (core/ceiling/ceiling_tour.hpp). Each part has its checksums; all three are written into the
// map's temporary folder, whose one atomic rename replaces the previous map (a crash leaves the
// old map or the new one); a part damaged later is named on load.
// Loading checks the parts against each other: one relay image per key image (same frames),
// every landmark a relay image sees in the mosaic. Errors throw (MapError, MosaicError,
// CeilingTourError, or std::runtime_error naming the file for a disagreement).

#include <filesystem>
#include <string>
#include <vector>

#include "core/ceiling/ceiling_tour.hpp"
#include "core/ceiling/mosaic.hpp"
#include "core/memory/visual_memory.hpp"
#include "session/ceiling_teach.hpp"

namespace pepper::app {

inline constexpr const char* kMosaicFileName = "mosaic.json";
inline constexpr const char* kCeilingTourFileName = "ceiling_tour.json";

/// Writes the three parts into `dir` (replacing a map there). Throws on any failure.
void save_ceiling_map(const CeilingMap& map, const std::filesystem::path& dir);

/// The ceiling parts of a ceiling-mode map, checked against its manifest summary.
struct CeilingParts {
  core::ceiling::Mosaic mosaic;
  core::ceiling::CeilingTour tour;
};
CeilingParts load_ceiling_parts(const std::filesystem::path& dir,
                                const core::memory::MapSummary& summary);

/// `map info`'s ceiling lines: landmarks, relay images (frame, pose), breaks, drift figures.
std::string ceiling_summary_text(const CeilingParts& parts);

/// Warnings about the taught tour: frames without a pose, breaks of the relay chain, and a
/// chained pose that disagrees with the odometry by more than max(0.1 m, 5 % of the driven
/// distance) (the mosaic drifted 0.4 % on the test hall, docs/method/ceiling.md).
std::vector<std::string> ceiling_warnings(const core::ceiling::CeilingTour& tour);

}  // namespace pepper::app
