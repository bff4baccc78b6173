#pragma once
// JSON form of the navigator's per-frame output, shared by replay-log, the teach UI and the
// replay recorder. Field names are the telemetry's own (units in names); NaN becomes null.
// The feature overlay is not part of telemetry_to_json (per-frame logs stay small); the teach UI
// gets it from overlay_to_json in its frame header format (docs/teach_ui.md "Frame").

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/ceiling/mosaic_builder.hpp"
#include "core/features/feature_overlay.hpp"
#include "core/navigator/navigator.hpp"

namespace pepper::app {

nlohmann::json command_to_json(const core::navigator::Command& command);
nlohmann::json telemetry_to_json(const core::navigator::Telemetry& telemetry);

/// The robot's odometry read with a frame: {"x_m", "y_m", "yaw_rad"}, or null when the frame had
/// none. Telemetry lines carry it next to the navigator's telemetry as "odom".
nlohmann::json odometry_to_json(const std::optional<core::OdometryPose>& odom);

/// {"lines":[{label, color, width_px, segments:[[u0,v0,u1,v1],...]}],
///  "points":[{label, color, radius_px, uv:[[u,v],...]}]} with pixels rounded to integers;
/// the labels are "<what> lines" and "<what> points" (e.g. what = "detected").
nlohmann::json overlay_to_json(const core::features::FeatureOverlay& overlay,
                               const std::string& what);

/// Ceiling mode's overlay (teach and replay views): the points as "ceiling landmarks" and
/// no lines group (ceiling landmarks are points only: no empty legend entry).
nlohmann::json ceiling_overlay_to_json(const core::features::FeatureOverlay& overlay);

/// The replay view's second caption line in ceiling mode, from one step's ceiling telemetry
/// (ceiling_telemetry_to_json): the localiser's inliers of its matches and the pose in the
/// mosaic (x, y in metres, heading in degrees), "coasting on odometry" with the distance when
/// the pose is not this frame's fix, "no pose in the mosaic" when none is known.
std::string ceiling_overlay_caption(const nlohmann::json& ceiling);

/// The teach panel's state in ceiling mode (the UI's "teach" state; docs/teach_ui.md): the
/// distance driven, and under "ceiling" this frame's landmarks (matched to the mosaic, added to
/// it, whether the frame got a pose), the mosaic's landmarks so far, the frames without a pose
/// and the loops closed. The relay images are chosen when the teach finishes, so there is no key
/// image list.
nlohmann::json ceiling_teach_state(double distance_m, const core::ceiling::MosaicFrameResult& step,
                                   size_t mosaic_landmarks, int64_t frames_without_pose,
                                   size_t loops_closed);

}  // namespace pepper::app
