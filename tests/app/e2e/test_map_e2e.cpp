// `pepper_app map list / show / trim` (issue 25) on a real map: taught once for the suite on the
// mock robot (2.5 m of robotics_room at QVGA, a few seconds), then listed, shown as an HTML page
// and trimmed; the trimmed map must load and pass `map info --full`, bad arguments must exit 2
// with a message naming the allowed range, and the input map must stay as it was.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "app/e2e/app_process.hpp"
#include "core/memory/visual_memory.hpp"
#include "session/taught_path.hpp"

namespace pepper::app {
namespace {

namespace fs = std::filesystem;

const std::string kWorldFile = std::string(PEPPER_SOURCE_DIR) + "/worlds/robotics_room.yaml";

class MapCommands : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: ctest runs each test of the suite as a process of its own, in
    // parallel, and each teaches its map.
    dir_ = fs::temp_directory_path() / ("pepper_e2e_map_commands_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "maps");
    test::AppProcess teach({"teach", "--robot", "mock:" + kWorldFile, "--map",
                            (dir_ / "maps" / "room").string(), "--max-distance", "2.5", "--set",
                            "robot.camera_width_px=320", "--set", "robot.camera_height_px=240"},
                           dir_, "teach");
    teach_ok_ = teach.wait() == 0;
    teach_output_ = teach.both();
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  void SetUp() override {
    ASSERT_TRUE(teach_ok_) << teach_output_;
    map_ = core::memory::load_map(dir_ / "maps" / "room");
    ASSERT_GE(map_.key_images.size(), 4u) << "the tests trim both ends and keep two";
  }
  static std::string run(const std::vector<std::string>& args, const std::string& name,
                         int expect_exit) {
    test::AppProcess p(args, dir_, name);
    const int rc = p.wait();
    EXPECT_EQ(rc, expect_exit) << p.both();
    return p.out() + p.err();
  }
  static std::string manifest() { return test::AppProcess::slurp(room() / "manifest.json"); }
  static fs::path room() { return dir_ / "maps" / "room"; }

  static fs::path dir_;
  static bool teach_ok_;
  static std::string teach_output_;
  core::memory::VisualMemory map_;
};
fs::path MapCommands::dir_;
bool MapCommands::teach_ok_ = false;
std::string MapCommands::teach_output_;

TEST_F(MapCommands, ListGivesOneLinePerMapWithKeyImagesLengthAndSize) {
  const std::string out = run({"map", "list", (dir_ / "maps").string()}, "list", 0);
  // One line for the map, none for its recording folder (maps/room.recording).
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  const double length_m = map_.key_images.back().travelled_m - map_.key_images.front().travelled_m;
  char length[32];
  std::snprintf(length, sizeof length, "%.2f m", length_m);
  EXPECT_NE(out.find("room  " + std::to_string(map_.key_images.size()) + " key images  " + length),
            std::string::npos)
      << out;
  EXPECT_TRUE(std::regex_search(out, std::regex(R"(\d{4}-\d\d-\d\d \d\d:\d\d  \d+ kB)"))) << out;
}

TEST_F(MapCommands, ShowWritesAPageWithEveryKeyImageAndItsCounts) {
  const fs::path page = dir_ / "room.html";
  const std::string out = run({"map", "show", room().string(), "--out", page.string()}, "show", 0);
  EXPECT_NE(out.find("page written to " + page.string()), std::string::npos) << out;
  const std::string html = test::AppProcess::slurp(page);
  const auto summary = core::memory::summarize(map_);
  for (std::size_t i = 0; i < summary.key_images.size(); ++i) {
    SCOPED_TRACE("key image " + std::to_string(i));
    std::ostringstream thumb, caption;
    thumb << "id=\"key-" << i << "\"><img alt=\"key image " << i
          << "\" src=\"data:image/jpeg;base64,";
    caption << "#" << i << ": " << summary.key_images[i].lines << " lines, "
            << summary.key_images[i].corners << " points";
    EXPECT_NE(html.find(thumb.str()), std::string::npos);
    EXPECT_NE(html.find(caption.str()), std::string::npos);
  }
  EXPECT_EQ(html.find("id=\"key-" + std::to_string(summary.key_images.size()) + "\""),
            std::string::npos);
  // The map was taught on the mock robot: its taught path is drawn.
  EXPECT_NE(html.find("Taught path in the mock world 'robotics_room'"), std::string::npos);
  EXPECT_NE(html.find("<h2>Warnings</h2>"), std::string::npos);
}

// A key image stripped of its features (a blank wall, as far as the replay is concerned) is
// named by `map info` and `map show`, with what to do, and framed as weak on the page.
TEST_F(MapCommands, InfoAndShowWarnAboutAKeyImageWithFewFeatures) {
  core::memory::VisualMemory weak = map_;
  auto& f = weak.key_images[2].features;
  ASSERT_GT(f.lines.size(), 10u);
  f.lines.resize(10);
  f.line_descriptors = f.line_descriptors.rowRange(0, 10).clone();  // one row per line
  f.corners_px.resize(std::min<std::size_t>(f.corners_px.size(), 10));
  const fs::path weak_dir = dir_ / "weak";
  core::memory::save_map(weak, weak_dir);
  const std::string info = run({"map", "info", weak_dir.string()}, "info_weak", 0);
  EXPECT_NE(info.find("warning: key image 2 has few features (10 lines, 10 points"),
            std::string::npos)
      << info;
  EXPECT_EQ(info.find("warning: key image 1 "), std::string::npos) << info;
  const fs::path page = dir_ / "weak.html";
  const std::string show =
      run({"map", "show", weak_dir.string(), "--out", page.string()}, "show_weak", 0);
  EXPECT_NE(show.find("1 warning\n  warning: key image 2 has few features"), std::string::npos)
      << show;
  EXPECT_NE(show.find("add texture"), std::string::npos) << show;
  const std::string html = test::AppProcess::slurp(page);
  EXPECT_NE(html.find("<figure class=\"key weak\" id=\"key-2\">"), std::string::npos);
  EXPECT_EQ(html.find("<figure class=\"key weak\" id=\"key-1\">"), std::string::npos);
  // The taught map itself: no warning on this well-textured tour.
  const std::string room_info = run({"map", "info", room().string()}, "info_room", 0);
  EXPECT_EQ(room_info.find("warning:"), std::string::npos) << room_info;
}

TEST_F(MapCommands, TrimWritesAValidMapOfTheRangeAndLeavesTheInputAlone) {
  const std::string before = manifest();
  const int last = static_cast<int>(map_.key_images.size()) - 1;
  const fs::path out_dir = dir_ / "trimmed";
  fs::remove_all(out_dir);
  run({"map", "trim", room().string(), "--from", "1", "--to", std::to_string(last - 1), "--out",
       out_dir.string()},
      "trim", 0);
  const std::string info = run({"map", "info", out_dir.string(), "--full"}, "info", 0);
  EXPECT_NE(info.find("all files present and checksums verified"), std::string::npos) << info;
  const auto trimmed = core::memory::load_map(out_dir);
  ASSERT_EQ(static_cast<int>(trimmed.key_images.size()), last - 1);
  for (int i = 0; i < last - 1; ++i) {
    EXPECT_EQ(trimmed.key_images[i].source_frame_index, map_.key_images[i + 1].source_frame_index);
    EXPECT_EQ(trimmed.key_images[i].features.lines.size(),
              map_.key_images[i + 1].features.lines.size());
  }
  EXPECT_DOUBLE_EQ(trimmed.key_images.front().travelled_m, 0.0);
  // The taught path follows: the kept key images' positions.
  const auto path = load_taught_path(out_dir);
  const auto original = load_taught_path(room());
  ASSERT_TRUE(path && original);
  ASSERT_EQ(static_cast<int>(path->key_images_m.size()), last - 1);
  EXPECT_EQ(path->key_images_m.front(), original->key_images_m[1]);
  EXPECT_EQ(manifest(), before) << "the input map changed";
}

TEST_F(MapCommands, TrimRefusesBadArgumentsWithExitCode2AndWritesNothing) {
  const std::string before = manifest();
  const int last = static_cast<int>(map_.key_images.size()) - 1;
  const fs::path out_dir = dir_ / "refused";
  fs::remove_all(out_dir);
  const std::string range = "the map has key images 0.." + std::to_string(last);
  EXPECT_NE(
      run({"map", "trim", room().string(), "--from", "3", "--to", "1", "--out", out_dir.string()},
          "trim_reversed", 2)
          .find(range),
      std::string::npos);
  EXPECT_NE(run({"map", "trim", room().string(), "--to", std::to_string(last + 5), "--out",
                 out_dir.string()},
                "trim_past_end", 2)
                .find(range),
            std::string::npos);
  EXPECT_NE(run({"map", "trim", room().string(), "--from", std::to_string(last), "--out",
                 out_dir.string()},
                "trim_one_left", 2)
                .find("at least two key images"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(out_dir));
  // The input is never the output unless asked.
  EXPECT_NE(run({"map", "trim", room().string(), "--from", "1", "--out", room().string()},
                "trim_onto_input", 2)
                .find("is the input map"),
            std::string::npos);
  EXPECT_EQ(manifest(), before);
  // Nor is another existing map replaced without --overwrite.
  fs::create_directories(out_dir);
  std::ofstream(out_dir / "keep.txt") << "keep";
  EXPECT_NE(run({"map", "trim", room().string(), "--from", "1", "--out", out_dir.string()},
                "trim_onto_other", 2)
                .find("already exists"),
            std::string::npos);
  // --overwrite replaces maps, never a folder of other files.
  EXPECT_NE(
      run({"map", "trim", room().string(), "--from", "1", "--out", out_dir.string(), "--overwrite"},
          "trim_onto_files", 2)
          .find("holds files that are not a map"),
      std::string::npos);
  EXPECT_TRUE(fs::exists(out_dir / "keep.txt"));
  const fs::path other_map = dir_ / "other_map";
  fs::remove_all(other_map);
  run({"map", "trim", room().string(), "--from", "2", "--out", other_map.string()}, "trim_other",
      0);
  run({"map", "trim", room().string(), "--from", "1", "--out", other_map.string(), "--overwrite"},
      "trim_overwrite", 0);
  EXPECT_EQ(core::memory::load_map(other_map).key_images.size(), map_.key_images.size() - 1);
}

}  // namespace
}  // namespace pepper::app
