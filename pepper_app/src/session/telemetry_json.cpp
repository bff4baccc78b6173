#include "session/telemetry_json.hpp"

#include <cmath>
#include <cstdio>

namespace pepper::app {
namespace {

nlohmann::json num(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

// Whole pixels are enough to draw and keep a frame's overlay at a few KB of JSON.
long px(float v) { return std::lround(v); }

// Colours of the page's legend: lines green, points red (distinct on a grey camera image).
constexpr const char* kLineColor = "#22c55e";
constexpr const char* kPointColor = "#ef4444";

}  // namespace

nlohmann::json command_to_json(const core::navigator::Command& c) {
  return {{"v_m_s", c.v_m_s},
          {"omega_rad_s", c.omega_rad_s},
          {"stop", c.stop},
          {"reason", core::navigator::to_string(c.reason)}};
}

nlohmann::json telemetry_to_json(const core::navigator::Telemetry& t) {
  using core::navigator::to_string;
  return {
      {"t_ns", t.t_ns},
      {"frame_index", t.frame_index},
      {"state", to_string(t.state)},
      {"reason", to_string(t.reason)},
      {"ip", t.ip},
      {"in", t.in},
      {"inn", t.inn},
      {"switched", t.switched},
      {"switch_streak", t.switch_streak},
      {"switch_criterion", t.switch_criterion},
      {"n_lines_next", t.n_lines_next},
      {"n_points_next", t.n_points_next},
      {"n_lines_next_next", t.n_lines_next_next},
      {"n_points_next_next", t.n_points_next_next},
      {"n_prev", t.n_prev},
      {"n_three_view_next", t.n_three_view_next},
      {"n_three_view_prev", t.n_three_view_prev},
      {"next_scale_ratio", num(t.next_scale_ratio)},
      {"line_err_next", num(t.line_err_next)},
      {"line_err_next_next", num(t.line_err_next_next)},
      {"point_err_next", num(t.point_err_next)},
      {"point_err_next_next", num(t.point_err_next_next)},
      {"J_L", num(t.J_L)},
      {"J_P", num(t.J_P)},
      {"used_lines", t.used_lines},
      {"used_points", t.used_points},
      {"vnhv_lateral_m", num(t.vnhv_lateral_m)},
      {"vnhv_heading_rad", num(t.vnhv_heading_rad)},
      {"vnhv_model_points", t.vnhv_model_points},
      {"vnhv_structures", t.vnhv_structures},
      {"vnhv_fix_refused", t.vnhv_fix_refused},
      {"vnhv_fix_lateral_m", num(t.vnhv_fix_lateral_m)},
      {"vnhv_fix_heading_rad", num(t.vnhv_fix_heading_rad)},
      {"vnhv_fix_d2", num(t.vnhv_fix_d2)},
      {"vnhv_fix_weight", num(t.vnhv_fix_weight)},
      {"vnhv_fix_r_units", num(t.vnhv_fix_r_units)},
      {"vnhv_gate_dx_m", num(t.vnhv_gate_dx_m)},
      {"vnhv_gate_dy_m", num(t.vnhv_gate_dy_m)},
      {"vnhv_gate_dyaw_rad", num(t.vnhv_gate_dyaw_rad)},
      {"vnhv_gate_sigma_x_m", num(t.vnhv_gate_sigma_x_m)},
      {"vnhv_gate_sigma_y_m", num(t.vnhv_gate_sigma_y_m)},
      {"vnhv_gate_sigma_yaw_rad", num(t.vnhv_gate_sigma_yaw_rad)},
      {"vnhv_fix_room_probability", num(t.vnhv_fix_room_probability)},
      {"odom_lateral_m", num(t.odom_lateral_m)},
      {"odom_heading_rad", num(t.odom_heading_rad)},
      {"odom_lateral_sigma_m", num(t.odom_lateral_sigma_m)},
      {"odom_lateral_sigma_grown_m", num(t.odom_lateral_sigma_grown_m)},
      {"odom_past_next_m", num(t.odom_past_next_m)},
      {"odom_along_sigma_m", num(t.odom_along_sigma_m)},
      {"odom_heading_sigma_rad", num(t.odom_heading_sigma_rad)},
      {"omega_demand_rad_s", num(t.omega_demand_rad_s)},
      {"turning", t.turning},
      {"hold_elapsed_ns", t.hold_elapsed_ns},
      {"odom_progress", num(t.odom_progress)},
      {"dead_reckoned_m", num(t.dead_reckoned_m)},
      {"dead_reckoned_rad", num(t.dead_reckoned_rad)},
      {"reacquired", t.reacquired},
      {"odometry_steered", t.odometry_steered},
      {"line_yaw_rad", num(t.line_yaw_rad)},
      {"line_yaw_correction_rad", num(t.line_yaw_correction_rad)},
      {"line_yaw_room_probability", num(t.line_yaw_room_probability)},
      {"floor_lines", t.floor_lines},
      {"floor_lateral_before_m", num(t.floor_lateral_before_m)},
      {"floor_lateral_after_m", num(t.floor_lateral_after_m)},
      {"switch_along_correction_m", num(t.switch_along_correction_m)},
      {"floor_lateral_lines_m", num(t.floor_lateral_lines_m)},
      {"floor_lateral_lines_sigma_m", num(t.floor_lateral_lines_sigma_m)},
      {"floor_room_probability", num(t.floor_room_probability)},
      {"drift_corrected_m", num(t.drift_corrected_m)},
      {"drift_corrected_rad", num(t.drift_corrected_rad)},
      {"arrival_along_m", num(t.arrival_along_m)},
      {"arrival_lateral_m", num(t.arrival_lateral_m)},
      {"arrival_heading_rad", num(t.arrival_heading_rad)},
      {"arrival_source", to_string(t.arrival_source)},
      {"localization_ran", t.localization_ran},
      {"localization_best", t.localization_best},
      {"localization_best_count", t.localization_best_count},
      {"timings_ms",
       {{"extract", t.timings.extract_ms},
        {"localize", t.timings.localize_ms},
        {"match", t.timings.match_ms},
        {"control", t.timings.control_ms},
        {"total", t.timings.total_ms},
        {"lines", t.timings.lines_ms},
        {"klt", t.timings.klt_ms},
        {"essential", t.timings.essential_ms},
        {"three_view", t.timings.three_view_ms},
        {"wide_baseline", t.timings.wide_baseline_ms}}},
  };
}

nlohmann::json odometry_to_json(const std::optional<core::OdometryPose>& odom) {
  if (!odom) return nullptr;
  return {{"x_m", num(odom->x_m)}, {"y_m", num(odom->y_m)}, {"yaw_rad", num(odom->yaw_rad)}};
}

nlohmann::json overlay_to_json(const core::features::FeatureOverlay& o, const std::string& what) {
  nlohmann::json segments = nlohmann::json::array();
  for (const auto& s : o.lines) {
    segments.push_back({px(s.p0_px.x), px(s.p0_px.y), px(s.p1_px.x), px(s.p1_px.y)});
  }
  nlohmann::json uv = nlohmann::json::array();
  for (const auto& p : o.points_px) uv.push_back({px(p.x), px(p.y)});
  nlohmann::json lines = {{"label", what + " lines"},
                          {"color", kLineColor},
                          {"width_px", 2},
                          {"segments", std::move(segments)}};
  nlohmann::json points = {{"label", what + " points"},
                           {"color", kPointColor},
                           {"radius_px", 3},
                           {"uv", std::move(uv)}};
  return {{"lines", nlohmann::json::array({std::move(lines)})},
          {"points", nlohmann::json::array({std::move(points)})}};
}

std::string ceiling_overlay_caption(const nlohmann::json& c) {
  char buf[160];
  const int inliers = c.value("inliers", 0), matches = c.value("matches", 0);
  const auto& pose = c.contains("T_mosaic_base") ? c["T_mosaic_base"] : nlohmann::json();
  if (!pose.is_object()) {
    std::snprintf(buf, sizeof buf, "ceiling: %d of %d landmarks, no pose in the mosaic", inliers,
                  matches);
    return buf;
  }
  const double x = pose.value("x_m", 0.0), y = pose.value("y_m", 0.0);
  const double deg = pose.value("theta_rad", 0.0) * 180.0 / M_PI;
  if (c.value("fix", false)) {
    std::snprintf(buf, sizeof buf, "ceiling: %d of %d landmarks, mosaic x %.2f y %.2f m, %.0f deg",
                  inliers, matches, x, y, deg);
  } else {
    std::snprintf(buf, sizeof buf,
                  "ceiling: coasting on odometry %.2f m, mosaic x %.2f y %.2f m, %.0f deg",
                  c.value("coasted_m", 0.0), x, y, deg);
  }
  return buf;
}

nlohmann::json ceiling_teach_state(double distance_m, const core::ceiling::MosaicFrameResult& step,
                                   size_t mosaic_landmarks, int64_t frames_without_pose,
                                   size_t loops_closed) {
  return {{"distance_m", distance_m},
          {"ceiling",
           {{"matched", step.inliers},
            {"added", step.added},
            {"localised", step.localised},
            {"mosaic_landmarks", mosaic_landmarks},
            {"frames_without_pose", frames_without_pose},
            {"loops_closed", loops_closed}}}};
}

nlohmann::json ceiling_overlay_to_json(const core::features::FeatureOverlay& overlay) {
  nlohmann::json j = overlay_to_json(overlay, "ceiling");
  j.erase("lines");
  j["points"][0]["label"] = "ceiling landmarks";  // the legend reads "ceiling landmarks: N"
  return j;
}

}  // namespace pepper::app
