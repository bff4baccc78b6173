#pragma once
// Typed builders for what the app publishes to the teach UI: the frame overlay, the documented
// state keys and plot samples. Each to_json() produces exactly the schema of docs/teach_ui.md, so
// the app does not spell JSON keys by hand and the page and the app cannot drift apart.
//
// Units and frames (docs/conventions.md): image coordinates in pixels (u right, v down, pixel
// centres at integers); speeds in m/s and rad/s (omega > 0 turns left); distances in metres;
// trajectories in the world frame seen from above (x_m, y_m). Plain data, no threads, no throws.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace pepper::teach_ui {

// ------------------------------------------------------------------ frame overlay
struct OverlaySegment {
  double u0_px = 0, v0_px = 0, u1_px = 0, v1_px = 0;
};
struct OverlayPoint {
  double u_px = 0, v_px = 0;
};
/// One colour of line segments (e.g. "matched lines" in green, "unmatched" in grey).
struct OverlayLineGroup {
  std::string label;              ///< legend text under the image; empty = not in the legend
  std::string color = "#22c55e";  ///< any CSS colour
  double width_px = 2.0;
  std::vector<OverlaySegment> segments;
};
struct OverlayPointGroup {
  std::string label;
  std::string color = "#ef4444";
  double radius_px = 3.0;
  std::vector<OverlayPoint> points;
};
/// What the page draws over the camera image. Coordinates refer to an image of
/// width_px x height_px (the page rescales when the encoded image has another size).
struct Overlay {
  int width_px = 0;
  int height_px = 0;
  std::optional<std::int64_t> t_ns;  ///< capture stamp of the frame, if known
  std::vector<OverlayLineGroup> lines;
  std::vector<OverlayPointGroup> points;
  std::vector<std::string> text;  ///< caption lines drawn at the top of the image
};
nlohmann::json to_json(const Overlay& overlay);

// ------------------------------------------------------------------ state pieces
/// One key image of the tour being taught (state key "teach").
struct KeyImageInfo {
  int index = 0;
  int n_lines = 0;
  int n_points = 0;
  double distance_m = 0.0;  ///< travelled distance along the tour when it was taken
  bool weak = false;        ///< too few features: the page frames it in red and warns
};
struct TeachStatus {
  std::vector<KeyImageInfo> key_images;
  double distance_m = 0.0;  ///< travelled so far
  int n_lines = 0;          ///< features in the current image
  int n_points = 0;
};
struct MapSummary {
  int key_images = 0;
  double length_m = 0.0;
  int min_lines = 0;
  int min_points = 0;
  std::vector<int> weak_key_images;
  std::string path;  ///< where the map was written
};
struct Localisation {
  bool ok = false;
  std::optional<int> key_index;
  std::string detail;  ///< e.g. "38 verified matches" or why it failed
};
/// State key "replay". `state` is one of "localising", "running", "stopped", "finished".
struct ReplayStatus {
  std::string state = "localising";
  std::optional<Localisation> localisation;
  int key_index = 0;
  int key_count = 0;
  double distance_m = 0.0;
  double total_m = 0.0;
};
struct XY {
  double x_m = 0.0, y_m = 0.0;
};
/// State key "trajectory" (offline replay top view).
struct TopView {
  std::vector<XY> taught;
  std::vector<XY> replayed;
  std::vector<XY> keys;
};
/// One point of the live plots (publish_samples). Unset fields are left out.
struct PlotSample {
  std::optional<double> t_s;
  std::optional<double> distance_m;
  std::optional<double> v_m_s;
  std::optional<double> omega_rad_s;
  std::optional<int> n_lines;
  std::optional<int> n_points;
};

nlohmann::json to_json(const TeachStatus& s);
nlohmann::json to_json(const MapSummary& s);
nlohmann::json to_json(const ReplayStatus& s);
nlohmann::json to_json(const TopView& s);
nlohmann::json to_json(const PlotSample& s);

/// State patch {"connection":{"robot":robot,"head_locked":...,"detail":...}}; `robot` is
/// "connected", "connecting" or "disconnected".
nlohmann::json connection_state(const std::string& robot, bool head_locked,
                                const std::string& detail = "");

}  // namespace pepper::teach_ui
