#pragma once
// Which view the robot navigates by (issue 24): the forward-looking camera of the first paper
// (the only one teach and replay implement), or the ceiling (Blanc et al. 2004, docs/method/
// ceiling.md: only the canonical ceiling view exists so far). A map records the mode it was
// taught in (docs/method/map_format.md); a map of one mode is refused by a run of the other.

#include <optional>
#include <string>

namespace pepper::core {

enum class NavMode { kForward, kCeiling };

/// "forward" / "ceiling": the spelling of --mode, of the map manifest and of messages.
inline const char* to_string(NavMode mode) {
  return mode == NavMode::kCeiling ? "ceiling" : "forward";
}

/// The inverse of to_string; std::nullopt for any other text.
inline std::optional<NavMode> nav_mode_from_string(const std::string& name) {
  if (name == "forward") return NavMode::kForward;
  if (name == "ceiling") return NavMode::kCeiling;
  return std::nullopt;
}

}  // namespace pepper::core
