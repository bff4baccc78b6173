// `pepper_app teach --mode ceiling` (issue 24) end to end: the scripted tour of the ceiling test
// hall (tests/worlds/ceiling_hall.yaml) at QVGA, cut by --max-distance after the turn, saves a
// ceiling-mode map whose mosaic and ceiling tour load back and agree with the truth; `map info`
// summarises it; `map trim` refuses it; a damaged mosaic or tour is refused by `map info --full`
// naming the file; replay in ceiling mode drives it (briefly; a forward replay is refused).
// One test: the teach takes ~30 s and ctest runs each test as a process of its own.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "app/e2e/app_process.hpp"
#include "core/ceiling/ceiling_tour.hpp"
#include "core/ceiling/mosaic.hpp"
#include "core/memory/visual_memory.hpp"
#include "session/taught_path.hpp"

namespace pepper::app {
namespace {

namespace fs = std::filesystem;

const std::string kHall = std::string(PEPPER_SOURCE_DIR) + "/tests/worlds/ceiling_hall.yaml";

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

void write_text(const fs::path& file, const std::string& text) {
  std::ofstream(file, std::ios::binary | std::ios::trunc) << text;
}

TEST(CeilingTeachE2E, TeachesTheHallSavesMosaicAndRelayImagesAndRefusesDamage) {
  const fs::path dir =
      fs::temp_directory_path() / ("pepper_e2e_ceiling_teach_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path map_dir = dir / "hall";

  // 7 m: the 5.5 m straight, the turn (1.9 m of arc) begun and mostly done.
  test::AppProcess teach({"teach", "--mode", "ceiling", "--robot", "mock:" + kHall, "--map",
                          map_dir.string(), "--scripted", "--max-distance", "7", "--set",
                          "robot.camera_width_px=320", "--set", "robot.camera_height_px=240"},
                         dir, "teach");
  ASSERT_EQ(teach.wait(), 0) << teach.both();
  EXPECT_TRUE(contains(teach.both(), "ceiling map with")) << teach.both();

  // The map: ceiling mode, the relay images as key images.
  const core::memory::VisualMemory map = core::memory::load_map(map_dir);
  EXPECT_EQ(map.mode, core::NavMode::kCeiling);
  EXPECT_EQ(map.camera.width_px, 320);
  ASSERT_GE(map.key_images.size(), 2u);
  core::memory::LoadOptions as_forward;
  as_forward.expected_mode = core::NavMode::kForward;
  EXPECT_THROW(core::memory::load_map(map_dir, as_forward), core::memory::MapError);

  // Replay in ceiling mode runs the map (the closed-loop figures are the evaluation's,
  // tests/app/evaluation/test_ceiling_closed_loop.cpp): 60 frames from the perturbed start 0,
  // localised against the mosaic and driving (the frame limit ends it, exit 1).
  {
    const fs::path events = dir / "replay_events.jsonl";
    const fs::path telemetry = dir / "replay_telemetry.jsonl";
    test::AppProcess replay({"replay", "--mode", "ceiling", "--robot", "mock:" + kHall, "--map",
                             map_dir.string(), "--mock-start", "0", "--seed", "1",
                             "--max-frames", "60", "--events", events.string(), "--json",
                             telemetry.string()},
                            dir, "replay");
    EXPECT_EQ(replay.wait(), 1) << replay.both();
    EXPECT_TRUE(contains(replay.both(), "replay max_frames")) << replay.both();
    EXPECT_TRUE(contains(replay.both(), "furthest key image")) << replay.both();
    std::ifstream in(events);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_TRUE(contains(text, "\"why\":\"navigator\"")) << "never drove";
    // Each --json line carries the ceiling telemetry; where the localiser fixed the pose, the
    // robot's pose in the mosaic moved as the simulated robot did (the mosaic's frame is the
    // teach's first base frame, so compare displacements, not positions).
    std::ifstream lines(telemetry);
    std::string line;
    int n = 0, fixes = 0;
    std::optional<nlohmann::json> first, last;
    while (std::getline(lines, line)) {
      const nlohmann::json j = nlohmann::json::parse(line);
      ++n;
      ASSERT_TRUE(j.contains("ceiling")) << line;
      const nlohmann::json& c = j.at("ceiling");
      if (!c.at("fix").get<bool>()) continue;
      ++fixes;
      EXPECT_TRUE(c.at("pose_known").get<bool>());
      EXPECT_GT(c.at("inliers").get<int>(), 0);
      if (!first) first = j;
      last = j;
    }
    EXPECT_EQ(n, 60);
    ASSERT_GT(fixes, 30);
    auto apart_m = [](const nlohmann::json& a, const nlohmann::json& b) {
      return std::hypot(b.at("x_m").get<double>() - a.at("x_m").get<double>(),
                        b.at("y_m").get<double>() - a.at("y_m").get<double>());
    };
    const double in_mosaic_m = apart_m(first->at("ceiling").at("T_mosaic_base"),
                                       last->at("ceiling").at("T_mosaic_base"));
    const double true_m = apart_m(first->at("ground_truth"), last->at("ground_truth"));
    EXPECT_GT(true_m, 0.1) << "the robot hardly moved";
    EXPECT_NEAR(in_mosaic_m, true_m, 0.03 + 0.05 * true_m);
  }
  // A forward replay of it is refused naming both modes.
  {
    test::AppProcess replay({"replay", "--robot", "mock:" + kHall, "--map", map_dir.string()}, dir,
                            "replay_forward");
    EXPECT_EQ(replay.wait(), 4) << replay.both();
    EXPECT_TRUE(contains(replay.err(), "ceiling mode")) << replay.both();
  }

  // The mosaic and the tour load back (checksums, validation).
  const core::ceiling::Mosaic mosaic = core::ceiling::load_mosaic(map_dir / "mosaic.json");
  EXPECT_GT(mosaic.landmarks.size(), 300u);
  EXPECT_DOUBLE_EQ(mosaic.px_per_m, 120.0);
  const core::ceiling::CeilingTour tour =
      core::ceiling::load_ceiling_tour(map_dir / "ceiling_tour.json");
  ASSERT_EQ(tour.relay_images.size(), map.key_images.size());
  EXPECT_GE(tour.relay_images.size(), 2u);
  EXPECT_GT(tour.frames, 100);
  EXPECT_EQ(tour.unlocalised_frames, 0) << "the hall's ceiling is textured everywhere";
  EXPECT_TRUE(tour.breaks.empty());
  EXPECT_EQ(tour.relay_images.front().frame, 0);
  EXPECT_EQ(tour.relay_images.back().frame, tour.frames - 1);
  ASSERT_TRUE(tour.odometry_disagreement_m.has_value());
  for (size_t i = 0; i < tour.relay_images.size(); ++i) {
    EXPECT_EQ(tour.relay_images[i].frame, map.key_images[i].source_frame_index) << i;
    // Condition (1) of the relay images (8 shared landmarks) needs at least 8 seen by each.
    EXPECT_GE(tour.relay_images[i].landmark_ids.size(), 8u) << i;
  }

  // The chained relay poses against the simulator's truth: the distance of each relay image from
  // the start (rotation-free: the mosaic frame is the first base frame, the truth the world's).
  const std::optional<TaughtPath> taught = load_taught_path(map_dir);
  ASSERT_TRUE(taught.has_value()) << "a mock teach saves the true path";
  const TaughtPath& truth = *taught;
  ASSERT_EQ(truth.key_images_m.size(), tour.relay_images.size());
  double last_from_start_m = 0.0;
  for (size_t i = 0; i < tour.relay_images.size(); ++i) {
    const auto& T = tour.relay_images[i].T_mosaic_base;
    const double chained_m = std::hypot(T.x_m, T.y_m);
    const double true_m = (truth.key_images_m[i] - truth.key_images_m[0]).norm();
    EXPECT_NEAR(chained_m, true_m, 0.01 * true_m + 0.03) << "relay image " << i;
    last_from_start_m = true_m;
  }
  EXPECT_GT(last_from_start_m, 5.5) << "the tour reached the turn";
  // The heading turned left with the path (the turn is begun when the tour ends).
  EXPECT_GT(tour.relay_images.back().T_mosaic_base.theta_rad, 0.3);

  // map info: the ceiling summary, in both forms.
  for (const bool full : {false, true}) {
    std::vector<std::string> args = {"map", "info", map_dir.string()};
    if (full) args.push_back("--full");
    test::AppProcess info(args, dir, full ? "info_full" : "info");
    ASSERT_EQ(info.wait(), 0) << info.both();
    const std::string out = info.out();
    EXPECT_TRUE(contains(out, "mode: ceiling")) << out;
    EXPECT_TRUE(
        contains(out, "ceiling mosaic: " + std::to_string(mosaic.landmarks.size()) + " landmarks"))
        << out;
    EXPECT_TRUE(contains(out, "relay images: " + std::to_string(tour.relay_images.size()))) << out;
    EXPECT_FALSE(contains(out, "warning:")) << out;
    EXPECT_EQ(contains(out, "checksums verified"), full) << out;
  }

  // map trim would leave the mosaic and the tour behind: refused.
  {
    test::AppProcess trim({"map", "trim", map_dir.string(), "--from", "0", "--to", "1", "--out",
                           (dir / "cut").string()},
                          dir, "trim");
    EXPECT_EQ(trim.wait(), 2) << trim.both();
    EXPECT_TRUE(contains(trim.err(), "ceiling-mode map")) << trim.both();
    EXPECT_FALSE(fs::exists(dir / "cut"));
  }

  // A damaged mosaic (one descriptor digit changed) and a truncated tour file: refused, named.
  const std::string mosaic_text = test::AppProcess::slurp(map_dir / "mosaic.json");
  const size_t digit = mosaic_text.find("\"descriptor\": \"") + 15;
  ASSERT_NE(digit, std::string::npos + 15);
  std::string damaged = mosaic_text;
  damaged[digit] = damaged[digit] == '0' ? '1' : '0';
  write_text(map_dir / "mosaic.json", damaged);
  {
    test::AppProcess info({"map", "info", "--full", map_dir.string()}, dir, "info_bad_mosaic");
    EXPECT_EQ(info.wait(), 1) << info.both();
    EXPECT_TRUE(contains(info.err(), (map_dir / "mosaic.json").string() + ": CRC-32 mismatch"))
        << info.both();
    EXPECT_TRUE(contains(info.err(), "teach --mode ceiling")) << info.both();
  }
  write_text(map_dir / "mosaic.json", mosaic_text);
  const std::string tour_text = test::AppProcess::slurp(map_dir / "ceiling_tour.json");
  write_text(map_dir / "ceiling_tour.json", tour_text.substr(0, tour_text.size() / 2));
  {
    test::AppProcess info({"map", "info", "--full", map_dir.string()}, dir, "info_bad_tour");
    EXPECT_EQ(info.wait(), 1) << info.both();
    EXPECT_TRUE(contains(info.err(), (map_dir / "ceiling_tour.json").string() + ": not valid JSON"))
        << info.both();
  }
  write_text(map_dir / "ceiling_tour.json", tour_text);
  fs::remove(map_dir / "mosaic.json");
  {
    test::AppProcess info({"map", "info", map_dir.string()}, dir, "info_no_mosaic");
    EXPECT_EQ(info.wait(), 1) << info.both();
    EXPECT_TRUE(contains(info.err(), (map_dir / "mosaic.json").string() + ": missing"))
        << info.both();
  }

  std::error_code ec;
  fs::remove_all(dir, ec);
}

}  // namespace
}  // namespace pepper::app
