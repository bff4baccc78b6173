// The ceiling height checked at teach against the wheel odometry (issue 24;
// core/ceiling/height_check.hpp; docs/method/ceiling.md "Checking the ceiling height at teach").
// `pepper_app teach --mode ceiling` of worlds/robotics_room.yaml (QVGA, scripted, the world's
// ceiling: the right height) emits a `ceiling_height_check` event, stores the check in
// ceiling_tour.json and does not warn. Then the teach's own recording (its frames and the
// simulator's wheel odometry) is taught again through the same CeilingTeacher with the camera
// geometry a real Pepper gets from a configured robot.ceiling_height_m (ceiling_camera_of_pepper)
// at wrong heights: each estimate must find the world's ceiling, and `map info` of such a map
// warns with the measured height. One test: the teach and the three re-teaches take ~30 s.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "app/e2e/app_process.hpp"
#include "config/app_config.hpp"
#include "core/ceiling/ceiling_tour.hpp"
#include "core/ceiling/height_check.hpp"
#include "session/ceiling_map.hpp"
#include "session/ceiling_teach.hpp"
#include "session/recording.hpp"
#include "session/session_cli.hpp"

namespace pepper::app {
namespace {

namespace fs = std::filesystem;
namespace cc = core::ceiling;

const std::string kRoom = std::string(PEPPER_SOURCE_DIR) + "/worlds/robotics_room.yaml";
constexpr double kWorldCeilingM = 2.7;  // worlds/robotics_room.yaml ceiling.height_m

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Bounds (measured: printed below and in docs/method/ceiling.md): the estimate of the height
// above the floor was 2.719 m with the right height and within 2.719-2.722 m at the wrong ones.
// What biases it: the simulator's wheel odometry reads distances 1.5 % long (the estimate of the
// height above the camera 1.5 % high, 2.3 cm) and the chain's own scale. Bound: 5 cm (2 % of the
// height above the floor, 3.3 % above the camera), under the check's 5 % verdict threshold.
constexpr double kEstimateBoundM = 0.05;

TEST(CeilingHeightCheckE2E, TheTeachChecksTheHeightAndFindsTheWorldsCeilingUnderWrongOnes) {
  const fs::path dir =
      fs::temp_directory_path() / ("pepper_e2e_ceiling_height_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path map_dir = dir / "room";
  const fs::path recording_dir = dir / "room.recording";
  const fs::path events = dir / "events.jsonl";

  test::AppProcess teach(
      {"teach", "--mode", "ceiling", "--robot", "mock:" + kRoom, "--map", map_dir.string(),
       "--recording", recording_dir.string(), "--scripted", "--events", events.string(), "--set",
       "robot.camera_width_px=320", "--set", "robot.camera_height_px=240"},
      dir, "teach");
  ASSERT_EQ(teach.wait(), 0) << teach.both();
  EXPECT_FALSE(contains(teach.both(), "ceiling height:")) << teach.both();

  // The event.
  std::optional<nlohmann::json> check_event;
  {
    std::ifstream in(events);
    for (std::string line; std::getline(in, line);) {
      const nlohmann::json j = nlohmann::json::parse(line);
      if (j.value("event", "") == "ceiling_height_check") check_event = j;
    }
  }
  ASSERT_TRUE(check_event.has_value()) << "no ceiling_height_check event";
  const nlohmann::json& ev = *check_event;
  EXPECT_EQ(ev.at("status"), "estimated") << ev.dump();
  EXPECT_EQ(ev.at("configured_height_m").get<double>(), kWorldCeilingM);
  EXPECT_NEAR(ev.at("estimated_height_m").get<double>(), kWorldCeilingM, kEstimateBoundM);
  EXPECT_FALSE(ev.at("disagrees").get<bool>());
  EXPECT_GE(ev.at("windows").get<int>(), 10) << "15.6 m of tour in 0.75 m windows";

  // The tour file keeps it; map info does not warn.
  const cc::CeilingTour tour = cc::load_ceiling_tour(map_dir / kCeilingTourFileName);
  ASSERT_TRUE(tour.height_check.has_value());
  EXPECT_EQ(tour.height_check->estimated_height_m, ev.at("estimated_height_m").get<double>());
  {
    test::AppProcess info({"map", "info", map_dir.string()}, dir, "info");
    ASSERT_EQ(info.wait(), 0) << info.both();
    EXPECT_FALSE(contains(info.out(), "ceiling height:")) << info.out();
  }
  std::printf(
      "height check, configured %.2f m (the world's): estimated %.3f +- %.3f m, s %.4f "
      "(spread %.4f), windows %d (rejected %d, turning %d) over %.2f m\n",
      kWorldCeilingM, tour.height_check->estimated_height_m, tour.height_check->estimated_sigma_m,
      tour.height_check->scale_ratio, tour.height_check->scale_ratio_spread,
      tour.height_check->windows, tour.height_check->windows_rejected,
      tour.height_check->windows_turning, tour.height_check->odometry_m);

  // The same frames and odometry taught under heights an operator mis-measured: the camera
  // geometry of a real Pepper with robot.ceiling_height_m set (within 1 mm of the mock's,
  // SessionMode.APeppersCeilingCameraIsTheSimulatedOnes).
  const Recording rec = read_recording(recording_dir, std::nullopt);
  const double pitch_rad = head_request(AppConfig{}, core::NavMode::kCeiling).head_pitch_rad;
  ASSERT_EQ(static_cast<int64_t>(rec.frames.size()), tour.frames);
  for (const double configured_m : {2.5, 2.6, 2.9}) {
    SCOPED_TRACE(configured_m);
    CeilingTeacher teacher(ceiling_camera_of_pepper(configured_m, rec.camera, pitch_rad),
                           rec.camera, core::features::FeatureExtractorOptions{});
    for (size_t i = 0; i < rec.frames.size(); ++i) teacher.add_frame(load_frame(rec, i));
    const CeilingMap cm = teacher.finish();
    ASSERT_TRUE(cm.tour.height_check.has_value());
    const cc::HeightCheck& h = *cm.tour.height_check;
    std::printf(
        "height check, configured %.2f m: estimated %.3f +- %.3f m, s %.4f (spread "
        "%.4f), windows %d (rejected %d, turning %d), disagrees %d\n",
        configured_m, h.estimated_height_m, h.estimated_sigma_m, h.scale_ratio,
        h.scale_ratio_spread, h.windows, h.windows_rejected, h.windows_turning,
        h.disagrees ? 1 : 0);
    ASSERT_TRUE(h.estimated());
    EXPECT_NEAR(h.estimated_height_m, kWorldCeilingM, kEstimateBoundM);
    // 2.6 m is 6.5 % low above the camera (1.43 against 1.53 m), the others 13 %: all warn.
    EXPECT_TRUE(h.disagrees);
    const std::optional<std::string> warning = ceiling_height_warning(h);
    ASSERT_TRUE(warning.has_value());
    EXPECT_TRUE(contains(*warning, "robot.ceiling_height_m=")) << *warning;
    EXPECT_TRUE(contains(*warning, configured_m > kWorldCeilingM ? "too long" : "too short"))
        << *warning;
    if (configured_m == 2.9) {  // map info of such a map says it too
      std::printf("warning: %s\n", warning->c_str());
      const fs::path wrong_dir = dir / "room_2.9";
      save_ceiling_map(cm, wrong_dir);
      test::AppProcess info({"map", "info", wrong_dir.string()}, dir, "info_wrong");
      ASSERT_EQ(info.wait(), 0) << info.both();
      EXPECT_TRUE(contains(info.out(), "warning: ceiling height: the odometry measures"))
          << info.out();
      EXPECT_TRUE(contains(info.out(), "not the configured 2.90 m")) << info.out();
    }
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pepper::app
