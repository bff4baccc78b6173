#include "config/app_config.hpp"

#include <fstream>

#include <gtest/gtest.h>

#include "config/config_yaml.hpp"
#include "support/temp_dir.hpp"

namespace pepper::app {
namespace {

TEST(AppConfig, DefaultsAreThePapersValuesAndValid) {
  const AppConfig c;
  EXPECT_TRUE(c.validate().empty());
  const auto nav = c.navigator_options();
  EXPECT_DOUBLE_EQ(nav.ibvs.g1, 0.7);  // METHOD.md: g1 = 0.7, g2 = 0.3, lambda = 1
  EXPECT_DOUBLE_EQ(nav.ibvs.g2, 0.3);
  EXPECT_DOUBLE_EQ(nav.ibvs.lambda, 1.0);
  EXPECT_DOUBLE_EQ(nav.schedule.v_straight_m_s, 0.15);
  EXPECT_DOUBLE_EQ(nav.schedule.v_turn_m_s, 0.08);
}

TEST(AppConfig, DumpThenLoadIsIdentity) {
  AppConfig c;
  c.navigator.ibvs.g1 = 0.55;
  c.navigator.controller = core::navigator::ControllerKind::kVnhv;
  c.navigator.features = core::control::FeatureMode::kPointsOnly;
  c.matcher.trifocal.seed = 42;
  c.robot.user = "nao";
  test::TempDir tmp;
  const auto file = tmp.path() / "config.yaml";
  std::ofstream(file) << json_to_yaml(config_to_json(c));
  const AppConfig back = load_app_config(file, {});
  EXPECT_EQ(config_to_json(back), config_to_json(c));
  EXPECT_EQ(back.navigator.controller, core::navigator::ControllerKind::kVnhv);
  EXPECT_EQ(back.robot.user, "nao");
}

TEST(AppConfig, OverridesApplyAfterTheFileInOrder) {
  test::TempDir tmp;
  const auto file = tmp.path() / "c.yaml";
  std::ofstream(file) << "navigator:\n  ibvs:\n    g1: 0.6\nrobot:\n  camera_fps: 10\n";
  const AppConfig c = load_app_config(
      file, {"navigator.ibvs.g1=0.5", "navigator.features=lines", "robot.camera_fps=12",
             "robot.user=\"123\""});
  EXPECT_DOUBLE_EQ(c.navigator.ibvs.g1, 0.5);
  EXPECT_EQ(c.navigator.features, core::control::FeatureMode::kLinesOnly);
  EXPECT_EQ(c.robot.camera_fps, 12);
  EXPECT_EQ(c.robot.user, "123");  // quoted: stays a string
}

void expect_config_error(const std::filesystem::path& file, const std::vector<std::string>& sets,
                         const std::string& needle) {
  try {
    load_app_config(file, sets);
    FAIL() << "expected ConfigError containing '" << needle << "'";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(AppConfig, UnknownKeysWrongTypesAndBadValuesNameTheKey) {
  test::TempDir tmp;
  const auto file = tmp.path() / "bad.yaml";
  std::ofstream(file) << "navigator:\n  ibvs:\n    gg1: 0.6\n";
  expect_config_error(file, {}, "bad.yaml: navigator.ibvs.gg1: unknown key");
  expect_config_error({}, {"robot.camera_fps=fast"}, "robot.camera_fps: must be a whole number");
  expect_config_error({}, {"navigator.controller=pid"}, "must be one of ibvs, vnhv");
  expect_config_error({}, {"robot.camera_fps=100"}, "robot.camera_fps = 100: must be in [1, 30]");
  expect_config_error({}, {"navigator.ibvs.g1=-1"}, "g1");
  expect_config_error({}, {"novalue"}, "expected dotted.key=value");
  expect_config_error(tmp.path() / "missing.yaml", {}, "missing.yaml: cannot open");
}

// An option that was removed says so, and what to do, in a file and on --set.
TEST(AppConfig, ARemovedOptionSaysItWasRemoved) {
  test::TempDir tmp;
  const auto file = tmp.path() / "old.yaml";
  std::ofstream(file) << "navigator:\n  switching:\n    passed_next_scale_ratio: 1.05\n";
  expect_config_error(file, {}, "old.yaml: navigator.switching.passed_next_scale_ratio: removed");
  expect_config_error({}, {"navigator.switching.passed_next_scale_ratio=0"}, "delete the key");
  expect_config_error({}, {"navigator.turn_feedforward=1"}, "navigator.turn_feedforward: removed");
  expect_config_error({}, {"ceiling.coast_max_m=0.3"}, "replaced by ceiling.coast_max_error_m");
}

TEST(AppConfig, SharedFeatureOptionsReachTeachAndReplay) {
  const AppConfig c = load_app_config({}, {"features.extractor.max_lines=80",
                                           "features.klt.window_px=15"});
  EXPECT_EQ(c.teach_options().extractor.max_lines, 80);
  EXPECT_EQ(c.navigator_options().extractor.max_lines, 80);
  EXPECT_EQ(c.navigator_options().matcher.klt.window_px, 15);  // tracking uses the key pyramids'
  EXPECT_EQ(c.teach_options().matcher.klt.window_px, 15);
}

}  // namespace
}  // namespace pepper::app
