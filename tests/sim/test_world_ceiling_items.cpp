// World files: `ceiling_items` (docs/mock_robot.md "Ceiling items"): each kind parses into the
// footprint and heights the file says and adds render geometry; bad values are refused naming
// the item and the key.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "sim/world.hpp"

namespace pepper::sim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

const std::filesystem::path kWorlds = std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds";

// A 6 x 4 m room, ceiling at 2.7 m; the floor (and so the ceiling) spans [-0.5, 6.5] x [-0.5, 4.5].
constexpr const char* kRoom = R"(
textures:
  paint: {type: noise, mean: 180, contrast: 10}
  grey: {type: uniform, mean: 90}
floor: {texture: paint}
ceiling: {height_m: 2.7, texture: paint}
walls:
  - points: [[0, 0], [6, 0], [6, 4], [0, 4]]
    closed: true
    texture: paint
ceiling_items:
)";

World room_with(const std::string& items) {
  return parse_world(std::string(kRoom) + items, "mem.yaml", kWorlds);
}

std::string error_of(const std::string& items, const char* base = kRoom) {
  try {
    parse_world(std::string(base) + items, "bad_world.yaml", kWorlds);
  } catch (const WorldError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(WorldCeilingItems, EachKindParsesIntoItsFootprintAndHeights) {
  const World bare = parse_world(std::string(kRoom) + "  []\n", "mem.yaml", kWorlds);
  const World w = room_with(
      "  - {kind: vent, center: [1, 1], size_m: [0.9, 0.3], yaw_deg: 90, texture: grey}\n"
      "  - {kind: tile, center: [2.1, 1.5], texture: grey, brightness: 0.5}\n"
      "  - {kind: sprinkler, center: [3, 1], texture: grey}\n"
      "  - {kind: detector, name: smoke, center: [3, 2], width_m: 0.15, drop_m: 0.05, texture: grey}\n"
      "  - {kind: beam, from: [4, 0], to: [4, 4], width_m: 0.3, depth_m: 0.25, texture: grey}\n"
      "  - {kind: sign, center: [5, 2], yaw_deg: 180, size_m: [0.4, 0.2], drop_m: 0.15, texture: grey}\n");
  ASSERT_EQ(w.ceiling_items.size(), 6u);
  const auto& it = w.ceiling_items;
  EXPECT_EQ(it[0].kind, CeilingItemKind::kVent);
  EXPECT_NEAR(it[0].yaw_rad, M_PI / 2, 1e-12);
  EXPECT_NEAR(it[0].size_m.x(), 0.9, 1e-12);
  EXPECT_NEAR(it[0].z_bottom_m, 2.7 - 0.004, 1e-12);
  EXPECT_EQ(it[1].kind, CeilingItemKind::kTile);
  EXPECT_NEAR(it[1].size_m.x(), 0.6, 1e-12);  // default: one 0.6 m tile
  EXPECT_NEAR(it[1].z_bottom_m, 2.7 - 0.002, 1e-12);
  EXPECT_EQ(it[2].kind, CeilingItemKind::kSprinkler);
  EXPECT_NEAR(it[2].size_m.x(), 0.06, 1e-12);
  EXPECT_NEAR(it[2].z_bottom_m, 2.67, 1e-12);
  EXPECT_EQ(it[3].what, "smoke");
  EXPECT_NEAR(it[3].size_m.y(), 0.15, 1e-12);
  EXPECT_NEAR(it[3].z_bottom_m, 2.65, 1e-12);
  EXPECT_EQ(it[4].kind, CeilingItemKind::kBeam);
  EXPECT_NEAR(it[4].center_m.x(), 4.0, 1e-12);
  EXPECT_NEAR(it[4].center_m.y(), 2.0, 1e-12);
  EXPECT_NEAR(it[4].size_m.x(), 4.0, 1e-12);
  EXPECT_NEAR(it[4].yaw_rad, M_PI / 2, 1e-12);
  EXPECT_NEAR(it[4].z_bottom_m, 2.45, 1e-12);
  EXPECT_EQ(it[5].kind, CeilingItemKind::kSign);
  EXPECT_NEAR(it[5].z_bottom_m, 2.7 - 0.15 - 0.2, 1e-12);
  EXPECT_NEAR(it[5].size_m.y(), 0.4, 1e-12);
  // Render geometry: 1 quad per flat item, 6 per hanging box (4 sides, top, bottom), 2 rods more
  // per sign; nothing to collide with.
  EXPECT_EQ(w.quads.size() - bare.quads.size(), 1u + 1u + 6u + 6u + 6u + 3u * 6u);
  EXPECT_EQ(w.boxes.size(), bare.boxes.size());
  EXPECT_FALSE(w.collision({4.0, 2.0}, 0.3, 0.0).has_value());  // under the beam
  EXPECT_THAT(summary(w), AllOf(HasSubstr("ceiling items:"), HasSubstr("1 beam"),
                                HasSubstr("1 vent")));
}

TEST(WorldCeilingItems, KindNamesRoundTrip) {
  for (CeilingItemKind k : {CeilingItemKind::kVent, CeilingItemKind::kTile,
                            CeilingItemKind::kSprinkler, CeilingItemKind::kDetector,
                            CeilingItemKind::kBeam, CeilingItemKind::kSign})
    EXPECT_EQ(ceiling_item_kind_from_string(to_string(k)), k);
  EXPECT_THROW(ceiling_item_kind_from_string("lamp"), std::invalid_argument);
}

TEST(WorldCeilingItems, UnknownKindListsTheKnownOnes) {
  EXPECT_THAT(error_of("  - {kind: chandelier, center: [1, 1], texture: grey}\n"),
              AllOf(HasSubstr("bad_world.yaml:12"), HasSubstr("ceiling_items[0].kind"),
                    HasSubstr("chandelier"), HasSubstr("vent, tile, sprinkler")));
  EXPECT_THAT(error_of("  - {center: [1, 1], texture: grey}\n"),
              AllOf(HasSubstr("ceiling_items[0].kind"), HasSubstr("missing required key")));
}

TEST(WorldCeilingItems, OutsideTheCeilingIsRefused) {
  EXPECT_THAT(error_of("  - {kind: vent, center: [6.4, 1], size_m: [0.6, 0.6], texture: grey}\n"),
              AllOf(HasSubstr("ceiling_items[0].center"), HasSubstr("outside the ceiling")));
  EXPECT_THAT(error_of("  - {kind: beam, from: [1, -1], to: [1, 3], texture: grey}\n"),
              AllOf(HasSubstr("ceiling_items[0].from"), HasSubstr("outside the ceiling")));
}

TEST(WorldCeilingItems, HangingTooLowIsRefusedNamingTheKey) {
  EXPECT_THAT(error_of("  - {kind: beam, from: [1, 0], to: [1, 4], depth_m: 0.8, texture: grey}\n"),
              AllOf(HasSubstr("ceiling_items[0].depth_m"), HasSubstr("hangs down to 1.9"),
                    HasSubstr("2 m")));
  EXPECT_THAT(error_of("  - {kind: sign, center: [1, 1], drop_m: 0.6, texture: grey}\n"),
              AllOf(HasSubstr("ceiling_items[0].drop_m"), HasSubstr("below the lowest")));
  EXPECT_THAT(error_of("  - {kind: sprinkler, center: [1, 1], drop_m: 1.0, texture: grey}\n"),
              HasSubstr("ceiling_items[0].drop_m"));
}

TEST(WorldCeilingItems, BadValuesAreRefusedNamingTheKey) {
  EXPECT_THAT(error_of("  - {kind: vent, center: [1, 1], size_m: [0.6, 0], texture: grey}\n"),
              AllOf(HasSubstr("ceiling_items[0].size_m"), HasSubstr("> 0")));
  EXPECT_THAT(error_of("  - {kind: sprinkler, center: [1, 1], width_m: -0.1, texture: grey}\n"),
              AllOf(HasSubstr("ceiling_items[0].width_m"), HasSubstr("> 0")));
  EXPECT_THAT(error_of("  - {kind: beam, from: [1, 1], to: [1, 1.01], texture: grey}\n"),
              AllOf(HasSubstr("ceiling_items[0].to"), HasSubstr("0.05 m apart")));
  EXPECT_THAT(error_of("  - {kind: tile, center: [1, 1], texture: marble}\n"),
              AllOf(HasSubstr("ceiling_items[0].texture"), HasSubstr("unknown texture")));
  EXPECT_THAT(error_of("  - {kind: vent, center: [1, 1], texture: grey, depth_m: 0.1}\n"),
              AllOf(HasSubstr("ceiling_items[0].depth_m"), HasSubstr("unknown key")));
  EXPECT_THAT(error_of("  - {kind: vent, size_m: [0.6, 0.6], texture: grey}\n"),
              AllOf(HasSubstr("ceiling_items[0].center"), HasSubstr("missing required key")));
  EXPECT_THAT(error_of("  - {kind: vent, center: [1, one], texture: grey}\n"),
              AllOf(HasSubstr("ceiling_items[0].center"), HasSubstr("expected a number")));
}

TEST(WorldCeilingItems, ItemsNeedACeiling) {
  std::string no_ceiling = kRoom;
  no_ceiling.erase(no_ceiling.find("ceiling: {"), std::string("ceiling: {height_m: 2.7, texture: paint}\n").size());
  EXPECT_THAT(error_of("  - {kind: vent, center: [1, 1], texture: grey}\n", no_ceiling.c_str()),
              AllOf(HasSubstr("ceiling_items"), HasSubstr("need a `ceiling:`")));
}

}  // namespace
}  // namespace pepper::sim
