// What the replay view gets in ceiling mode (docs/teach_ui.md): the IP / IN / INN thumbnails,
// published whenever IN changes, also where a step function replaces the navigator (ceiling
// mode), whose relay images are the map's key images all the same; and plot samples that carry
// the ceiling landmarks instead of lines and points, and key-image captions without forward
// counts. In-process mock robot, the real UiServer and a WebSocket client that connects after
// the replay and reads the snapshot (every image published, latest per name, the state and the
// sample history).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "session/replay_session.hpp"
#include "session/robot_connection.hpp"
#include "session/session_link.hpp"
#include "teach_ui/ui_server.hpp"
#include "teach_ui/ui_test_client.hpp"
#include "teach_ui/wire.hpp"

namespace pepper::app {
namespace {

namespace fs = std::filesystem;
namespace nav = core::navigator;

const std::string kWorld = std::string("mock:") + PEPPER_SOURCE_DIR + "/worlds/robotics_room.yaml";

struct Snapshot {
  std::map<std::string, size_t> image_bytes;  ///< name -> payload size
  std::vector<nlohmann::json> samples;
  nlohmann::json key_images;  ///< the state's teach.key_images (the strip's captions)
};

/// A late client's snapshot; stops at the frame (the snapshot's last part) or when nothing more
/// comes.
Snapshot read_snapshot(std::uint16_t port) {
  teach_ui::testing::WsClient client(port);
  Snapshot snap;
  for (;;) {
    const auto m = client.read(std::chrono::seconds(5));
    if (!m) break;
    if (!m->binary) {
      const nlohmann::json j = nlohmann::json::parse(m->data);
      if (j.value("type", "") == "samples") {
        for (const auto& s : j.at("samples")) snap.samples.push_back(s);
      }
      if (j.value("type", "") == "state" && j.at("state").contains("teach")) {
        snap.key_images = j.at("state").at("teach").value("key_images", nlohmann::json());
      }
      continue;
    }
    const auto v = teach_ui::decode_binary_message(m->data);
    if (!v) continue;
    if (v->kind == teach_ui::kBinaryFrame) break;
    if (v->kind == teach_ui::kBinaryImage) {
      snap.image_bytes[nlohmann::json::parse(v->header_json).at("name").get<std::string>()] =
          v->payload.size();
    }
  }
  return snap;
}

/// Six frames of a replay whose step (as ceiling mode's: the navigator is replaced) is on relay
/// images 1 -> 2 -> 3 of a four-image map, with `ceiling_telemetry` when given; the UI's
/// snapshot after it.
Snapshot replay_with_a_step_function(std::function<nlohmann::json()> ceiling_telemetry) {
  const fs::path web = fs::temp_directory_path() / "pepper_replay_ui_images_web";
  fs::remove_all(web);
  fs::create_directories(web);
  std::ofstream(web / "index.html") << "<!doctype html><title>replay</title>";
  teach_ui::UiOptions ui_options;
  ui_options.web_root = web.string();
  teach_ui::UiServer ui(ui_options);
  ui.start();

  RobotConnection robot = open_robot(kWorld, {});
  core::memory::VisualMemory map;
  map.camera = robot.mock->intrinsics(320, 240);
  map.key_images.resize(4);
  for (size_t i = 0; i < map.key_images.size(); ++i) {
    map.key_images[i].features.gray = cv::Mat(240, 320, CV_8UC1, cv::Scalar(40 + 50 * i));
  }
  ReplaySessionOptions options;
  options.camera.width_px = 320;
  options.camera.height_px = 240;
  options.frame_timeout_ms = 200;
  options.max_frames = 6;
  options.ceiling_telemetry = std::move(ceiling_telemetry);
  SessionLink link(&ui, nullptr);
  const ReplayResult r = run_replay_session(robot, map, options, link, [](const core::Frame& f) {
    nav::StepResult s;
    s.command = {0.1, 0.0, false, nav::StopReason::kNone};
    s.telemetry.t_ns = f.t_ns;
    s.telemetry.state = nav::NavState::kNavigating;
    s.telemetry.ip = 1;
    s.telemetry.in = 2;
    s.telemetry.inn = 3;
    s.telemetry.n_lines_next = 5;
    s.telemetry.n_points_next = 9;
    return s;
  });
  EXPECT_EQ(r.outcome, "max_frames");
  Snapshot snap = read_snapshot(ui.port());
  ui.stop();
  fs::remove_all(web);
  return snap;
}

TEST(ReplayUiImages, TheSegmentsKeyImagesAreShownWhenAStepFunctionDrives) {
  const Snapshot snap = replay_with_a_step_function({});
  for (const char* name : {"ip", "in", "inn", "key/0", "key/3"}) {
    ASSERT_TRUE(snap.image_bytes.count(name)) << name << " was not published";
    EXPECT_GT(snap.image_bytes.at(name), 0u) << name << " is empty";
  }
  ASSERT_FALSE(snap.samples.empty());
  EXPECT_EQ(snap.samples.back().value("n_points", -1), 9);
  EXPECT_FALSE(snap.samples.back().contains("ceiling_inliers"));
  ASSERT_EQ(snap.key_images.size(), 4u);
  EXPECT_TRUE(snap.key_images[0].contains("n_lines")) << snap.key_images.dump();
}

TEST(ReplayUiImages, CeilingModeSamplesCarryTheLandmarksNotLinesAndPoints) {
  const Snapshot snap =
      replay_with_a_step_function([] { return nlohmann::json{{"inliers", 17}, {"matches", 20}}; });
  ASSERT_FALSE(snap.samples.empty());
  for (const nlohmann::json& s : snap.samples) {
    EXPECT_EQ(s.value("ceiling_inliers", -1), 17) << s.dump();
    EXPECT_FALSE(s.contains("n_lines")) << s.dump();
    EXPECT_FALSE(s.contains("n_points")) << s.dump();
  }
  // The strip's captions carry no forward counts either.
  ASSERT_EQ(snap.key_images.size(), 4u);
  for (const nlohmann::json& k : snap.key_images) {
    EXPECT_FALSE(k.contains("n_lines")) << k.dump();
    EXPECT_FALSE(k.contains("n_points")) << k.dump();
  }
}

}  // namespace
}  // namespace pepper::app
