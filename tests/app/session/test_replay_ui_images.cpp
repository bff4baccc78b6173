// The replay view's IP / IN / INN thumbnails (docs/teach_ui.md): the session publishes the
// segment's key images whenever IN changes, also where a step function replaces the navigator
// (ceiling mode), whose relay images are the map's key images all the same. In-process mock
// robot, the real UiServer and a WebSocket client that connects after the replay and reads the
// snapshot (every image published, latest per name).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>

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

/// Names of the images in a late client's snapshot, with their payload sizes; stops at the frame
/// (the snapshot's last part) or when nothing more comes.
std::map<std::string, size_t> snapshot_images(std::uint16_t port) {
  teach_ui::testing::WsClient client(port);
  std::map<std::string, size_t> images;
  for (;;) {
    const auto m = client.read(std::chrono::seconds(5));
    if (!m) break;
    if (!m->binary) continue;
    const auto v = teach_ui::decode_binary_message(m->data);
    if (!v) continue;
    if (v->kind == teach_ui::kBinaryFrame) break;
    if (v->kind == teach_ui::kBinaryImage) {
      images[nlohmann::json::parse(v->header_json).at("name").get<std::string>()] =
          v->payload.size();
    }
  }
  return images;
}

TEST(ReplayUiImages, TheSegmentsKeyImagesAreShownWhenAStepFunctionDrives) {
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
  SessionLink link(&ui, nullptr);
  // As ceiling mode's step: the navigator is replaced; the segment is relay images 1 -> 2 -> 3.
  const ReplayResult r = run_replay_session(robot, map, options, link, [](const core::Frame& f) {
    nav::StepResult s;
    s.command = {0.1, 0.0, false, nav::StopReason::kNone};
    s.telemetry.t_ns = f.t_ns;
    s.telemetry.state = nav::NavState::kNavigating;
    s.telemetry.ip = 1;
    s.telemetry.in = 2;
    s.telemetry.inn = 3;
    return s;
  });
  EXPECT_EQ(r.outcome, "max_frames");
  const std::map<std::string, size_t> images = snapshot_images(ui.port());
  for (const char* name : {"ip", "in", "inn", "key/0", "key/3"}) {
    ASSERT_TRUE(images.count(name)) << name << " was not published";
    EXPECT_GT(images.at(name), 0u) << name << " is empty";
  }
  ui.stop();
  fs::remove_all(web);
}

}  // namespace
}  // namespace pepper::app
