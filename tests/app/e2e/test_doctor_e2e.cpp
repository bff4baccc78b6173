// `pepper_app doctor` against `pepper_app mock-robot` over real sockets on 127.0.0.1 (issue 30
// item 7): the mock robot is asleep, on low battery and in Autonomous Life, and doctor says so,
// says what to do and exits 1; a ready robot passes; a robot without some services gets warnings
// naming them, not a crash. Both programs run as subprocesses, as an operator runs them. The
// mock's simulation options also drive a replay's supervision end to end: a move failure is
// printed as a robot_warning event, a head Autonomous Life keeps ends the replay.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "app/e2e/app_process.hpp"

namespace pepper::app {
namespace {

namespace fs = std::filesystem;


fs::path fresh_dir(const std::string& name) {
  auto p = fs::temp_directory_path() / ("pepper_doctor_e2e_" + name);
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}




/// The doctor line of a check ("" when absent).
std::string line_of(const std::string& out, const std::string& check) {
  std::istringstream in(out);
  std::string line;
  while (std::getline(in, line)) {
    if (line.size() > 6 && line.compare(6, check.size(), check) == 0 &&
        (line.size() == 6 + check.size() || line[6 + check.size()] == ' ')) {
      return line;
    }
  }
  return "";
}

bool has(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

struct DoctorRun {
  int code = -1;
  std::string out;
  std::string all;
};

DoctorRun run_doctor_against(const std::vector<std::string>& mock_options,
                             const std::string& name,
                             const std::vector<std::string>& doctor_options = {}) {
  const fs::path dir = fresh_dir(name);
  std::vector<std::string> args = {"mock-robot", "--listen", "tcp://127.0.0.1:0"};
  args.insert(args.end(), mock_options.begin(), mock_options.end());
  test::AppProcess mock(args, dir, "mock");
  const std::string url = test::mock_robot_url(mock);
  DoctorRun r;
  if (url.empty()) {
    r.all = mock.both();
    return r;
  }
  test::AppProcess doctor(
      test::cat({"doctor", "--robot", url, "--camera-seconds", "0.5"}, doctor_options), dir,
      "doctor");
  r.code = doctor.wait(std::chrono::seconds(60));
  r.out = doctor.out();
  r.all = doctor.both() + "\nmock:\n" + mock.both();
  mock.signal(SIGINT);
  mock.wait(std::chrono::seconds(10));
  return r;
}

}  // namespace

TEST(DoctorE2E, AsleepLowBatteryAutonomousLifeRobotIsReportedWithWhatToDo) {
  const DoctorRun r =
      run_doctor_against({"--asleep", "--battery", "12", "--autonomous-life", "solitary"}, "bad");
  ASSERT_FALSE(r.out.empty()) << r.all;
  EXPECT_EQ(r.code, 1) << r.all;  // the battery fails the run
  const std::string battery = line_of(r.out, "battery");
  EXPECT_EQ(battery.rfind("FAIL", 0), 0u) << battery;
  EXPECT_TRUE(has(battery, "12 %")) << battery;
  EXPECT_TRUE(has(battery, "-> charge")) << battery;
  const std::string wake = line_of(r.out, "wake state");
  EXPECT_EQ(wake.rfind("WARN", 0), 0u) << wake;
  EXPECT_TRUE(has(wake, "resting")) << wake;
  EXPECT_TRUE(has(wake, "-> ")) << wake;
  const std::string life = line_of(r.out, "autonomous life");
  EXPECT_EQ(life.rfind("WARN", 0), 0u) << life;
  EXPECT_TRUE(has(life, "'solitary'")) << life;
  EXPECT_TRUE(has(life, "-> ") && has(life, "disabled")) << life;
  // The rest of the robot is fine, and each check still has its one line.
  for (const char* ok : {"naoqi version", "charger", "collision protection", "odometry", "camera",
                         "head lock", "base"}) {
    EXPECT_EQ(line_of(r.out, ok).rfind("OK", 0), 0u) << ok << "\n" << r.out;
  }
  EXPECT_TRUE(has(line_of(r.out, "naoqi version"), "2.5.10.7")) << r.out;
  EXPECT_TRUE(has(r.out, "1 check(s) failed")) << r.out;
}

TEST(DoctorE2E, AReadyRobotPassesAndOptionsChangeWhatIsReported) {
  const DoctorRun ready = run_doctor_against({"--autonomous-life", "disabled"}, "ready");
  EXPECT_EQ(ready.code, 0) << ready.all;
  for (const char* ok : {"naoqi version", "battery", "charger", "wake state", "autonomous life",
                         "collision protection", "odometry"}) {
    EXPECT_EQ(line_of(ready.out, ok).rfind("OK", 0), 0u) << ok << "\n" << ready.out;
  }
  EXPECT_TRUE(has(ready.out, "all checks passed")) << ready.out;
  // Charging, collision protection off, another NAOqi: each line says so.
  const DoctorRun other = run_doctor_against(
      {"--autonomous-life", "disabled", "--charging", "--no-collision-protection",
       "--naoqi-version", "2.1.4.13", "--battery", "35"},
      "other");
  EXPECT_EQ(other.code, 1) << other.all;
  EXPECT_EQ(line_of(other.out, "charger").rfind("FAIL", 0), 0u) << other.out;
  EXPECT_TRUE(has(line_of(other.out, "charger"), "power hatch")) << other.out;
  EXPECT_EQ(line_of(other.out, "collision protection").rfind("WARN", 0), 0u) << other.out;
  EXPECT_EQ(line_of(other.out, "naoqi version").rfind("WARN", 0), 0u) << other.out;
  EXPECT_TRUE(has(line_of(other.out, "naoqi version"), "2.1.4.13")) << other.out;
  EXPECT_EQ(line_of(other.out, "battery").rfind("WARN", 0), 0u) << other.out;
}

// Issue 30, "the map decides the camera size": with --map, doctor checks the camera at the size
// the map was taught at (as its replay will subscribe), and says so; without, at VGA.
TEST(DoctorE2E, WithAMapTheCameraIsCheckedAtTheMapsSize) {
  const fs::path dir = fresh_dir("map");
  test::AppProcess teach({"teach", "--robot",
                          "mock:" + std::string(PEPPER_SOURCE_DIR) + "/worlds/robotics_room.yaml",
                          "--map", (dir / "qvga").string(), "--max-distance", "0.5", "--set",
                          "robot.camera_width_px=320", "--set", "robot.camera_height_px=240"},
                         dir, "teach");
  ASSERT_EQ(teach.wait(), 0) << teach.both();
  const DoctorRun with_map =
      run_doctor_against({"--autonomous-life", "disabled"}, "with_map", {"--map", (dir / "qvga").string()});
  const std::string camera = line_of(with_map.out, "camera");
  EXPECT_EQ(camera.rfind("OK", 0), 0u) << with_map.all;
  EXPECT_TRUE(has(camera, "320x240 grey")) << camera;
  EXPECT_TRUE(has(camera, "the size " + (dir / "qvga").string() + " was taught at")) << camera;
  const DoctorRun without = run_doctor_against({"--autonomous-life", "disabled"}, "without_map");
  EXPECT_TRUE(has(line_of(without.out, "camera"), "640x480 grey")) << without.all;
}

TEST(DoctorE2E, MissingServicesGiveWarningsNamingThem) {
  const DoctorRun r = run_doctor_against(
      {"--autonomous-life", "disabled", "--without-service", "ALBattery", "--without-service",
       "ALMemory", "--without-service", "ALSystem", "--without-service", "ALBasicAwareness"},
      "missing");
  ASSERT_FALSE(r.out.empty()) << r.all;
  EXPECT_EQ(r.code, 0) << r.all;  // nothing the session needs is missing
  EXPECT_EQ(line_of(r.out, "battery").rfind("WARN", 0), 0u) << r.out;
  EXPECT_TRUE(has(line_of(r.out, "battery"), "ALBattery")) << r.out;
  EXPECT_TRUE(has(line_of(r.out, "charger"), "ALMemory")) << r.out;
  EXPECT_EQ(line_of(r.out, "service ALBasicAwareness").rfind("WARN", 0), 0u) << r.out;
  // The version falls back to ALMotion.version when ALSystem is missing.
  EXPECT_TRUE(has(line_of(r.out, "naoqi version"), "ALMotion.version")) << r.out;
  // A required service missing fails, still without a crash.
  const DoctorRun no_motion = run_doctor_against({"--without-service", "ALMotion"}, "no_motion");
  EXPECT_EQ(no_motion.code, 1) << no_motion.all;
  EXPECT_EQ(line_of(no_motion.out, "service ALMotion").rfind("FAIL", 0), 0u) << no_motion.out;
  EXPECT_TRUE(has(no_motion.out, "check(s) failed")) << no_motion.all;
}

namespace {

const std::string kWorldFile = std::string(PEPPER_SOURCE_DIR) + "/worlds/robotics_room.yaml";
const std::vector<std::string> kQvga = {"--set", "robot.camera_width_px=320", "--set",
                                        "robot.camera_height_px=240"};


}  // namespace

TEST(DoctorE2E, MockRobotSimulationOptionsReachTheReplaysSupervision) {
  const fs::path dir = fresh_dir("supervision");
  test::AppProcess teach(test::cat({"teach", "--robot", "mock:" + kWorldFile, "--map", (dir / "map").string(),
                  "--max-distance", "2.0"},
                 kQvga),
             dir, "teach");
  ASSERT_EQ(teach.wait(std::chrono::seconds(120)), 0) << teach.both();

  // 1. The robot stops executing moves 4 s after start-up (an obstacle): warned, not stopped.
  {
    test::AppProcess mock({"mock-robot", "--listen", "tcp://127.0.0.1:0", "--world", kWorldFile, "--fail-moves",
               "Safety: obstacle (e2e)", "--fail-moves-after-s", "4"},
              dir, "mock_fail");
    const std::string url = test::mock_robot_url(mock);
    ASSERT_FALSE(url.empty()) << mock.both();
    test::AppProcess replay(
        test::cat({"replay", "--robot", url, "--map", (dir / "map").string(), "--max-frames", "150",
                   "--events", (dir / "replay_fail_events.jsonl").string()},
            kQvga),
        dir, "replay_fail");
    replay.wait(std::chrono::seconds(90));
    // The event for programs, and the warning for the person on the console.
    const std::string events = test::AppProcess::slurp(dir / "replay_fail_events.jsonl");
    EXPECT_TRUE(has(events, "\"event\":\"robot_warning\"")) << events;
    EXPECT_TRUE(has(events, "move failed")) << events;
    EXPECT_TRUE(has(events, "Safety: obstacle (e2e)")) << events;
    const std::string console = replay.err();
    EXPECT_TRUE(has(console, "warning: robot: ")) << replay.both();
    EXPECT_TRUE(has(console, "Safety: obstacle (e2e)")) << replay.both();
    mock.signal(SIGINT);
    mock.wait(std::chrono::seconds(10));
  }
  // 2. Autonomous Life takes the head 4 s after start-up and cannot be turned off: the replay
  // ends with head_lock_lost (exit code 1) and says what to do.
  {
    test::AppProcess mock({"mock-robot", "--listen", "tcp://127.0.0.1:0", "--world", kWorldFile,
               "--take-head-after-s", "4", "--take-head-sticky"},
              dir, "mock_head");
    const std::string url = test::mock_robot_url(mock);
    ASSERT_FALSE(url.empty()) << mock.both();
    test::AppProcess replay(
        test::cat({"replay", "--robot", url, "--map", (dir / "map").string(), "--max-frames", "600"},
            kQvga),
        dir, "replay_head");
    EXPECT_EQ(replay.wait(std::chrono::seconds(90)), 1) << replay.both();
    const std::string all = replay.both();
    EXPECT_TRUE(has(all, "head_lock_lost")) << all;
    EXPECT_TRUE(has(all, "Set Autonomous Life to \"disabled\"")) << all;
    mock.signal(SIGINT);
    mock.wait(std::chrono::seconds(10));
  }
}

}  // namespace pepper::app
