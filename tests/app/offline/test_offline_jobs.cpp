// map build and replay-log over a recording made by driving the mock robot along the first
// metres of a shipped world's tour (QVGA to keep it quick).
#include "offline/offline_jobs.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "naoqi_bridge/mock_bridge.hpp"
#include "sim/mock_robot.hpp"
#include "sim/teach_driver.hpp"
#include "support/temp_dir.hpp"

namespace pepper::app {
namespace {

/// Ground-truth path length of the recorded drive, m (set by record_teach).
double g_recorded_path_m = 0.0;

/// Records `frames` frames of the teach drive of `world_file` into `folder`, each with the
/// command in force while the base moved to it (the recording format's convention).
void record_teach(const std::filesystem::path& world_file, const std::filesystem::path& folder,
                  int frames) {
  auto world = std::make_shared<const sim::World>(sim::load_world(world_file));
  sim::MockRobot robot(world);
  naoqi_bridge::MockBridge bridge(robot);
  bridge.connect();
  const core::CameraIntrinsics camera = bridge.start_camera({0, 320, 240, 15});
  sim::TeachDriver driver(world->scenario);
  RecordingWriter writer(folder, camera, "mock:" + world_file.string());
  naoqi_bridge::BaseVelocity in_force{};
  std::optional<sim::Pose2D> last;
  for (int i = 0; i < frames; ++i) {
    auto frame = bridge.next_frame(std::chrono::milliseconds(1000));
    ASSERT_TRUE(frame.has_value());
    const auto truth = robot.ground_truth();
    if (last) g_recorded_path_m += std::hypot(truth.base.x_m - last->x_m, truth.base.y_m - last->y_m);
    last = truth.base;
    writer.append(*frame, in_force.v_x_m_s, in_force.omega_rad_s);
    in_force = driver.command(truth.base, static_cast<double>(frame->t_ns) * 1e-9);
    bridge.move(in_force);
  }
  bridge.stop();
}

class OfflineJobsData : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tmp_ = new test::TempDir("offline-jobs");
    record_teach(std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds/robotics_room.yaml",
                 tmp_->path() / "rec", 150);  // 10 s at 15 fps: ~2 m of the loop
  }
  static void TearDownTestSuite() { delete tmp_; }
  static test::TempDir* tmp_;
};
test::TempDir* OfflineJobsData::tmp_ = nullptr;

TEST_F(OfflineJobsData, MapBuildThenReplayLogOfTheSameFramesReachesTheEnd) {
  const Recording rec = read_recording(tmp_->path() / "rec", std::nullopt);
  ASSERT_EQ(rec.frames.size(), 150u);
  std::size_t last_progress = 0;
  // Default teach options (relative threshold): the same frames replayed must reach the end.
  core::mapping::TeachOptions teach;
  const auto map = build_map_from_recording(rec, teach, false, "{}",
                                            [&](std::size_t done, std::size_t) { last_progress = done; });
  EXPECT_EQ(last_progress, 150u);
  ASSERT_GE(map.key_images.size(), 2u);
  EXPECT_EQ(map.key_images.front().source_frame_index, 0);
  EXPECT_EQ(map.key_images.back().source_frame_index, 149);  // the last image is always stored
  EXPECT_LT(map.key_images.size(), 150u);                      // but not every frame
  // The distance driven, from the recorded commands: 0 at the start, the drive's length at the
  // end (the base lags its commands by the acceleration limit and the command latency).
  EXPECT_EQ(map.key_images.front().travelled_m, 0.0);
  EXPECT_GT(g_recorded_path_m, 1.5);
  EXPECT_NEAR(map.key_images.back().travelled_m, g_recorded_path_m, 0.05 * g_recorded_path_m);

  core::memory::save_map(map, tmp_->path() / "map");
  auto loaded = core::memory::load_map(tmp_->path() / "map");
  const ReplayLogResult result = replay_log(rec, std::move(loaded), {});
  ASSERT_EQ(result.frames.size(), 150u);
  // Replaying the taught frames themselves: the navigator must walk the key images in order
  // and recognise the final image.
  int previous_in = -1;
  for (const auto& f : result.frames) {
    if (f.telemetry.in >= 0) {
      EXPECT_GE(f.telemetry.in, previous_in) << "IN went backwards at frame " << f.frame_index;
      previous_in = f.telemetry.in;
    }
  }
  EXPECT_EQ(result.max_key_image_reached, static_cast<int>(map.key_images.size()) - 1);
  EXPECT_TRUE(result.reached_end);
  EXPECT_TRUE(result.frames.back().command.stop);
  const auto json = result.to_json();
  EXPECT_EQ(json["summary"]["frames"], 150);
  EXPECT_EQ(json["frames"].size(), 150u);
}

// Issue 30: the map decides the size, and only what cannot be matched is refused. The same
// drive at twice the size (each QVGA frame's pixels doubled: area averaging gives them back
// exactly) replays against the QVGA map as the QVGA frames do; 1.5 times the size is refused.
TEST_F(OfflineJobsData, ReplayLogScalesAWholeMultipleOfTheMapsSizeAndRefusesOthers) {
  const Recording rec = read_recording(tmp_->path() / "rec", std::nullopt);
  const auto map = build_map_from_recording(rec, {}, false, "{}", {});
  auto rescaled = [&](const std::string& name, double factor) {
    const auto folder = tmp_->path() / name;
    {
      RecordingWriter writer(folder, rec.camera.scaled_to(static_cast<int>(320 * factor),
                                                          static_cast<int>(240 * factor)),
                             "test");
      for (std::size_t i = 0; i < rec.frames.size(); ++i) {
        core::Frame f = load_frame(rec, i);
        cv::Mat big;
        cv::resize(f.gray, big, cv::Size(), factor, factor, cv::INTER_NEAREST);
        f.gray = big;
        writer.append(f, rec.frames[i].v_m_s, rec.frames[i].omega_rad_s);
      }
    }
    return read_recording(folder, std::nullopt);
  };
  const ReplayLogResult same = replay_log(rec, map, {});
  const ReplayLogResult vga = replay_log(rescaled("rec_vga", 2.0), map, {});
  EXPECT_EQ(same.downscale, 1);
  EXPECT_EQ(vga.downscale, 2);
  ASSERT_EQ(vga.frames.size(), same.frames.size());
  EXPECT_TRUE(vga.reached_end);
  for (std::size_t i = 0; i < vga.frames.size(); ++i) {
    EXPECT_EQ(vga.frames[i].command.omega_rad_s, same.frames[i].command.omega_rad_s) << i;
  }
  try {
    (void)replay_log(rescaled("rec_odd", 1.5), map, {});
    FAIL() << "480x360 frames against a 320x240 map were not refused";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("480x360"), std::string::npos) << e.what();
  }
}

TEST_F(OfflineJobsData, EveryFrameKeyTakesAllImages) {
  const Recording rec = read_recording(tmp_->path() / "rec", std::nullopt);
  Recording first_ten = rec;
  first_ten.frames.resize(10);
  const auto map = build_map_from_recording(first_ten, {}, true, "{}");
  ASSERT_EQ(map.key_images.size(), 10u);
  EXPECT_GT(map.key_images[3].features.lines.size(), 0u);
  EXPECT_GT(map.key_images[9].travelled_m, map.key_images[1].travelled_m);
  // A plain image folder has no commands: its map has no distances (not zeros).
  Recording plain = first_ten;
  plain.commands_known = false;
  const auto plain_map = build_map_from_recording(plain, {}, true, "{}");
  EXPECT_TRUE(std::isnan(plain_map.key_images[9].travelled_m));
}

// map build's mode (issue 24): --mode, else the recording's, else forward; the other mode than
// the recording's is refused naming it.
TEST(CeilingMapBuild, ModeComesFromTheRecordingAndAContradictionIsRefused) {
  using core::NavMode;
  Recording unknown;
  unknown.folder = "rec";
  EXPECT_EQ(map_build_mode(unknown, std::nullopt), NavMode::kForward);
  EXPECT_EQ(map_build_mode(unknown, NavMode::kCeiling), NavMode::kCeiling);
  Recording ceiling = unknown;
  ceiling.setup = RecordingSetup{NavMode::kCeiling, -0.7, RecordedCeiling{2.8, 1.6, 0.0, 0.0}};
  EXPECT_EQ(map_build_mode(ceiling, std::nullopt), NavMode::kCeiling);
  EXPECT_EQ(map_build_mode(ceiling, NavMode::kCeiling), NavMode::kCeiling);
  EXPECT_THROW(map_build_mode(ceiling, NavMode::kForward), std::invalid_argument);
  Recording forward = unknown;
  forward.setup = RecordingSetup{NavMode::kForward, 0.0, std::nullopt};
  EXPECT_EQ(map_build_mode(forward, std::nullopt), NavMode::kForward);
  try {
    map_build_mode(forward, NavMode::kCeiling);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("rec was taught in forward mode"), std::string::npos)
        << e.what();
  }
}

// The camera geometry of a ceiling rebuild: the recorded one exactly (the live teach's canonical
// view), a corrected height with the camera where it was, or for recordings that do not say,
// Pepper's head geometry under the height the operator gives (else a clear refusal).
TEST(CeilingMapBuild, SetupIsTheRecordedOneOrNeedsTheCeilingHeight) {
  const auto camera = core::CameraIntrinsics::pepper_top_vga().scaled_to(320, 240);
  const CeilingCameraSetup live = ceiling_camera_of_pepper(2.7, camera, -0.65);
  Recording rec;
  rec.folder = "rec";
  rec.version = 2;
  rec.setup = RecordingSetup{core::NavMode::kCeiling, -0.65, to_recorded(live)};
  const CeilingCameraSetup same = ceiling_setup_for_build(rec, camera, {});
  EXPECT_EQ(same.camera.ceiling_above_cam_m, live.camera.ceiling_above_cam_m);  // bit for bit
  EXPECT_EQ(same.camera.head_pitch_rad, -0.65);
  EXPECT_EQ(same.cam_in_base_m, live.cam_in_base_m);
  EXPECT_EQ(same.ceiling_height_m, 2.7);
  CeilingBuildInputs corrected;
  corrected.ceiling_height_m = 2.5;
  const CeilingCameraSetup lower = ceiling_setup_for_build(rec, camera, corrected);
  EXPECT_NEAR(lower.camera.ceiling_above_cam_m, live.camera.ceiling_above_cam_m - 0.2, 1e-12);
  EXPECT_EQ(lower.cam_in_base_m, live.cam_in_base_m);
  corrected.ceiling_height_m = 0.5;  // under the camera
  EXPECT_THROW(ceiling_setup_for_build(rec, camera, corrected), std::invalid_argument);

  Recording old;
  old.folder = "old_rec";
  old.version = 1;
  try {
    ceiling_setup_for_build(old, camera, {});
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("old_rec: this recording does not say how high the ceiling was"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("--set robot.ceiling_height_m="), std::string::npos) << what;
  }
  CeilingBuildInputs given;
  given.ceiling_height_m = 2.7;
  given.head_pitch_rad = -0.65;
  const CeilingCameraSetup pepper = ceiling_setup_for_build(old, camera, given);
  EXPECT_EQ(pepper.camera.ceiling_above_cam_m, live.camera.ceiling_above_cam_m);
  // A real robot's teach recorded its configuration: its height and head pitch are taken.
  old.config = {{"robot", {{"ceiling_height_m", 2.7}, {"ceiling_head_pitch_rad", -0.65}}}};
  const CeilingCameraSetup from_config = ceiling_setup_for_build(old, camera, {});
  EXPECT_EQ(from_config.camera.ceiling_above_cam_m, live.camera.ceiling_above_cam_m);
  EXPECT_EQ(from_config.camera.head_pitch_rad, -0.65);
}

}  // namespace
}  // namespace pepper::app
