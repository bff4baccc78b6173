#pragma once
// `pepper_app map show`: one self-contained HTML page about a map (issue 25): a summary, the
// warnings where the tour is weak (offline/map_tools.hpp), the taught path (the mock world's
// ground truth when the map carries taught_path.json, else the key images' odometry), and every
// key image as a thumbnail with its line and point counts; weak ones are framed in red.

#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/memory/visual_memory.hpp"
#include "offline/map_tools.hpp"
#include "report/html_report.hpp"
#include "session/taught_path.hpp"

namespace pepper::app::report {

/// Every key image of `map` (loaded with its images) as a numbered thumbnail with its line and
/// point counts, in tour order; those in `flagged` framed in red. HTML with its own style, for
/// `map show` and the evaluation report.
std::string key_image_thumbnails(const core::memory::VisualMemory& map,
                                 const std::set<int>& flagged);

/// The page for `map` (loaded with its images), titled after `name`.
HtmlReport map_page(const std::string& name, const core::memory::VisualMemory& map,
                    const std::vector<TourWarning>& warnings,
                    const std::optional<TaughtPath>& taught_path);

}  // namespace pepper::app::report
