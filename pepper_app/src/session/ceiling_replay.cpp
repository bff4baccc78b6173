#include "session/ceiling_replay.hpp"

#include <stdexcept>

#include "session/ceiling_map.hpp"
#include "session/ceiling_teach.hpp"

namespace pepper::app {

CeilingReplay make_ceiling_replay(const sim::MockRobot* robot, double ceiling_height_m,
                                  const std::filesystem::path& map_dir,
                                  const core::memory::VisualMemory& map, double head_pitch_rad,
                                  const core::ceiling::CeilingNavigatorOptions& options) {
  if (map.mode != core::NavMode::kCeiling) {
    throw std::invalid_argument(map_dir.string() + ": not a ceiling-mode map");
  }
  CeilingParts parts = load_ceiling_parts(map_dir, core::memory::summarize(map));
  // The map's camera: the session checks that the started camera agrees with it.
  const CeilingCameraSetup setup =
      ceiling_camera_for(robot, ceiling_height_m, map.camera, head_pitch_rad);
  CeilingReplay r;
  r.navigator = std::make_shared<core::ceiling::CeilingNavigator>(
      std::move(parts.mosaic), std::move(parts.tour), setup.camera, setup.cam_in_base_m, options);
  r.step = [nav = r.navigator](const core::Frame& frame) { return nav->step(frame).step; };
  return r;
}

}  // namespace pepper::app
