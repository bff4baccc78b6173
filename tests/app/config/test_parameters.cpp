// The parameter table (pepper_app/src/config/parameters.cpp) and what is generated from it: range
// checks, the reader's messages, dump / load, presets and docs/configuration.md.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <limits>
#include <set>
#include <sstream>
#include <string>

#include "config/app_config.hpp"
#include "config/config_doc.hpp"
#include "config/config_yaml.hpp"
#include "config/parameters.hpp"
#include "support/temp_dir.hpp"

namespace pepper::app {
namespace {

using nlohmann::json;

std::string config_error(const ConfigSources& sources) {
  try {
    load_app_config(sources);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string set_error(const std::string& assignment) {
  return config_error(ConfigSources{"", "", {assignment}});
}

/// The error of loading a file called `name` holding `text`.
std::string file_error(const std::string& name, const std::string& text) {
  test::TempDir tmp;
  const auto file = tmp.path() / name;
  std::ofstream(file) << text;
  return config_error(ConfigSources{file.string(), "", {}});
}

double no_reference(const std::string&) { return 0.0; }

void collect_leaves(const json& node, const std::string& path, std::set<std::string>& out) {
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string key = path.empty() ? it.key() : path + "." + it.key();
    if (it->is_object()) {
      collect_leaves(*it, key, out);
    } else {
      out.insert(key);
    }
  }
}

TEST(ConfigRange, ParsesIntervalsAlternativesAndReferences) {
  const Range half_open("[0, 1)");
  EXPECT_TRUE(half_open.contains(0.0, no_reference));
  EXPECT_FALSE(half_open.contains(1.0, no_reference));
  EXPECT_EQ(half_open.describe(), "in [0, 1)");

  const Range off_or("0 (off) or [1, inf)");
  EXPECT_TRUE(off_or.contains(0.0, no_reference));
  EXPECT_FALSE(off_or.contains(0.5, no_reference));
  EXPECT_TRUE(off_or.contains(1e12, no_reference));
  EXPECT_FALSE(off_or.contains(std::numeric_limits<double>::infinity(), no_reference));
  EXPECT_FALSE(off_or.contains(std::numeric_limits<double>::quiet_NaN(), no_reference));
  EXPECT_EQ(off_or.describe(), "0 (off) or in [1, inf)");

  const Range angle("(0, pi/2]");
  EXPECT_TRUE(angle.contains(1.5707963267948966, no_reference));
  EXPECT_FALSE(angle.contains(1.571, no_reference));

  const Range sized("320 (QVGA) or 640 (VGA)");
  EXPECT_TRUE(sized.contains(640.0, no_reference));
  EXPECT_FALSE(sized.contains(480.0, no_reference));

  const Range bounded("[1, max_iterations]");
  EXPECT_EQ(bounded.references(), std::vector<std::string>{"max_iterations"});
  EXPECT_TRUE(bounded.contains(500.0, [](const std::string&) { return 500.0; }));
  EXPECT_FALSE(bounded.contains(501.0, [](const std::string&) { return 500.0; }));

  EXPECT_TRUE(Range("").empty());
  for (const char* bad : {"[1, 0]", "(0 1)", "0 off", "[0, inf]", "[0, 1) or", "[0, x-y]"}) {
    EXPECT_THROW(Range{bad}, std::invalid_argument) << bad;
  }
}

TEST(ConfigParameters, EveryRowIsDocumentedAndEveryDefaultLiesWithinItsRange) {
  const AppConfig defaults;
  std::set<std::string> sections;
  for (const auto& [section, doc] : section_docs()) sections.insert(section);
  ASSERT_GE(parameters().size(), 130u);
  for (const Parameter& p : parameters()) {
    EXPECT_FALSE(p.doc.empty()) << p.key;
    EXPECT_TRUE(sections.count(p.section())) << p.key << ": section without a doc";
    if (!p.numeric()) continue;
    EXPECT_FALSE(p.range.empty()) << p.key << ": a number needs a range";
    auto lookup = [&](const std::string& ref) {
      return find_parameter(p.section() + "." + ref)->get(defaults).get<double>();
    };
    EXPECT_TRUE(p.range.contains(p.get(defaults).get<double>(), lookup))
        << p.key << " = " << p.get(defaults) << " outside " << p.range.text();
  }
  EXPECT_TRUE(check_ranges(defaults).empty());
  EXPECT_TRUE(defaults.validate().empty());
}

TEST(ConfigParameters, RangeErrorNamesTheKeyTheValueTheRangeAndTheUnit) {
  EXPECT_NE(set_error("navigator.vnhv.kp_1_m2=-1")
                .find("navigator.vnhv.kp_1_m2 = -1: must be in (0, inf) (1/m^2)"),
            std::string::npos)
      << set_error("navigator.vnhv.kp_1_m2=-1");
  EXPECT_NE(set_error("navigator.blind_switch_min_driven_fraction=1.5")
                .find("navigator.blind_switch_min_driven_fraction = 1.5: must be 0 (off) or in "
                      "(0, 1]"),
            std::string::npos)
      << set_error("navigator.blind_switch_min_driven_fraction=1.5");
  // A bound named by another parameter: its value is given.
  const std::string cross = set_error("features.matcher.trifocal.min_iterations=600");
  EXPECT_NE(cross.find("features.matcher.trifocal.min_iterations = 600: must be in "
                       "[1, max_iterations] (max_iterations = 500)"),
            std::string::npos)
      << cross;
  EXPECT_NE(set_error("navigator.speed.v_turn_m_s=0.2")
                .find("must be in [0, v_straight_m_s] (m/s; v_straight_m_s = 0.15)"),
            std::string::npos);
}

TEST(ConfigParameters, RulesBetweenFieldsStillComeFromTheValidateFunctions) {
  EXPECT_NE(set_error("features.klt.window_px=14").find("features.klt.window_px = 14 must be odd"),
            std::string::npos);
  EXPECT_NE(set_error("robot.camera_width_px=320").find("must be 640x480 (kVGA) or 320x240"),
            std::string::npos);
  const std::string gains = config_error({"", "", {"navigator.ibvs.g1=0", "navigator.ibvs.g2=0"}});
  EXPECT_NE(gains.find("g1 + g2 must be > 0"), std::string::npos) << gains;
}

TEST(ConfigParameters, UnknownKeySuggestsTheClosest) {
  const std::string typo = file_error("typo.yaml", "navigator:\n  ibvs:\n    gg1: 0.6\n");
  EXPECT_NE(
      typo.find("typo.yaml: navigator.ibvs.gg1: unknown key (did you mean navigator.ibvs.g1?)"),
      std::string::npos)
      << typo;
  EXPECT_EQ(closest_key("navigator.vnhv.kp"), "navigator.vnhv.kp_1_m2");
  EXPECT_EQ(closest_key("navigator.kp_1_m2"), "navigator.vnhv.kp_1_m2");  // wrong section
  EXPECT_EQ(closest_key("navigater"), "navigator");
  EXPECT_EQ(closest_key("features.matcher.trifocal.thresold_px"),
            "features.matcher.trifocal.threshold_px");
  EXPECT_NE(set_error("robot.camera_fsp=10").find("did you mean robot.camera_fps?"),
            std::string::npos);
}

TEST(ConfigParameters, WrongTypesNameTheKeyAndTheFile) {
  EXPECT_NE(file_error("types.yaml", "robot:\n  camera_fps: fast\n")
                .find("types.yaml: robot.camera_fps: must be a whole number, got \"fast\""),
            std::string::npos);
  EXPECT_NE(file_error("deep.yaml", "navigator:\n  vnhv:\n    pose: 3\n")
                .find("deep.yaml: navigator.vnhv.pose: must be a mapping"),
            std::string::npos);
  EXPECT_NE(set_error("robot.camera_fps=1e10").find("robot.camera_fps: must be a whole number"),
            std::string::npos);
  EXPECT_NE(set_error("robot.camera_fps=99999999999").find("must be a whole number in"),
            std::string::npos);
  EXPECT_NE(set_error("navigator.features=all").find("must be one of both, lines, points"),
            std::string::npos);
  EXPECT_NE(set_error("robot=3").find("robot: must be a mapping"), std::string::npos);
}

/// A value of `p` other than its default that its range allows (cross-field rules aside).
json changed_value(const Parameter& p, const AppConfig& defaults) {
  const json d = p.get(defaults);
  switch (p.type) {
    case ParamType::kBool:
      return !d.get<bool>();
    case ParamType::kString:
      return "changed";
    case ParamType::kEnum:
      return p.enum_names.front() == d.get<std::string>() ? p.enum_names.back()
                                                          : p.enum_names.front();
    default:
      break;
  }
  auto lookup = [&](const std::string& ref) {
    return find_parameter(p.section() + "." + ref)->get(defaults).get<double>();
  };
  const double v = d.get<double>();
  const bool integral = p.type != ParamType::kFloat && p.type != ParamType::kDouble;
  // Integers step by 2 first (KLT windows stay odd); halving keeps a double exact in the dump.
  const std::vector<double> candidates =
      integral ? std::vector<double>{v + 2, v - 2, v + 1, v - 1, 320, 240}
               : std::vector<double>{v * 0.5, v + 0.5, v - 0.5, v * 2, 0.5, 0.75, 0.25};
  for (const double c : candidates) {
    if (c != v && p.range.contains(c, lookup)) {
      return integral ? json(static_cast<std::int64_t>(c)) : json(c);
    }
  }
  ADD_FAILURE() << p.key << ": no other value in " << p.range.text();
  return d;
}

TEST(ConfigParameters, DumpWritesExactlyTheTableAndEveryRowRoundTrips) {
  const AppConfig defaults;
  std::set<std::string> dumped, table;
  collect_leaves(config_to_json(defaults), "", dumped);
  for (const Parameter& p : parameters()) table.insert(p.key);
  EXPECT_EQ(dumped, table);

  test::TempDir tmp;
  const auto file = tmp.path() / "one.yaml";
  for (const Parameter& p : parameters()) {
    AppConfig c;
    const json value = changed_value(p, defaults);
    ASSERT_EQ(p.set(c, value), "") << p.key;
    std::ofstream(file) << json_to_yaml(config_to_json(c));
    AppConfig back;
    apply_config_json(read_config_file(file), back, file.string());
    EXPECT_EQ(p.get(back), value) << p.key;
    EXPECT_EQ(config_to_json(back), config_to_json(c)) << p.key;
  }
}

TEST(ConfigParameters, PresetsApply) {
  using core::navigator::ControllerKind;
  EXPECT_EQ(load_app_config(ConfigSources{"", "paper", {}}).navigator.controller,
            ControllerKind::kIbvs);
  EXPECT_EQ(load_app_config(ConfigSources{"", "default", {}}).navigator.controller,
            ControllerKind::kVnhv);
  EXPECT_EQ(config_to_json(load_app_config(ConfigSources{"", "default", {}})),
            config_to_json(AppConfig{}));
  // --set applies after the preset.
  EXPECT_EQ(load_app_config(ConfigSources{"", "paper", {"navigator.controller=vnhv"}})
                .navigator.controller,
            ControllerKind::kVnhv);

  test::TempDir tmp;
  const auto file = tmp.path() / "p.yaml";
  std::ofstream(file) << "preset: paper\nrobot:\n  camera_fps: 10\n";
  const AppConfig from_file = load_app_config(ConfigSources{file.string(), "", {}});
  EXPECT_EQ(from_file.navigator.controller, ControllerKind::kIbvs);
  EXPECT_EQ(from_file.robot.camera_fps, 10);
  // --preset wins over the file's preset: key.
  EXPECT_EQ(load_app_config(ConfigSources{file.string(), "default", {}}).navigator.controller,
            ControllerKind::kVnhv);

  EXPECT_NE(config_error({"", "turbo", {}})
                .find("--preset turbo: unknown preset (known: default, paper, fast)"),
            std::string::npos);
  // fast (issue 22): a 9 px KLT window, for extraction and tracking alike; the planar
  // essential model is the default since session 31.
  const auto fast = load_app_config(ConfigSources{"", "fast", {}}).navigator_options();
  EXPECT_TRUE(fast.matcher.essential.planar);
  EXPECT_EQ(fast.extractor.klt.window_px, 9);
  EXPECT_EQ(fast.matcher.klt.window_px, 9);
  EXPECT_TRUE(AppConfig{}.navigator_options().matcher.essential.planar);
  EXPECT_EQ(AppConfig{}.navigator_options().matcher.klt.window_px, 15);
  for (const Preset& p : presets()) {
    EXPECT_NO_THROW(load_app_config(ConfigSources{"", p.name, {}})) << p.name;
  }
}

TEST(ConfigDoc, CommittedReferenceIsCurrent) {
  std::ifstream in(std::string(PEPPER_SOURCE_DIR) + "/docs/configuration.md");
  ASSERT_TRUE(in) << "docs/configuration.md missing";
  std::stringstream committed;
  committed << in.rdbuf();
  EXPECT_TRUE(committed.str() == configuration_markdown())
      << "docs/configuration.md differs from the parameter table; regenerate it with\n"
         "  build/pepper_app/pepper_app config doc > docs/configuration.md";
}

TEST(ConfigDoc, ListsEveryKeyWithItsDefaultAndEveryPreset) {
  const std::string md = configuration_markdown();
  for (const Parameter& p : parameters()) {
    EXPECT_NE(md.find("| `" + p.key + "` |"), std::string::npos) << p.key;
  }
  EXPECT_NE(md.find("| `navigator.controller` | enum | `vnhv` |"), std::string::npos);
  EXPECT_NE(md.find("| `navigator.vnhv.kp_1_m2` | double | `9` | 1/m^2 | `(0, inf)` |"),
            std::string::npos);
  for (const Preset& p : presets()) EXPECT_NE(md.find("| `" + p.name + "` |"), std::string::npos);
}

}  // namespace
}  // namespace pepper::app
