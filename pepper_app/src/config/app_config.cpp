#include "config/app_config.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "config/parameters.hpp"
#include "core/ceiling/ceiling_navigator.hpp"

namespace pepper::app {
namespace {

using nlohmann::json;

[[noreturn]] void fail(const std::string& origin, const std::string& key, const std::string& what) {
  throw ConfigError((origin.empty() ? std::string() : origin + ": ") + key + ": " + what);
}

/// Keys that were options and are gone, with why: an old configuration file names what to do
/// instead of only "unknown key" (docs/method/navigator.md, "ablations").
const char* removed_key(const std::string& key) {
  static const std::pair<const char*, const char*> kRemoved[] = {
      {"navigator.switching.passed_next_scale_ratio",
       "removed: the \"passed IN\" switch by IN's scale changed no run of the evaluation "
       "matrix when it was off; \"passed IN by travel\" covers it (delete the key)"},
      {"navigator.arrival_fade_ratio",
       "removed: arrival when the final image fades is now fixed (0.95) and acts only without "
       "odometry, where nothing else stops the robot at the end (delete the key)"},
      {"navigator.turn_feedforward",
       "removed: the taught-turn feed-forward changed no run of the evaluation matrix when it "
       "was off (odometry steers where VNHV has no estimate; delete the key)"},
      {"navigator.turn_feedforward_max_lead_rad",
       "removed with the taught-turn feed-forward it capped (delete the key)"},
      {"navigator.dead_reckoning_max_m",
       "replaced by navigator.dead_reckoning_max_lateral_sigma_m: driving blind now ends when "
       "the odometry's error model says the robot may be that far off the path since its "
       "position across the path was last measured, not after a fixed distance (delete the "
       "key)"},
      {"navigator.dead_reckoning_max_rad",
       "replaced by navigator.dead_reckoning_max_lateral_sigma_m, which counts the turns' "
       "heading error too (delete the key)"},
      {"ceiling.coast_max_m",
       "replaced by ceiling.coast_max_error_m: coasting now ends when the odometry's error "
       "model says the pose may be that far off, not after a fixed distance (delete the key)"},
  };
  for (const auto& [k, why] : kRemoved) {
    if (key == k) return why;
  }
  return nullptr;
}

/// Reads one mapping of the tree at dotted path `path` ("" = the top) through the table.
void apply_node(const json& node, const std::string& path, AppConfig& config,
                const std::string& origin) {
  if (!node.is_object()) fail(origin, path.empty() ? "(top level)" : path, "must be a mapping");
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string key = path.empty() ? it.key() : path + "." + it.key();
    if (const Parameter* p = find_parameter(key)) {
      if (const std::string problem = p->set(config, *it); !problem.empty()) {
        fail(origin, key, problem);
      }
    } else if (is_section(key)) {
      apply_node(*it, key, config, origin);
    } else if (const char* why = removed_key(key)) {
      fail(origin, key, why);
    } else {
      fail(origin, key, "unknown key (did you mean " + closest_key(key) + "?)");
    }
  }
}

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

void append_new(std::vector<std::string>& out, const std::string& prefix,
                const std::vector<std::string>& errors) {
  for (const auto& e : errors) {
    if (std::find(out.begin(), out.end(), prefix + e) == out.end()) out.push_back(prefix + e);
  }
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

/// The tree of "dotted.key=value" assignments, later ones over earlier ones.
json overrides_tree(const std::vector<std::string>& sets) {
  json tree = json::object();
  for (const auto& s : sets) merge_into(tree, parse_override(s));
  return tree;
}

}  // namespace

std::vector<std::string> RobotConfig::validate() const {
  const bool vga = camera_width_px == 640 && camera_height_px == 480;
  const bool qvga = camera_width_px == 320 && camera_height_px == 240;
  if (vga || qvga) return {};
  return {"camera_width_px x camera_height_px = " + std::to_string(camera_width_px) + "x" +
          std::to_string(camera_height_px) + ": must be 640x480 (kVGA) or 320x240 (kQVGA)"};
}

core::mapping::TeachOptions AppConfig::teach_options() const {
  core::mapping::TeachOptions t;
  t.selector = key_images;
  t.extractor = extractor;
  t.matcher = matcher;
  t.matcher.klt = extractor.klt;  // tracking must use the key images' pyramid parameters
  t.matcher.essential.camera_pitch_rad = robot.head_pitch_rad;  // the camera is the locked head's
  return t;
}

core::navigator::NavigatorOptions AppConfig::navigator_options() const {
  core::navigator::NavigatorOptions n = navigator;
  n.extractor = extractor;
  n.matcher = matcher;
  n.matcher.klt = extractor.klt;
  n.matcher.essential.camera_pitch_rad = robot.head_pitch_rad;
  return n;
}

core::ceiling::CeilingNavigatorOptions AppConfig::ceiling_navigator_options() const {
  core::ceiling::CeilingNavigatorOptions c;
  c.vnhv = navigator.vnhv;
  c.schedule = navigator.schedule;
  c.arc_min_turn_rad = ceiling.arc_min_turn_rad;
  c.turn_in_place_gain_1_s = ceiling.turn_in_place_gain_1_s;
  c.coast_max_error_m = ceiling.coast_max_error_m;
  c.coast_max_s = ceiling.coast_max_s;
  return c;
}

std::vector<std::string> AppConfig::validate() const {
  std::vector<std::string> e = check_ranges(*this);
  if (!e.empty()) return e;
  // The rules between fields (odd KLT windows, ibvs.g1 + g2 > 0, ...), part by part so that the
  // shared extractor and matcher are checked once; their messages carry the part's own names.
  append_new(e, "features.", extractor.validate());
  append_new(e, "features.matcher.", matcher.validate());
  append_new(e, "", key_images.validate());
  append_new(e, "", navigator.validate());
  append_new(e, "robot.", robot.validate());
  return e;
}

json config_to_json(const AppConfig& config) {
  json out = json::object();
  for (const Parameter& p : parameters()) {
    std::string pointer = "/" + p.key;
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    out[json::json_pointer(pointer)] = p.get(config);
  }
  return out;
}

void apply_config_json(const json& tree, AppConfig& config, const std::string& origin) {
  if (tree.is_null()) return;
  apply_node(tree, "", config, origin);
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

AppConfig load_app_config(const ConfigSources& sources) {
  json file_tree;
  if (!sources.file.empty()) file_tree = read_config_file(sources.file);
  std::string preset_name = sources.preset;
  std::string preset_origin = "--preset " + preset_name;
  if (file_tree.is_object() && file_tree.contains("preset")) {
    if (!file_tree["preset"].is_string()) {
      fail(sources.file, "preset", "must be a preset name, got " + file_tree["preset"].dump());
    }
    if (preset_name.empty()) {
      preset_name = file_tree["preset"].get<std::string>();
      preset_origin = sources.file + ": preset " + preset_name;
    }
    file_tree.erase("preset");
  }
  AppConfig config;
  if (!preset_name.empty()) {
    const Preset* preset = find_preset(preset_name);
    if (preset == nullptr) {
      std::string known;
      for (const auto& p : presets()) known += (known.empty() ? "" : ", ") + p.name;
      throw ConfigError(preset_origin + ": unknown preset (known: " + known + ")");
    }
    apply_config_json(overrides_tree(preset->sets), config, "preset " + preset->name);
  }
  apply_config_json(file_tree, config, sources.file);
  apply_config_json(overrides_tree(sources.sets), config, "--set");
  const auto errors = config.validate();
  if (!errors.empty()) {
    std::string msg = "invalid configuration:";
    for (const auto& e : errors) msg += "\n  " + e;
    throw ConfigError(msg);
  }
  return config;
}

AppConfig load_app_config(const std::filesystem::path& file, const std::vector<std::string>& sets) {
  return load_app_config(ConfigSources{file.string(), "", sets});
}

}  // namespace pepper::app
