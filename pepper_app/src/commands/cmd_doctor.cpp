// `pepper_app doctor`: checks a robot the way an operator wants before a demo: reachable, logged
// in, services present, the robot's state (NAOqi version, battery and charger, awake or resting,
// Autonomous Life, external collision protection, odometry), camera streaming, head lock
// holding, base accepting commands, robot-side deadman. One line per check: OK, WARN (works, with
// something to know or do) or FAIL (fix before driving), each WARN and FAIL with what to do.
// Exit code 0 when nothing failed (warnings allowed), 1 when a check failed, 2 for bad options.
// The robot-state checks read only (they run before the head-lock check, which wakes the robot
// up and turns Autonomous Life off for its duration); their services and keys are listed in
// docs/naoqi_bridge.md with the source of each (doctor_robot_state.hpp).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

#include "commands/cli_util.hpp"
#include "commands/commands.hpp"
#include "commands/doctor_report.hpp"
#include "commands/doctor_robot_state.hpp"
#include "commands/error_advice.hpp"
#include "core/memory/visual_memory.hpp"
#include "session/known_robots.hpp"
#include "session/robot_connection.hpp"
#include "naoqi_bridge/qi/errors.hpp"
#include "naoqi_bridge/qi/qi_bridge.hpp"
#include "naoqi_bridge/qi/session.hpp"

namespace pepper::app {

namespace {

namespace qi = pepper::naoqi_bridge::qi;
namespace nb = pepper::naoqi_bridge;
using Clock = std::chrono::steady_clock;
using doctor::classify;
using doctor::fmt;
using doctor::Report;
using doctor::summarize;

struct DoctorArgs {
  std::string robot;
  std::string user;
  std::string password_file;
  std::string tls_pin;
  bool trust_new_robot = false;
  double camera_seconds = 3.0;
  int timeout_ms = 5000;
  std::string map;  ///< --map: check the camera at the size this map was taught at
};

struct ServiceCheck {
  const char* name;
  std::vector<std::pair<const char*, const char*>> methods;  // name, parameters signature
  /// Required services fail the check when missing; the others only limit what a session
  /// can do (said in `without`).
  bool required = true;
  const char* without = "";
};

int run_doctor(const DoctorArgs& a) {
  Report report;
  // The map decides the camera size (issue 30): with --map the camera is checked at the size the
  // replay of that map will subscribe at, else at the robot's full VGA. Read before connecting,
  // so that a bad map is refused before anything is asked of the robot.
  nb::CameraRequest camera_req;  // VGA grey, 15 fps
  std::string camera_size_why = "the default";
  if (!a.map.empty()) {
    try {
      const auto info = core::memory::read_map_info(a.map);
      camera_req.width_px = info.camera.width_px;
      camera_req.height_px = info.camera.height_px;
      camera_size_why = "the size " + a.map + " was taught at";
    } catch (const std::exception& e) {
      std::cerr << "pepper_app doctor: " << message_with_next_step(e) << "\n";
      return 2;
    }
  }
  qi::QiBridgeOptions o;
  o.url = a.robot;
  o.tls_pin_sha256 = a.tls_pin;
  o.connect_timeout = std::chrono::milliseconds(a.timeout_ms);
  o.call_timeout = std::chrono::milliseconds(a.timeout_ms);
  o.subscriber_name = "pepper_doctor";
  try {
    // tcps:// logs in as "nao" unless --user says otherwise (the same rule as teach and replay).
    const RobotLogin login = robot_login(a.robot.rfind("tcps://", 0) == 0, a.user,
                                         a.password_file, /*allow_prompt=*/true, a.robot);
    o.user = login.user;
    o.password = login.password;
  } catch (const std::exception& e) {
    std::cerr << "pepper_app doctor: " << e.what() << "\n";
    return 2;
  }
  const auto errors = o.validate();
  if (!errors.empty()) {
    for (const auto& e : errors) std::cerr << "pepper_app doctor: " << e << "\n";
    return 2;
  }
  if (a.robot.rfind("tcps://", 0) == 0 && a.tls_pin.empty()) {
    // Trust on first use, checked before the login: asked or accepted once here, so the
    // bridge's own connection below finds the robot known.
    TrustOptions trust;
    trust.trust_new_robot = a.trust_new_robot;
    o.verify_certificate = known_robots_verifier(trust);
  }
  const char* skipped = "not checked: no connection";

  // 1. Connection and login, and the services the bridge uses.
  qi::SessionOptions so;
  so.connect_timeout = o.connect_timeout;
  so.call_timeout = o.call_timeout;
  so.user = o.user;
  so.password = o.password;
  so.tls_pin_sha256 = o.tls_pin_sha256;
  so.verify_certificate = o.verify_certificate;
  qi::QiSession session(so);
  const std::vector<ServiceCheck> services = {
      {"ALMotion",
       {{"wakeUp", "()"},
        {"setStiffnesses", "(mm)"},
        {"setAngles", "(mmf)"},
        {"getAngles", "(mb)"},
        {"move", "(fff)"},
        {"stopMove", "()"}}},
      {"ALVideoDevice",
       {{"subscribeCamera", "(siiii)"}, {"getImageRemote", "(s)"}, {"unsubscribe", "(s)"}}},
      {"ALAutonomousLife",
       {{"getState", "()"}, {"setState", "(s)"}},
       false,
       "sessions cannot turn Autonomous Life off: make sure it is disabled on the robot"},
      {"ALBasicAwareness",
       {{"isEnabled", "()"}, {"setEnabled", "(b)"}},
       false,
       "sessions cannot turn basic awareness off: make sure the robot does not track people"},
  };
  const auto t0 = Clock::now();
  try {
    session.connect(a.robot);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    std::string msg = "connected to " + session.describe() + " in " + fmt(ms, 0) + " ms";
    if (!session.peer_certificate_sha256().empty()) {
      msg += "; TLS certificate SHA-256 " + session.peer_certificate_sha256() +
             (a.tls_pin.empty() ? " (known robot: " + default_known_robots_file().string() + ")"
                                : std::string(" (pinned)"));
    }
    report.ok("connect", msg);
  } catch (const std::exception& e) {
    report.fail("connect", classify(e),
                "check the URL, that the robot is on and on this network (ping it), and the "
                "login");
    for (const auto& s : services) report.fail(std::string("service ") + s.name, skipped);
    for (const char* c : doctor::robot_state_checks()) report.fail(c, skipped);
    for (const char* c : {"camera", "head lock", "base"}) report.fail(c, skipped);
    return summarize(report);
  }
  for (const auto& s : services) {
    const std::string check = std::string("service ") + s.name;
    try {
      const auto h = session.service(s.name);
      std::string missing;
      for (const auto& [m, sig] : s.methods) {
        if (!h.meta.find(m, sig)) missing += (missing.empty() ? "" : ", ") + std::string(m) + sig;
      }
      if (missing.empty()) {
        report.ok(check, "present (id " + std::to_string(h.id) + ", " +
                             std::to_string(h.meta.methods.size()) + " methods)");
      } else if (s.required) {
        report.fail(check, "present but lacks " + missing + " (unsupported NAOqi version?)",
                    "use a robot with NAOqi 2.5 or 2.9");
      } else {
        report.warn(check, "present but lacks " + missing, s.without);
      }
    } catch (const qi::ServiceNotFound& e) {
      if (s.required) {
        report.fail(check, classify(e), "restart NAOqi on the robot (or reboot it)");
      } else {
        report.warn(check, std::string("the robot has no ") + s.name + " service", s.without);
      }
    } catch (const std::exception& e) {
      report.fail(check, classify(e));
    }
  }
  // The robot's state, read before the head-lock check below changes it (wakeUp, Autonomous
  // Life off for the duration of the check).
  doctor::check_robot_state(session, report, std::chrono::milliseconds(a.timeout_ms));
  session.close();

  // 2. Camera, head lock and base through the bridge, as a session would use them.
  qi::QiBridge bridge(o);
  try {
    bridge.connect();
  } catch (const std::exception& e) {
    for (const char* c : {"camera", "head lock", "base"}) report.fail(c, classify(e));
    return summarize(report);
  }
  try {
    bridge.start_camera(camera_req);
    int frames = 0;
    std::int64_t first_t = -1;
    std::int64_t last_t = -1;
    int w = 0, h = 0;
    const auto start = Clock::now();
    const auto until = start + std::chrono::milliseconds(static_cast<int>(a.camera_seconds * 1000));
    while (Clock::now() < until) {
      auto f = bridge.next_frame(std::chrono::milliseconds(a.timeout_ms));
      if (!f) break;
      if (first_t < 0) first_t = f->t_ns;
      last_t = f->t_ns;
      w = f->gray.cols;
      h = f->gray.rows;
      ++frames;
    }
    const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
    const double rate = frames / std::max(wall_s, 1e-3);
    const std::string size = std::to_string(w) + "x" + std::to_string(h);
    const std::string asked =
        std::to_string(camera_req.width_px) + "x" + std::to_string(camera_req.height_px);
    const std::string detail = std::to_string(frames) + " frames in " + fmt(wall_s, 1) +
                               " s: " + fmt(rate, 1) + " fps received, " + size + " grey, " +
                               fmt(rate * w * h / 1e6, 1) + " MB/s";
    if (frames < 2) {
      report.fail("camera", "no frames streamed (" + detail + ")");
    } else if (w != camera_req.width_px || h != camera_req.height_px) {
      report.fail("camera", "unexpected frame size " + size + " (asked " + asked + ", " +
                                camera_size_why + ")");
    } else if (last_t <= first_t) {
      report.fail("camera", "robot timestamps do not advance (" + detail + ")");
    } else if (rate < 5.0) {
      report.fail("camera",
                  "too slow for navigation, < 5 fps (" + detail + "; check the WiFi link)");
    } else {
      report.ok("camera", detail + " (" + camera_size_why + ")");
    }
  } catch (const std::exception& e) {
    report.fail("camera", classify(e));
  }
  try {
    nb::HeadLockRequest req;
    const auto st = bridge.lock_head(req);
    const std::string detail = "HeadYaw " + fmt(st.head_yaw_rad, 3) + " rad, HeadPitch " +
                               fmt(st.head_pitch_rad, 3) + " rad, max error " +
                               fmt(st.max_error_rad, 3) + " rad (tolerance " +
                               fmt(req.tolerance_rad, 3) + ")";
    if (st.holding) {
      report.ok("head lock", "holds: " + detail);
    } else {
      report.fail("head lock", "does not hold: " + detail +
                                   " (is the robot awake, the hatch closed, awareness off?)");
    }
  } catch (const std::exception& e) {
    report.fail("head lock", classify(e));
  }
  try {
    const auto t = Clock::now();
    bridge.move({0.0, 0.0, 0.0});
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t).count();
    bridge.stop();
    report.ok("base",
              "zero-velocity move accepted (round trip " + fmt(ms, 2) + " ms), stopMove sent");
  } catch (const std::exception& e) {
    report.fail("base", classify(e) + " (charging hatch open? motion calls are refused then)");
  }
  // 3. The robot-side deadman: does a velocity command end by itself on this robot?
  try {
    if (bridge.robot_side_deadman()) {
      // A zero-length time-constrained move: NAOqi answers it when it ends, so the round trip
      // shows the robot runs it (not only lists it) without moving the base.
      const auto motion = bridge.session().service("ALMotion");
      const auto t = Clock::now();
      bridge.session().call(motion, "moveTo", "(ffff)",
                            {qi::Value::float32(0.f), qi::Value::float32(0.f),
                             qi::Value::float32(0.f), qi::Value::float32(0.25f)},
                            std::chrono::milliseconds(a.timeout_ms));
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t).count();
      report.ok("deadman", bridge.robot_side_deadman_summary() + " (moveTo answered in " +
                               fmt(ms, 0) + " ms)");
    } else {
      report.warn("deadman", bridge.robot_side_deadman_summary());
    }
  } catch (const std::exception& e) {
    report.fail("deadman", "ALMotion.moveTo(x, y, theta, time) refused: " + classify(e));
  }
  bridge.stop();
  bridge.release();
  return summarize(report);
}

}  // namespace

void register_doctor_command(CLI::App& app) {
  auto args = std::make_shared<DoctorArgs>();
  auto* cmd = app.add_subcommand(
      "doctor",
      "Check a robot before a demo: reachability, TLS and login, the NAOqi services used, the "
      "robot's state (NAOqi version, battery, charger, awake or resting, Autonomous Life, "
      "external collision protection, odometry), camera streaming rate and frame size, head lock "
      "read-back, a zero-velocity move, and whether velocity commands end by themselves on the "
      "robot (the robot-side deadman). One line per check: OK, WARN or FAIL, with what to do. "
      "Exit code 0 when no check failed (warnings allowed), 1 when one did. tcps:// robots are "
      "checked against the known-robots file before the password is sent.");
  cmd->add_option("--robot", args->robot, "Robot URL: tcp://HOST:9559 or tcps://HOST:9503")
      ->required();
  cmd->add_option("--user", args->user,
                  "Login user (default for tcps://: nao, Pepper's user on NAOqi 2.9); the "
                  "password comes from "
                  "--password-file, PEPPER_PASSWORD or a prompt");
  cmd->add_option("--password-file", args->password_file, "File whose first line is the password");
  add_trust_options(cmd, args->tls_pin, args->trust_new_robot);
  cmd->add_option("--camera-seconds", args->camera_seconds,
                  "How long to stream for the camera "
                  "check")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  // The bridge's own limits (QiBridgeOptions::validate), refused by the parser like any range.
  cmd->add_option("--timeout-ms", args->timeout_ms, "Connect and call timeout")
      ->check(CLI::Range(1, 600000))
      ->capture_default_str();
  cmd->add_option("--map", args->map,
                  "Check the camera at the size this map was taught at (as its replay will "
                  "subscribe; default: 640x480)");
  cmd->footer(
      "Examples:\n"
      "  pepper_app doctor --robot tcp://10.0.0.5:9559\n"
      "  pepper_app doctor --robot tcp://10.0.0.5:9559 --map maps/lab  # camera at the map's size\n"
      "  pepper_app doctor --robot tcp://127.0.0.1:9559 --camera-seconds 1  # a local mock-robot\n"
      "  pepper_app doctor --robot tcps://10.0.0.5:9503 --password-file ~/.pepper_pw  # user nao");
  cmd->callback([args] {
    try {
      exit_code() = run_doctor(*args);
    } catch (const std::exception& e) {
      std::cerr << "pepper_app doctor: " << e.what() << "\n";
      exit_code() = 1;
    }
  });
}

}  // namespace pepper::app
