// Map management (offline/map_tools.hpp, issue 25): where a tour is weak, the range check and
// the trimming of a map and of its taught path, on small hand-made maps whose expected results
// follow from their numbers. The commands on a real taught map: tests/app/e2e/test_map_e2e.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <stdexcept>

#include "offline/map_tools.hpp"
#include "support/temp_dir.hpp"

namespace pepper::app {
namespace {

namespace mem = core::memory;

/// Key images every `gap_m` metres (taught at 0.2 m/s), each with `lines` lines and `corners`
/// points.
mem::MapSummary evenly_spaced(int n, double gap_m, int lines = 30, int corners = 30) {
  mem::MapSummary s;
  s.key_image_count = n;
  s.final_index = n - 1;
  for (int i = 0; i < n; ++i) {
    mem::MapSummary::PerKeyImage k;
    k.source_frame_index = 10 * i;
    k.travelled_m = gap_m * i;
    k.t_ns = static_cast<int64_t>(gap_m * i / 0.2 * 1e9);
    k.lines = lines;
    k.corners = corners;
    s.key_images.push_back(k);
  }
  return s;
}

TEST(MapTools, AnEvenTourWithEnoughFeaturesHasNoWarning) {
  EXPECT_TRUE(check_tour(evenly_spaced(8, 0.5)).empty());
}

TEST(MapTools, AKeyImageWithFewFeaturesIsWarnedWithWhatToDo) {
  mem::MapSummary s = evenly_spaced(6, 0.5);
  s.key_images[3].lines = 12;
  s.key_images[3].corners = 20;  // 32 < 40
  const auto w = check_tour(s);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].key_index, 3);
  EXPECT_NE(w[0].text.find("key image 3 has few features (12 lines, 20 points"), std::string::npos)
      << w[0].text;
  EXPECT_NE(w[0].text.find("add texture"), std::string::npos) << w[0].text;
  // 40 features exactly is enough (the teach UI's threshold is "fewer than").
  s.key_images[3].lines = 20;
  EXPECT_TRUE(check_tour(s).empty());
}

TEST(MapTools, ALongGapIsWarnedOnlyWhenLongInMetresAndAgainstTheTour) {
  mem::MapSummary s = evenly_spaced(6, 0.5);
  // Key image 4 moves 1.6 m further on: the gap 3..4 is 2.1 m, over 3 x the median (0.5 m) and
  // over 1.5 m.
  for (int i = 4; i < 6; ++i) s.key_images[i].travelled_m += 1.6;
  auto w = check_tour(s);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].key_index, 4);
  EXPECT_NE(w[0].text.find("2.1 m between key images 3 and 4 (typical: 0.5 m)"), std::string::npos)
      << w[0].text;
  // A tour of short gaps: 3 x the median is not enough when the gap itself is short (1.2 m).
  mem::MapSummary shortgaps = evenly_spaced(6, 0.2);
  for (int i = 4; i < 6; ++i) shortgaps.key_images[i].travelled_m += 1.0;
  EXPECT_TRUE(check_tour(shortgaps).empty());
}

TEST(MapTools, WithoutDistancesGapsAreMeasuredInTaughtTime) {
  mem::MapSummary s = evenly_spaced(6, 0.5);  // 2.5 s between key images
  for (auto& k : s.key_images) k.travelled_m = NAN;
  for (int i = 4; i < 6; ++i) s.key_images[i].t_ns += 20'000'000'000;  // + 20 s
  const auto w = check_tour(s);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].text.find("22.5 s between key images 3 and 4"), std::string::npos) << w[0].text;
}

mem::VisualMemory numbered_map(int n) {
  mem::VisualMemory map;
  map.camera.width_px = 320;
  map.camera.height_px = 240;
  map.parameters_json = R"({"a":1})";
  for (int i = 0; i < n; ++i) {
    mem::KeyImage k;
    k.source_frame_index = 10 * i;
    k.t_ns = 1'000'000'000LL * i;
    k.travelled_m = 0.5 * i;
    k.odom = core::OdometryPose{0.5 * i, 0.0, 0.0};
    map.key_images.push_back(k);
  }
  return map;
}

TEST(MapTools, TrimKeepsTheRangeAndMeasuresFromItsFirstKeyImage) {
  const mem::VisualMemory map = numbered_map(8);
  const mem::VisualMemory t = trim_map(map, 2, 5);
  ASSERT_EQ(t.key_images.size(), 4u);
  EXPECT_EQ(t.parameters_json, map.parameters_json);
  EXPECT_EQ(t.camera.width_px, 320);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(t.key_images[i].source_frame_index, 10 * (i + 2));
    EXPECT_EQ(t.key_images[i].t_ns, 1'000'000'000LL * (i + 2));
    EXPECT_DOUBLE_EQ(t.key_images[i].travelled_m, 0.5 * i);  // from the new start
    ASSERT_TRUE(t.key_images[i].odom.has_value());
    EXPECT_DOUBLE_EQ(t.key_images[i].odom->x_m, 0.5 * (i + 2));  // odometry as taught
  }
}

TEST(MapTools, TrimRefusesRangesThatDoNotLeaveTwoKeyImages) {
  const mem::VisualMemory map = numbered_map(5);  // key images 0..4
  for (const auto& [from, to] : std::vector<std::pair<int, int>>{{3, 3}, {4, 2}, {-1, 3}, {0, 5}}) {
    SCOPED_TRACE(std::to_string(from) + ".." + std::to_string(to));
    try {
      trim_map(map, from, to);
      ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("the map has key images 0..4"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_EQ(trim_map(map, 0, 4).key_images.size(), 5u);
  EXPECT_EQ(trim_map(map, 3, 4).key_images.size(), 2u);
}

TEST(MapTools, TrimmedTaughtPathKeepsTheFramesBetweenTheKeptKeyImages) {
  const mem::VisualMemory map = numbered_map(5);  // source frames 0, 10, ..., 40
  TaughtPath path;
  path.world = "w";
  for (int f = 0; f <= 40; ++f) path.path_m.emplace_back(0.05 * f, 0.0);
  for (int i = 0; i < 5; ++i) path.key_images_m.emplace_back(0.5 * i, 0.0);
  const TaughtPath t = trim_taught_path(path, map, 1, 3);
  EXPECT_EQ(t.world, "w");
  ASSERT_EQ(t.key_images_m.size(), 3u);
  EXPECT_DOUBLE_EQ(t.key_images_m.front().x(), 0.5);
  ASSERT_EQ(t.path_m.size(), 21u);  // frames 10..30
  EXPECT_DOUBLE_EQ(t.path_m.front().x(), 0.5);
  EXPECT_DOUBLE_EQ(t.path_m.back().x(), 1.5);
  // A path that does not reach the kept frames is not this map's: the key positions stand in.
  path.path_m.resize(20);
  EXPECT_EQ(trim_taught_path(path, map, 1, 3).path_m.size(), 3u);
}

TEST(MapTools, FindMapsListsMapFoldersAndNamesUnreadableOnes) {
  test::TempDir dir("pepper-map-list");
  std::filesystem::create_directories(dir.path() / "empty");
  std::filesystem::create_directories(dir.path() / "site" / "junk");
  std::ofstream(dir.path() / "site" / "junk" / "manifest.json") << "not JSON";
  const auto maps = find_maps(dir.path());
  ASSERT_EQ(maps.size(), 1u);
  EXPECT_EQ(maps[0].name, "site/junk");
  EXPECT_FALSE(maps[0].readable);
  EXPECT_NE(to_text(maps[0]).find("site/junk  unreadable: "), std::string::npos)
      << to_text(maps[0]);
  EXPECT_THROW(find_maps(dir.path() / "no_such_folder"), std::runtime_error);
}

}  // namespace
}  // namespace pepper::app
