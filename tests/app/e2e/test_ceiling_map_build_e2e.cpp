// `pepper_app map build` of a ceiling teach's recording (issue 24): the recording says how the
// teach ran (format version 2: mode, head pitch, ceiling), and map build runs the live teach's
// CeilingTeacher over its frames. One short scripted teach of the ceiling test hall
// (tests/worlds/ceiling_hall.yaml, QVGA, 3 m: ~2 s) serves every test of the suite.
// Measured (one run): 188 frames, 852 landmarks, 4 relay images (frames 0, 105, 181, 187); the
// rebuild's mosaic.json and ceiling_tour.json are byte for byte the teach's, and so are its key
// images (the pipeline is deterministic: seeded RANSAC, no threads); each build takes ~1.2 s.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "app/e2e/app_process.hpp"
#include "core/ceiling/ceiling_tour.hpp"
#include "core/ceiling/mosaic.hpp"
#include "core/memory/visual_memory.hpp"

namespace pepper::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kHall = std::string(PEPPER_SOURCE_DIR) + "/tests/worlds/ceiling_hall.yaml";
constexpr double kHallCeilingM = 2.8;  // tests/worlds/ceiling_hall.yaml

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

json read_json(const fs::path& file) { return json::parse(test::AppProcess::slurp(file)); }

void write_json(const fs::path& file, const json& j) {
  std::ofstream(file, std::ios::trunc) << j.dump(2) << "\n";
}

class CeilingMapBuildE2E : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("pepper_e2e_ceiling_build_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    test::AppProcess teach({"teach", "--mode", "ceiling", "--robot", "mock:" + kHall, "--map",
                            (dir_ / "taught").string(), "--recording", (dir_ / "rec").string(),
                            "--scripted", "--max-distance", "3", "--set",
                            "robot.camera_width_px=320", "--set", "robot.camera_height_px=240"},
                           dir_, "teach");
    teach_code_ = teach.wait();
    teach_output_ = teach.both();
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  void SetUp() override { ASSERT_EQ(teach_code_, 0) << teach_output_; }

  /// `map build --recording REC --map DIR` plus `extra`; its exit code, output in `*both`.
  static int build(const fs::path& rec, const fs::path& map, std::vector<std::string> extra,
                   const std::string& name, std::string* both, std::string* out = nullptr) {
    std::vector<std::string> args = {"map", "build", "--recording", rec.string(), "--map",
                                     map.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    test::AppProcess p(args, dir_, name);
    const int code = p.wait();
    *both = p.both();
    if (out) *out = p.out();
    return code;
  }

  /// A copy of the teach's recording whose manifest `edit` changes.
  template <class Edit>
  static fs::path edited_recording(const std::string& name, Edit edit) {
    const fs::path rec = dir_ / name;
    fs::remove_all(rec);
    fs::copy(dir_ / "rec", rec, fs::copy_options::recursive);
    json m = read_json(rec / "recording.json");
    edit(m);
    write_json(rec / "recording.json", m);
    return rec;
  }

  static fs::path dir_;
  static int teach_code_;
  static std::string teach_output_;
};
fs::path CeilingMapBuildE2E::dir_;
int CeilingMapBuildE2E::teach_code_ = -1;
std::string CeilingMapBuildE2E::teach_output_;

TEST_F(CeilingMapBuildE2E, RecordingSaysHowTheTeachRan) {
  const json m = read_json(dir_ / "rec" / "recording.json");
  EXPECT_EQ(m.at("version"), 2);
  EXPECT_EQ(m.at("mode"), "ceiling");
  EXPECT_DOUBLE_EQ(m.at("head_pitch_rad").get<double>(), -0.7);  // robot.ceiling_head_pitch_rad
  EXPECT_DOUBLE_EQ(m.at("ceiling").at("height_m").get<double>(), kHallCeilingM);
  // The ceiling above the camera is the one the tour was taught under.
  const core::ceiling::CeilingTour tour =
      core::ceiling::load_ceiling_tour(dir_ / "taught" / "ceiling_tour.json");
  ASSERT_TRUE(tour.ceiling.has_value());
  EXPECT_EQ(m.at("ceiling").at("above_camera_m").get<double>(), tour.ceiling->above_camera_m);
}

// The main promise: the offline build of a teach's recording is the live teach's map.
TEST_F(CeilingMapBuildE2E, RebuildsTheLiveTeachsMapBitForBit) {
  const fs::path built = dir_ / "built";
  std::string both, out;
  ASSERT_EQ(build(dir_ / "rec", built, {}, "build", &both, &out), 0) << both;
  EXPECT_TRUE(contains(out, "ceiling map written to")) << both;
  EXPECT_TRUE(contains(both, "as recorded")) << both;
  const auto live = core::memory::load_map(dir_ / "taught");
  const auto offline = core::memory::load_map(built);
  EXPECT_EQ(offline.mode, core::NavMode::kCeiling);
  ASSERT_GE(live.key_images.size(), 2u);
  // Same relay images: frames, stamps, distances, odometry, pixels and features (their CRCs).
  EXPECT_EQ(read_json(built / "manifest.json").at("key_images"),
            read_json(dir_ / "taught" / "manifest.json").at("key_images"));
  for (const char* file : {"mosaic.json", "ceiling_tour.json"}) {
    EXPECT_EQ(test::AppProcess::slurp(built / file),
              test::AppProcess::slurp(dir_ / "taught" / file))
        << file << " differs from the live teach's";
  }
  std::printf("[measured] %zu relay images, %zu landmarks, rebuilt byte for byte\n",
              offline.key_images.size(),
              core::ceiling::load_mosaic(built / "mosaic.json").landmarks.size());
  {
    test::AppProcess info({"map", "info", "--full", built.string()}, dir_, "info_built");
    ASSERT_EQ(info.wait(), 0) << info.both();
    EXPECT_TRUE(contains(info.out(), "mode: ceiling")) << info.out();
  }
  // Built again over it: replaced (one atomic rename: no temporary folder left beside it).
  ASSERT_EQ(build(dir_ / "rec", built, {}, "build_again", &both), 0) << both;
  EXPECT_EQ(test::AppProcess::slurp(built / "mosaic.json"),
            test::AppProcess::slurp(dir_ / "taught" / "mosaic.json"));
  for (const auto& e : fs::directory_iterator(dir_)) {
    EXPECT_NE(e.path().filename().string().rfind("built.", 0), 0u) << e.path();
  }

  // The forward options of map build make no ceiling map: refused, nothing written.
  const std::vector<std::vector<std::string>> forward_options = {{"--mode", "forward"},
                                                                 {"--every-frame-key"}};
  for (const auto& extra : forward_options) {
    const fs::path refused = dir_ / "refused";
    ASSERT_EQ(build(dir_ / "rec", refused, extra, "build_refused", &both), 2) << both;
    EXPECT_FALSE(fs::exists(refused)) << both;
    EXPECT_TRUE(contains(both, extra.size() == 2 ? "taught in ceiling mode" : "forward maps"))
        << both;
  }
}

// Re-teach offline with another parameter: a corrected ceiling height rescales the mosaic, and
// the height check (against the same odometry) says the 2.6 m is wrong.
TEST_F(CeilingMapBuildE2E, AnotherCeilingHeightRebuildsUnderIt) {
  const fs::path built = dir_ / "built_2.6";
  std::string both, out;
  ASSERT_EQ(build(dir_ / "rec", built, {"--set", "robot.ceiling_height_m=2.6"}, "build_2.6",
                  &both, &out),
            0)
      << both;
  const auto taught = core::ceiling::load_ceiling_tour(dir_ / "taught" / "ceiling_tour.json");
  const auto tour = core::ceiling::load_ceiling_tour(built / "ceiling_tour.json");
  ASSERT_TRUE(tour.ceiling && taught.ceiling);
  EXPECT_DOUBLE_EQ(tour.ceiling->height_m, 2.6);
  // The camera stays where it was: 0.2 m nearer the ceiling.
  EXPECT_NEAR(tour.ceiling->above_camera_m, taught.ceiling->above_camera_m - 0.2, 1e-9);
  EXPECT_TRUE(contains(out, "warning: ceiling height: the odometry measures")) << both;
}

// Recordings made before they recorded their mode (format version 1): forward unless told; in
// ceiling mode the ceiling's height must be given, and then Pepper's head geometry is used.
TEST_F(CeilingMapBuildE2E, OldRecordingsNeedTheModeAndTheCeilingHeight) {
  const fs::path old = edited_recording("rec_v1", [](json& m) {
    m["version"] = 1;
    for (const char* key : {"mode", "head_pitch_rad", "ceiling"}) m.erase(key);
  });
  std::string both, out;
  ASSERT_EQ(build(old, dir_ / "old_forward", {}, "build_v1", &both), 0) << both;
  EXPECT_TRUE(contains(both, "does not say which mode")) << both;
  EXPECT_EQ(core::memory::load_map(dir_ / "old_forward").mode, core::NavMode::kForward);

  ASSERT_EQ(build(old, dir_ / "old_no_height", {"--mode", "ceiling"}, "build_v1_no_h", &both), 2)
      << both;
  EXPECT_TRUE(contains(both, "robot.ceiling_height_m=")) << both;
  EXPECT_TRUE(contains(both, "recording format version 1")) << both;
  EXPECT_FALSE(fs::exists(dir_ / "old_no_height"));

  const fs::path built = dir_ / "old_ceiling";
  ASSERT_EQ(build(old, built,
                  {"--mode", "ceiling", "--set",
                   "robot.ceiling_height_m=" + std::to_string(kHallCeilingM)},
                  "build_v1_ceiling", &both),
            0)
      << both;
  EXPECT_TRUE(contains(both, "Pepper's head geometry")) << both;
  // Pepper's geometry is the simulated mount's within a millimetre: the same relay images.
  const auto live = core::ceiling::load_ceiling_tour(dir_ / "taught" / "ceiling_tour.json");
  const auto tour = core::ceiling::load_ceiling_tour(built / "ceiling_tour.json");
  ASSERT_EQ(tour.relay_images.size(), live.relay_images.size());
  for (size_t i = 0; i < tour.relay_images.size(); ++i) {
    EXPECT_EQ(tour.relay_images[i].frame, live.relay_images[i].frame) << i;
  }
}

// A forward teach's recording is refused in ceiling mode: its camera looked ahead.
TEST_F(CeilingMapBuildE2E, ForwardRecordingIsRefusedInCeilingMode) {
  const fs::path forward = edited_recording("rec_forward", [](json& m) {
    m["mode"] = "forward";
    m["head_pitch_rad"] = 0.0;
    m.erase("ceiling");
  });
  std::string both;
  ASSERT_EQ(build(forward, dir_ / "fwd_ceiling", {"--mode", "ceiling"}, "build_fwd", &both), 2)
      << both;
  EXPECT_TRUE(contains(both, "taught in forward mode")) << both;
  EXPECT_FALSE(fs::exists(dir_ / "fwd_ceiling"));
  // A manifest whose mode is neither is a damaged recording (exit 1, named).
  const fs::path bad = edited_recording("rec_bad_mode", [](json& m) { m["mode"] = "up"; });
  ASSERT_EQ(build(bad, dir_ / "bad", {}, "build_bad", &both), 1) << both;
  EXPECT_TRUE(contains(both, (bad / "recording.json").string() + ": mode \"up\"")) << both;
}

}  // namespace
}  // namespace pepper::app
