// The typed builders produce the documented schema (docs/teach_ui.md, teach_ui/ui_messages.hpp).
#include <gtest/gtest.h>

#include "teach_ui/ui_messages.hpp"

namespace pepper::teach_ui {
namespace {

TEST(UiMessages, OverlayHasSizeGroupsAndOptionalStamp) {
  Overlay o;
  o.width_px = 640;
  o.height_px = 480;
  o.lines.push_back({"matched", "#0f0", 2.0, {{1, 2, 3, 4}}});
  o.points.push_back({"", "#f00", 3.0, {{5, 6}, {7, 8}}});
  nlohmann::json j = to_json(o);
  EXPECT_EQ(j["width_px"], 640);
  EXPECT_EQ(j["lines"][0]["segments"][0], nlohmann::json({1.0, 2.0, 3.0, 4.0}));
  EXPECT_EQ(j["lines"][0]["label"], "matched");
  EXPECT_EQ(j["points"][0]["uv"].size(), 2u);
  EXPECT_FALSE(j["points"][0].contains("label"));
  EXPECT_FALSE(j.contains("t_ns"));
  o.t_ns = 42;
  EXPECT_EQ(to_json(o)["t_ns"], 42);
}

TEST(UiMessages, ReplayStatusOmitsMissingLocalisation) {
  ReplayStatus r;
  r.state = "running";
  r.key_index = 3;
  r.key_count = 12;
  EXPECT_FALSE(to_json(r).contains("localisation"));
  r.localisation = Localisation{true, 2, "38 matches"};
  const auto j = to_json(r);
  EXPECT_EQ(j["localisation"]["ok"], true);
  EXPECT_EQ(j["localisation"]["key_index"], 2);
  EXPECT_EQ(j["key_count"], 12);
}

TEST(UiMessages, TeachSummaryTopViewSamplesAndConnection) {
  TeachStatus t;
  t.key_images.push_back({0, 14, 40, 0.0, false});
  t.key_images.push_back({1, 3, 5, 0.6, true});
  const auto tj = to_json(t);
  EXPECT_EQ(tj["key_images"].size(), 2u);
  EXPECT_EQ(tj["key_images"][1]["weak"], true);
  const auto mj = to_json(MapSummary{2, 0.6, 3, 5, {1}, "maps/a"});
  EXPECT_EQ(mj["weak_key_images"], nlohmann::json({1}));
  const auto vj = to_json(TopView{{{0, 0}, {1, 0.5}}, {}, {{0, 0}}});
  EXPECT_EQ(vj["taught"][1], nlohmann::json({1.0, 0.5}));
  EXPECT_TRUE(vj["replayed"].empty());
  PlotSample s;
  s.t_s = 1.5;
  s.omega_rad_s = -0.2;
  const auto sj = to_json(s);
  EXPECT_EQ(sj.size(), 2u);
  EXPECT_DOUBLE_EQ(sj["omega_rad_s"].get<double>(), -0.2);
  const auto cj = connection_state("connected", true);
  EXPECT_EQ(cj["connection"]["robot"], "connected");
  EXPECT_FALSE(cj["connection"].contains("detail"));
}

}  // namespace
}  // namespace pepper::teach_ui
