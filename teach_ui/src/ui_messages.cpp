// JSON builders for the teach UI schema (see teach_ui/ui_messages.hpp, docs/teach_ui.md).
#include "teach_ui/ui_messages.hpp"

namespace pepper::teach_ui {
namespace {

using json = nlohmann::json;

json xy_list(const std::vector<XY>& pts) {
  json out = json::array();
  for (const auto& p : pts) out.push_back({p.x_m, p.y_m});
  return out;
}

}  // namespace

json to_json(const Overlay& overlay) {
  json lines = json::array();
  for (const auto& g : overlay.lines) {
    json segments = json::array();
    for (const auto& s : g.segments) segments.push_back({s.u0_px, s.v0_px, s.u1_px, s.v1_px});
    json group = {{"color", g.color}, {"width_px", g.width_px}, {"segments", std::move(segments)}};
    if (!g.label.empty()) group["label"] = g.label;
    lines.push_back(std::move(group));
  }
  json points = json::array();
  for (const auto& g : overlay.points) {
    json uv = json::array();
    for (const auto& p : g.points) uv.push_back({p.u_px, p.v_px});
    json group = {{"color", g.color}, {"radius_px", g.radius_px}, {"uv", std::move(uv)}};
    if (!g.label.empty()) group["label"] = g.label;
    points.push_back(std::move(group));
  }
  json out = {{"width_px", overlay.width_px},
              {"height_px", overlay.height_px},
              {"lines", std::move(lines)},
              {"points", std::move(points)}};
  if (overlay.t_ns) out["t_ns"] = *overlay.t_ns;
  if (!overlay.text.empty()) out["text"] = overlay.text;
  return out;
}

json to_json(const TeachStatus& s) {
  json keys = json::array();
  for (const auto& k : s.key_images) {
    keys.push_back({{"index", k.index},
                    {"n_lines", k.n_lines},
                    {"n_points", k.n_points},
                    {"distance_m", k.distance_m},
                    {"weak", k.weak}});
  }
  return {{"key_images", std::move(keys)},
          {"distance_m", s.distance_m},
          {"n_lines", s.n_lines},
          {"n_points", s.n_points}};
}

json to_json(const MapSummary& s) {
  return {{"key_images", s.key_images},
          {"length_m", s.length_m},
          {"min_lines", s.min_lines},
          {"min_points", s.min_points},
          {"weak_key_images", s.weak_key_images},
          {"path", s.path}};
}

json to_json(const ReplayStatus& s) {
  json out = {{"state", s.state},
              {"key_index", s.key_index},
              {"key_count", s.key_count},
              {"distance_m", s.distance_m},
              {"total_m", s.total_m}};
  if (s.localisation) {
    json loc = {{"ok", s.localisation->ok}, {"detail", s.localisation->detail}};
    if (s.localisation->key_index) loc["key_index"] = *s.localisation->key_index;
    out["localisation"] = std::move(loc);
  }
  return out;
}

json to_json(const TopView& s) {
  return {
      {"taught", xy_list(s.taught)}, {"replayed", xy_list(s.replayed)}, {"keys", xy_list(s.keys)}};
}

json to_json(const PlotSample& s) {
  json out = json::object();
  if (s.t_s) out["t_s"] = *s.t_s;
  if (s.distance_m) out["distance_m"] = *s.distance_m;
  if (s.v_m_s) out["v_m_s"] = *s.v_m_s;
  if (s.omega_rad_s) out["omega_rad_s"] = *s.omega_rad_s;
  if (s.n_lines) out["n_lines"] = *s.n_lines;
  if (s.n_points) out["n_points"] = *s.n_points;
  return out;
}

json connection_state(const std::string& robot, bool head_locked, const std::string& detail) {
  json c = {{"robot", robot}, {"head_locked", head_locked}};
  if (!detail.empty()) c["detail"] = detail;
  return {{"connection", std::move(c)}};
}

}  // namespace pepper::teach_ui
