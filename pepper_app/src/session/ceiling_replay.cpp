#include "session/ceiling_replay.hpp"

#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <utility>

#include "session/ceiling_map.hpp"
#include "session/ceiling_teach.hpp"

namespace pepper::app {

void check_taught_ceiling(const core::ceiling::CeilingTour& tour, const CeilingCameraSetup& setup,
                          const std::filesystem::path& tour_file) {
  if (!tour.ceiling) return;
  const double taught_m = tour.ceiling->above_camera_m;
  const double now_m = setup.camera.ceiling_above_cam_m;
  const double scale = now_m / taught_m;
  if (std::abs(scale - 1.0) <= kCeilingScaleTolerance) return;
  char text[512];
  std::snprintf(text, sizeof text,
                "%s: taught under a ceiling %.2f m above the floor (%.2f m above the camera), "
                "this replay's is %.2f m (%.2f m above the camera): every distance of the tour "
                "would be %.0f %% off; replay with the teach's ceiling (--set "
                "robot.ceiling_height_m=%.2f; mock: robots take their world's) or teach again "
                "under this one",
                tour_file.string().c_str(), tour.ceiling->height_m, taught_m,
                setup.ceiling_height_m, now_m, std::abs(scale - 1.0) * 100.0,
                tour.ceiling->height_m);
  throw std::invalid_argument(text);
}

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
  const std::filesystem::path tour_file = map_dir / kCeilingTourFileName;
  check_taught_ceiling(parts.tour, setup, tour_file);
  CeilingReplay r;
  if (!parts.tour.ceiling) {
    r.warnings.push_back(tour_file.string() +
                         ": taught before tours recorded their ceiling (format version 1): this "
                         "replay cannot check that its ceiling height is the teach's; teach "
                         "again to record it");
  }
  r.navigator = std::make_shared<core::ceiling::CeilingNavigator>(
      std::move(parts.mosaic), std::move(parts.tour), setup.camera, setup.cam_in_base_m, options);
  auto last = std::make_shared<core::ceiling::CeilingTelemetry>();
  r.step = [nav = r.navigator, last](const core::Frame& frame) {
    core::ceiling::CeilingStepResult result = nav->step(frame);
    *last = result.ceiling;
    return std::move(result.step);
  };
  r.telemetry_json = [last] { return ceiling_telemetry_to_json(*last); };
  return r;
}

nlohmann::json ceiling_telemetry_to_json(const core::ceiling::CeilingTelemetry& t) {
  nlohmann::json pose = nullptr;
  if (t.pose_known) {
    pose = {{"x_m", t.T_mosaic_base.x_m},
            {"y_m", t.T_mosaic_base.y_m},
            {"theta_rad", t.T_mosaic_base.theta_rad}};
  }
  return {{"fix", t.fix},
          {"prior_used", t.prior_used},
          {"matches", t.matches},
          {"inliers", t.inliers},
          {"pose_known", t.pose_known},
          {"T_mosaic_base", pose},
          {"coasted_m", t.coasted_m},
          {"perceive_ms", t.perceive_ms},
          {"localise_ms", t.localise_ms}};
}

}  // namespace pepper::app
