#include "config/app_config.hpp"

#include <fstream>
#include <set>
#include <sstream>
#include <type_traits>
#include <utility>

#include <yaml-cpp/yaml.h>

namespace pepper::app {
namespace {

using nlohmann::json;
namespace cf = core::features;
namespace cg = core::geometry;
namespace cc = core::control;
namespace cl = core::localization;
namespace cm = core::mapping;
namespace cn = core::navigator;

template <class E>
using EnumNames = std::vector<std::pair<const char*, E>>;

const EnumNames<cc::FeatureMode>& feature_mode_names() {
  static const EnumNames<cc::FeatureMode> names = {{"both", cc::FeatureMode::kLinesAndPoints},
                                                   {"lines", cc::FeatureMode::kLinesOnly},
                                                   {"points", cc::FeatureMode::kPointsOnly}};
  return names;
}
const EnumNames<cn::ControllerKind>& controller_names() {
  static const EnumNames<cn::ControllerKind> names = {{"ibvs", cn::ControllerKind::kIbvs},
                                                      {"vnhv", cn::ControllerKind::kVnhv}};
  return names;
}

// ---- One visit function per options struct: every field listed once. ----------------------

template <class V> void visit(V& v, cf::KltOptions& o) {
  v("window_px", o.window_px);
  v("max_level", o.max_level);
  v("max_iterations", o.max_iterations);
  v("epsilon", o.epsilon);
  v("min_eig_threshold", o.min_eig_threshold);
  v("max_error", o.max_error);
  v("prior_max_level", o.prior_max_level);
  v("prior_probes", o.prior_probes);
  v("prior_window_px", o.prior_window_px);
}
template <class V> void visit(V& v, cf::FeatureExtractorOptions& o) {
  v("max_lines", o.max_lines);
  v("min_line_length_frac", o.min_line_length_frac);
  v("ed_gradient_threshold", o.ed_gradient_threshold);
  v("ed_anchor_threshold", o.ed_anchor_threshold);
  v("ed_sigma", o.ed_sigma);
  v("ed_line_fit_error_px", o.ed_line_fit_error_px);
  v("lbd_band_width_px", o.lbd_band_width_px);
  v("lbd_samples_along", o.lbd_samples_along);
  v("fast_threshold", o.fast_threshold);
  v("max_corners", o.max_corners);
  v("corner_grid_cols", o.corner_grid_cols);
  v("corner_grid_rows", o.corner_grid_rows);
  v("orb_max_features", o.orb_max_features);
}
template <class V> void visit(V& v, cf::LineMatchOptions& o) {
  v("ratio", o.ratio);
  v("mutual", o.mutual);
  v("max_descriptor_distance", o.max_descriptor_distance);
  v("max_angle_change_rad", o.max_angle_change_rad);
  v("vertical_tolerance_rad", o.vertical_tolerance_rad);
  v("vertical_mismatch_rad", o.vertical_mismatch_rad);
  v("epipolar_overlap", o.epipolar_overlap);
}
template <class V> void visit(V& v, cg::EssentialRansacOptions& o) {
  v("threshold_px", o.threshold_px);
  v("confidence", o.confidence);
  v("max_iterations", o.max_iterations);
  v("min_inliers", o.min_inliers);
}
template <class V> void visit(V& v, cg::PlanarTrifocalOptions& o) {
  v("threshold_px", o.threshold_px);
  v("confidence", o.confidence);
  v("max_iterations", o.max_iterations);
  v("min_iterations", o.min_iterations);
  v("min_inliers", o.min_inliers);
  v("max_yaw_rad", o.max_yaw_rad);
  v("min_rotation_leverage", o.min_rotation_leverage);
  v("yaw_scan_steps", o.yaw_scan_steps);
  v("lo_iterations", o.lo_iterations);
  v("max_lo_runs", o.max_lo_runs);
  v("optimal_threshold_px", o.optimal_threshold_px);
  v("check_overlap", o.check_overlap);
  v("overlap_margin_px", o.overlap_margin_px);
  v("overlap_min_plane_sine", o.overlap_min_plane_sine);
  v("prior_from_points", o.prior_from_points);
  v("prior_min_points", o.prior_min_points);
  v("prior_max_tilt_rad", o.prior_max_tilt_rad);
  v("prior_max_t_y", o.prior_max_t_y);
  v("prior_min_parallax_px", o.prior_min_parallax_px);
  v("prior_min_cheirality", o.prior_min_cheirality);
  v("prior_min_samples", o.prior_min_samples);
  v("prior_max_challengers", o.prior_max_challengers);
  v("prior_replace_ratio", o.prior_replace_ratio);
  v("seed", o.seed);
}
template <class V> void visit(V& v, cf::MatcherOptions& o) {
  v.group("lines", [&](V& s) { visit(s, o.lines); });
  v.group("essential", [&](V& s) { visit(s, o.essential); });
  v.group("trifocal", [&](V& s) { visit(s, o.trifocal); });
  v("three_view_point_radius_px", o.three_view_point_radius_px);
  v("klt_shift_from_lines", o.klt_shift_from_lines);
  v("orb_ratio", o.orb_ratio);
  v("orb_max_hamming", o.orb_max_hamming);
  v("orb_fallback_below_points", o.orb_fallback_below_points);
}
template <class V> void visit(V& v, cm::KeyImageSelectorOptions& o) {
  v("epsilon", o.epsilon);
  v("min_frame_gap", o.min_frame_gap);
  v("relative", o.relative);
  v("max_fraction", o.max_fraction);
}
template <class V> void visit(V& v, cc::IbvsOptions& o) {
  v("g1", o.g1);
  v("g2", o.g2);
  v("lambda", o.lambda);
}
template <class V> void visit(V& v, cc::VnhvOptions& o) {
  v("kp_1_m2", o.kp_1_m2);
  v("kd_1_m", o.kd_1_m);
  v("max_abs_theta_rad", o.max_abs_theta_rad);
  v("teach_speed_m_s", o.teach_speed_m_s);
  v("max_segment_turn_rad", o.max_segment_turn_rad);
  v("max_arc_turn_rad", o.max_arc_turn_rad);
  v("straight_min_parallax_rad", o.straight_min_parallax_rad);
  v("straight_min_points", o.straight_min_points);
  v("straight_min_length_m", o.straight_min_length_m);
  v.group("pose", [&](V& s) {
    s("min_parallax_rad", o.pose.min_parallax_rad);
    s("max_reprojection_px", o.pose.max_reprojection_px);
    s("min_points", o.pose.min_points);
    s("ransac_iterations", o.pose.ransac_iterations);
    s("gauss_newton_iterations", o.pose.gauss_newton_iterations);
  });
  v.group("filter", [&](V& s) {
    s("measurement_sigma_m", o.filter.measurement_sigma_m);
    s("measurement_sigma_rad", o.filter.measurement_sigma_rad);
    s("process_sigma_m", o.filter.process_sigma_m);
    s("process_sigma_rad", o.filter.process_sigma_rad);
    s("gate_chi2", o.filter.gate_chi2);
    s("max_rejections", o.filter.max_rejections);
    s("max_prediction_ns", o.filter.max_prediction_ns);
  });
}
template <class V> void visit(V& v, cc::VelocityScheduleOptions& o) {
  v("v_straight_m_s", o.v_straight_m_s);
  v("v_turn_m_s", o.v_turn_m_s);
  v("turn_enter_rad_s", o.turn_enter_rad_s);
  v("turn_exit_rad_s", o.turn_exit_rad_s);
  v("turn_exit_hold_s", o.turn_exit_hold_s);
  v("max_omega_rad_s", o.max_omega_rad_s);
  v("max_omega_accel_rad_s2", o.max_omega_accel_rad_s2);
  v("first_step_dt_s", o.first_step_dt_s);
}
template <class V> void visit(V& v, cl::InitialLocalizerOptions& o) {
  v("min_best_count", o.rule.min_best_count);
  v("top_k", o.top_k);
  v("vote_ratio", o.vote_ratio);
  v("vote_max_hamming", o.vote_max_hamming);
}
template <class V> void visit(V& v, cl::SwitcherOptions& o) {
  v("consecutive_frames", o.consecutive_frames);
  v("min_next_scale_ratio", o.min_next_scale_ratio);
  v("passed_next_scale_ratio", o.passed_next_scale_ratio);
}
template <class V> void visit(V& v, cn::NavigatorOptions& o) {
  v.enumeration("controller", o.controller, controller_names());
  v.enumeration("features", o.features, feature_mode_names());
  v.group("ibvs", [&](V& s) { visit(s, o.ibvs); });
  v.group("vnhv", [&](V& s) { visit(s, o.vnhv); });
  v.group("speed", [&](V& s) { visit(s, o.schedule); });
  v.group("localization", [&](V& s) { visit(s, o.initial); });
  v.group("switching", [&](V& s) { visit(s, o.switching); });
  v("hold_ns", o.hold_ns);
  v("min_line_matches", o.min_line_matches);
  v("min_point_matches", o.min_point_matches);
  v("min_point_texture", o.min_point_texture);
  v("arrival_scale_ratio", o.arrival_scale_ratio);
  v("arrival_min_scale_points", o.arrival_min_scale_points);
  v("arrival_fade_ratio", o.arrival_fade_ratio);
  v("blind_switch_min_driven_fraction", o.blind_switch_min_driven_fraction);
  v("blind_passed_driven_factor", o.blind_passed_driven_factor);
  v("turn_feedforward", o.turn_feedforward);
  v("turn_feedforward_max_lead_rad", o.turn_feedforward_max_lead_rad);
  v("min_scale_points", o.min_scale_points);
  v("scale_quantile", o.scale_quantile);
  v("min_scale_lines", o.min_scale_lines);
  v("min_scale_pairs", o.min_scale_pairs);
  v("scale_line_max_angle_rad", o.scale_line_max_angle_rad);
  v("segment_overdue_factor", o.segment_overdue_factor);
  v("segment_overdue_min_ns", o.segment_overdue_min_ns);
}
template <class V> void visit(V& v, RobotConfig& o) {
  v("camera_width_px", o.camera_width_px);
  v("camera_height_px", o.camera_height_px);
  v("camera_fps", o.camera_fps);
  v("head_pitch_rad", o.head_pitch_rad);
  v("head_yaw_rad", o.head_yaw_rad);
  v("watchdog_ms", o.watchdog_ms);
  v("frame_timeout_ms", o.frame_timeout_ms);
  v("user", o.user);
}
template <class V> void visit(V& v, ReplayConfig& o) {
  v("give_up_lost_s", o.give_up_lost_s);
  v("give_up_not_localised_s", o.give_up_not_localised_s);
}
template <class V> void visit(V& v, UiConfig& o) {
  v("port", o.port);
  v("max_v_m_s", o.max_v_m_s);
  v("max_omega_rad_s", o.max_omega_rad_s);
}
template <class V> void visit(V& v, AppConfig& o) {
  v.group("features", [&](V& f) {
    f.group("extractor", [&](V& s) { visit(s, o.extractor); });
    f.group("klt", [&](V& s) { visit(s, o.extractor.klt); });
    f.group("matcher", [&](V& s) { visit(s, o.matcher); });
  });
  v.group("key_images", [&](V& s) { visit(s, o.key_images); });
  v.group("navigator", [&](V& s) { visit(s, o.navigator); });
  v.group("robot", [&](V& s) { visit(s, o.robot); });
  v.group("replay", [&](V& s) { visit(s, o.replay); });
  v.group("ui", [&](V& s) { visit(s, o.ui); });
}

// ---- Visitors. ------------------------------------------------------------------------------

class JsonWriter {
 public:
  explicit JsonWriter(json& node) : node_(node) {}
  template <class T> void operator()(const char* key, T& value) { node_[key] = value; }
  template <class F> void group(const char* key, F&& f) {
    json& sub = node_[key];
    if (!sub.is_object()) sub = json::object();
    JsonWriter w(sub);
    f(w);
  }
  template <class E> void enumeration(const char* key, E& value, const EnumNames<E>& names) {
    for (const auto& [name, e] : names) {
      if (e == value) node_[key] = name;
    }
  }

 private:
  json& node_;
};

class JsonReader {
 public:
  JsonReader(const json& node, std::string path, const std::string& origin)
      : node_(node), path_(std::move(path)), origin_(origin) {
    if (!node_.is_object()) fail(path_.empty() ? "(top level)" : path_, "must be a mapping");
  }

  template <class T> void operator()(const char* key, T& value) {
    const auto it = node_.find(key);
    seen_.insert(key);
    if (it == node_.end()) return;
    const std::string name = dotted(key);
    if constexpr (std::is_same_v<T, bool>) {
      if (!it->is_boolean()) fail(name, "must be true or false, got " + it->dump());
      value = it->template get<bool>();
    } else if constexpr (std::is_integral_v<T>) {
      if (!it->is_number_integer()) fail(name, "must be a whole number, got " + it->dump());
      if constexpr (std::is_unsigned_v<T>) {
        if (it->is_number_integer() && !it->is_number_unsigned() && it->template get<int64_t>() < 0)
          fail(name, "must be >= 0, got " + it->dump());
      }
      value = it->template get<T>();
    } else if constexpr (std::is_floating_point_v<T>) {
      if (!it->is_number()) fail(name, "must be a number, got " + it->dump());
      value = it->template get<T>();
    } else {
      if (!it->is_string()) fail(name, "must be a string, got " + it->dump());
      value = it->template get<T>();
    }
  }

  template <class F> void group(const char* key, F&& f) {
    seen_.insert(key);
    const auto it = node_.find(key);
    if (it == node_.end()) return;
    JsonReader sub(*it, dotted(key), origin_);
    f(sub);
    sub.check_unknown();
  }

  template <class E> void enumeration(const char* key, E& value, const EnumNames<E>& names) {
    seen_.insert(key);
    const auto it = node_.find(key);
    if (it == node_.end()) return;
    std::string allowed;
    for (const auto& [name, e] : names) {
      if (it->is_string() && it->template get<std::string>() == name) {
        value = e;
        return;
      }
      allowed += allowed.empty() ? name : std::string(", ") + name;
    }
    fail(dotted(key), "must be one of " + allowed + ", got " + it->dump());
  }

  void check_unknown() const {
    for (auto it = node_.begin(); it != node_.end(); ++it) {
      if (!seen_.count(it.key())) fail(dotted(it.key()), "unknown key");
    }
  }

 private:
  std::string dotted(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  [[noreturn]] void fail(const std::string& name, const std::string& what) const {
    throw ConfigError((origin_.empty() ? std::string() : origin_ + ": ") + name + ": " + what);
  }

  const json& node_;
  std::string path_;
  const std::string& origin_;
  std::set<std::string> seen_;
};

json yaml_to_json(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
    case YAML::NodeType::Undefined:
      return nullptr;
    case YAML::NodeType::Sequence: {
      json out = json::array();
      for (const auto& item : node) out.push_back(yaml_to_json(item));
      return out;
    }
    case YAML::NodeType::Map: {
      json out = json::object();
      for (const auto& kv : node) out[kv.first.as<std::string>()] = yaml_to_json(kv.second);
      return out;
    }
    case YAML::NodeType::Scalar:
      break;
  }
  const std::string text = node.Scalar();
  if (node.Tag() == "!") return text;  // quoted in the file: a string
  if (text == "true" || text == "True" || text == "yes") return true;
  if (text == "false" || text == "False" || text == "no") return false;
  try {
    std::size_t used = 0;
    const long long i = std::stoll(text, &used);
    if (used == text.size()) return i;
  } catch (...) {
  }
  try {
    std::size_t used = 0;
    const double d = std::stod(text, &used);
    if (used == text.size()) return d;
  } catch (...) {
  }
  return text;
}

void append_prefixed(std::vector<std::string>& out, const std::string& prefix,
                     const std::vector<std::string>& errors) {
  for (const auto& e : errors) out.push_back(prefix + e);
}

void merge_into(json& base, const json& patch) {
  for (auto it = patch.begin(); it != patch.end(); ++it) {
    if (it->is_object() && base.contains(it.key()) && base[it.key()].is_object()) {
      merge_into(base[it.key()], *it);
    } else {
      base[it.key()] = *it;
    }
  }
}

}  // namespace

std::vector<std::string> RobotConfig::validate() const {
  std::vector<std::string> e;
  const bool vga = camera_width_px == 640 && camera_height_px == 480;
  const bool qvga = camera_width_px == 320 && camera_height_px == 240;
  if (!vga && !qvga) e.push_back("camera size must be 640x480 (kVGA) or 320x240 (kQVGA)");
  if (camera_fps < 1 || camera_fps > 30) e.push_back("camera_fps must be in 1..30");
  if (!(head_pitch_rad >= -0.707 && head_pitch_rad <= 0.637))
    e.push_back("head_pitch_rad must be in [-0.707, 0.637] (Pepper's HeadPitch range)");
  if (!(head_yaw_rad >= -2.086 && head_yaw_rad <= 2.086))
    e.push_back("head_yaw_rad must be in [-2.086, 2.086] (Pepper's HeadYaw range)");
  if (watchdog_ms < 50 || watchdog_ms > 2000) e.push_back("watchdog_ms must be in 50..2000");
  if (frame_timeout_ms < 100 || frame_timeout_ms > 10000)
    e.push_back("frame_timeout_ms must be in 100..10000");
  return e;
}

std::vector<std::string> ReplayConfig::validate() const {
  std::vector<std::string> e;
  if (!(give_up_lost_s >= 0 && give_up_lost_s <= 3600)) e.push_back("give_up_lost_s must be in [0, 3600]");
  if (!(give_up_not_localised_s >= 0 && give_up_not_localised_s <= 3600))
    e.push_back("give_up_not_localised_s must be in [0, 3600]");
  return e;
}

std::vector<std::string> UiConfig::validate() const {
  std::vector<std::string> e;
  if (port < 0 || port > 65535) e.push_back("port must be in 0..65535");
  if (!(max_v_m_s > 0.0 && max_v_m_s <= 0.55)) e.push_back("max_v_m_s must be in (0, 0.55]");
  if (!(max_omega_rad_s > 0.0 && max_omega_rad_s <= 2.0))
    e.push_back("max_omega_rad_s must be in (0, 2]");
  return e;
}

core::mapping::TeachOptions AppConfig::teach_options() const {
  core::mapping::TeachOptions t;
  t.selector = key_images;
  t.extractor = extractor;
  t.matcher = matcher;
  t.matcher.klt = extractor.klt;  // tracking must use the key images' pyramid parameters
  return t;
}

core::navigator::NavigatorOptions AppConfig::navigator_options() const {
  core::navigator::NavigatorOptions n = navigator;
  n.extractor = extractor;
  n.matcher = matcher;
  n.matcher.klt = extractor.klt;
  return n;
}

std::vector<std::string> AppConfig::validate() const {
  std::vector<std::string> e;
  append_prefixed(e, "", teach_options().validate());
  append_prefixed(e, "", navigator_options().validate());
  append_prefixed(e, "robot.", robot.validate());
  append_prefixed(e, "replay.", replay.validate());
  append_prefixed(e, "ui.", ui.validate());
  return e;
}

json config_to_json(const AppConfig& config) {
  AppConfig copy = config;
  json out = json::object();
  JsonWriter w(out);
  visit(w, copy);
  return out;
}

void apply_config_json(const json& tree, AppConfig& config, const std::string& origin) {
  if (tree.is_null()) return;
  JsonReader r(tree, "", origin);
  visit(r, config);
  r.check_unknown();
}

json read_config_file(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ConfigError(file.string() + ": cannot open configuration file");
  std::stringstream ss;
  ss << in.rdbuf();
  try {
    if (file.extension() == ".json") return json::parse(ss.str());
    return yaml_to_json(YAML::Load(ss.str()));
  } catch (const std::exception& e) {
    throw ConfigError(file.string() + ": not valid YAML/JSON: " + e.what());
  }
}

json parse_override(const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw ConfigError("--set " + assignment + ": expected dotted.key=value");
  }
  const std::string key = assignment.substr(0, eq);
  json value;
  try {
    value = yaml_to_json(YAML::Load(assignment.substr(eq + 1)));
  } catch (const std::exception& e) {
    throw ConfigError("--set " + assignment + ": bad value: " + e.what());
  }
  json patch = value;
  std::size_t end = key.size();
  while (true) {
    const auto dot = key.rfind('.', end - 1);
    const std::string part = key.substr(dot == std::string::npos ? 0 : dot + 1,
                                        end - (dot == std::string::npos ? 0 : dot + 1));
    if (part.empty()) throw ConfigError("--set " + assignment + ": empty key component");
    patch = json{{part, patch}};
    if (dot == std::string::npos) break;
    end = dot;
  }
  return patch;
}

AppConfig load_app_config(const std::filesystem::path& file, const std::vector<std::string>& sets) {
  AppConfig config;
  if (!file.empty()) apply_config_json(read_config_file(file), config, file.string());
  json overrides = json::object();
  for (const auto& s : sets) merge_into(overrides, parse_override(s));
  apply_config_json(overrides, config, "--set");
  const auto errors = config.validate();
  if (!errors.empty()) {
    std::string msg = "invalid configuration:";
    for (const auto& e : errors) msg += "\n  " + e;
    throw ConfigError(msg);
  }
  return config;
}

}  // namespace pepper::app
