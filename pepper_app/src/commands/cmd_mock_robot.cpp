// `pepper_app mock-robot`: serve a simulated Pepper over the qi-messaging protocol (the mock
// NAOqi server of naoqi_bridge/qi), until Ctrl-C. See docs/naoqi_bridge.md.
#include <pthread.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <functional>
#include <iostream>
#include <mutex>
#include <thread>
#include <vector>
#include <memory>
#include <string>

#include "commands/commands.hpp"
#include "commands/error_advice.hpp"
#include "naoqi_bridge/qi/mock_server.hpp"
#include "naoqi_bridge/qi/session.hpp"
#include "sim/mock_robot.hpp"
#include "sim/synthetic_pattern_robot.hpp"
#include "sim/world.hpp"

namespace pepper::app {

namespace {

namespace qi = pepper::naoqi_bridge::qi;

struct MockRobotArgs {
  std::string listen = "tcp://127.0.0.1:9559";
  std::string world;
  std::string user;
  std::string password_file;
  std::string tls_cert;
  std::string tls_key;
  std::string log_file;
  int latency_ms = 0;
  int drop_every = 0;
  int disconnect_after = 0;
  int malformed_every = 0;
  double rate_hz = 15.0;
  double idle_timeout_s = 60.0;
  int max_connections = 64;
  bool legacy_service_info = false;
  bool lockstep = false;
  // Robot state (docs/mock_robot.md "Robot state")
  qi::MockRobotState state;
  bool asleep = false;
  bool no_collision_protection = false;
  std::string fail_moves;          ///< cause; every move fails (from fail_moves_after_s)
  double fail_moves_after_s = 0.0;
  double take_head_after_s = -1.0;  ///< < 0: never
  bool take_head_sticky = false;
  double take_head_yaw_rad = 0.5;
};

/// Runs the timed robot-state events of the options (a move failure, Autonomous Life taking the
/// head back) on a thread of its own until stopped.
class StateEvents {
 public:
  StateEvents(qi::MockNaoqiServer& server, const MockRobotArgs& a) {
    if (a.fail_moves.empty() && a.take_head_after_s < 0) return;
    thread_ = std::thread([this, &server, a] {
      struct Due {
        double at_s;
        std::function<void()> run;
      };
      std::vector<Due> due;
      if (!a.fail_moves.empty()) {
        due.push_back(
            {a.fail_moves_after_s, [&server, a] { server.set_move_failure(a.fail_moves); }});
      }
      if (a.take_head_after_s >= 0) {
        due.push_back({a.take_head_after_s, [&server, a] {
                         server.take_head_back(a.take_head_yaw_rad, a.take_head_sticky);
                       }});
      }
      std::sort(due.begin(), due.end(),
                [](const Due& x, const Due& y) { return x.at_s < y.at_s; });
      const auto t0 = std::chrono::steady_clock::now();
      for (const auto& d : due) {
        std::unique_lock lock(mutex_);
        if (cv_.wait_until(lock, t0 + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                          std::chrono::duration<double>(d.at_s)),
                           [this] { return quit_; })) {
          return;
        }
        d.run();
      }
    });
  }
  ~StateEvents() {
    {
      std::lock_guard lock(mutex_);
      quit_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool quit_ = false;
  std::thread thread_;
};

int run_mock_robot(const MockRobotArgs& a) {
  qi::MockServerOptions so;
  so.listen_url = a.listen;
  so.tls_certificate_file = a.tls_cert;
  so.tls_private_key_file = a.tls_key;
  so.reply_latency = std::chrono::milliseconds(a.latency_ms);
  so.drop_every_nth_frame = a.drop_every;
  so.disconnect_after_messages = a.disconnect_after;
  so.malformed_reply_every_nth = a.malformed_every;
  so.legacy_service_info = a.legacy_service_info;
  so.pace_frames = !a.lockstep;
  so.call_log_file = a.log_file;
  so.idle_timeout = std::chrono::milliseconds(static_cast<long>(a.idle_timeout_s * 1000.0));
  so.max_connections = a.max_connections;
  so.robot_state = a.state;
  so.robot_state.awake = !a.asleep;
  so.robot_state.collision_protection = !a.no_collision_protection;
  if (!a.user.empty()) {
    so.user = a.user;
    if (!a.password_file.empty()) {
      so.password = qi::read_password_file(a.password_file);
    } else if (auto env = qi::read_password_env("PEPPER_PASSWORD")) {
      so.password = *env;
    } else {
      so.password = qi::prompt_password("Password the mock robot expects for '" + a.user + "': ");
    }
  }
  const auto errors = so.validate();
  if (!errors.empty()) {
    for (const auto& e : errors) std::cerr << "pepper_app mock-robot: " << e << "\n";
    return 2;
  }

  std::unique_ptr<sim::SimRobot> robot;
  std::string what;
  if (!a.world.empty()) {
    auto world = std::make_shared<const sim::World>(sim::load_world(a.world));
    sim::MockRobotOptions ro;
    ro.frame_rate_hz = a.rate_hz;
    robot = std::make_unique<sim::MockRobot>(world, ro);
    what = "textured world " + a.world;
  } else {
    sim::SyntheticPatternOptions ro;
    ro.frame_rate_hz = a.rate_hz;
    robot = std::make_unique<sim::SyntheticPatternRobot>(ro);
    what = "synthetic test pattern";
  }

  // Block the stop signals in every thread (the server's I/O thread inherits the mask), then
  // wait for them here.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  qi::MockNaoqiServer server(*robot, so);
  server.start();
  StateEvents events(server, a);
  std::cout << "mock NAOqi serving a simulated Pepper (" << what << ") on " << server.url() << "\n";
  const auto& rs = so.robot_state;
  std::cout << "robot state: NAOqi " << rs.naoqi_version << ", battery " << rs.battery_percent
            << " %" << (rs.charging ? " (charging)" : "") << ", "
            << (rs.awake ? "awake" : "resting") << ", Autonomous Life " << rs.autonomous_life
            << ", external collision protection " << (rs.collision_protection ? "on" : "off");
  for (const auto& m : rs.missing_services) std::cout << ", no " << m;
  std::cout << "\n";
  if (!server.certificate_sha256().empty()) {
    std::cout << "TLS certificate SHA-256: " << server.certificate_sha256() << "\n";
  }
  if (!a.user.empty()) std::cout << "login required: user '" << a.user << "'\n";
  std::cout << "connect with: pepper_app doctor --robot " << server.url()
            << (a.user.empty() ? "" : " --user " + a.user) << "\nCtrl-C to stop.\n"
            << std::flush;
  int sig = 0;
  sigwait(&stop_signals, &sig);
  const auto st = server.stats();
  server.stop();
  std::cout << "\nstopped (" << (sig == SIGINT ? "SIGINT" : "SIGTERM")
            << "): " << st.connections_accepted << " connections, " << st.messages_received
            << " messages, " << st.frames_served << " frames, " << st.auth_failures
            << " failed logins, " << st.bounded_moves_ended
            << " time-constrained moves that stopped the base by themselves\n";
  return 0;
}

}  // namespace

void register_mock_robot_command(CLI::App& app) {
  auto args = std::make_shared<MockRobotArgs>();
  auto* cmd = app.add_subcommand(
      "mock-robot",
      "Serve a simulated Pepper over NAOqi's qi-messaging protocol (tcp:// or tcps://) until "
      "Ctrl-C, so the real client (doctor, teach, replay) can connect to it.");
  cmd->add_option("--listen", args->listen,
                  "URL to listen on, tcp://HOST:PORT or tcps://HOST:PORT"
                  " (port 0: any free port)")
      ->capture_default_str();
  cmd->add_option("--world", args->world,
                  "World YAML for the textured-world MockRobot "
                  "(default: a synthetic moving test pattern)");
  cmd->add_option("--user", args->user,
                  "Require this login user (password from --password-file, "
                  "PEPPER_PASSWORD or a prompt)");
  cmd->add_option("--password-file", args->password_file, "File whose first line is the password");
  cmd->add_option("--tls-cert", args->tls_cert,
                  "PEM certificate for tcps (default: self-signed, "
                  "generated at start-up)");
  cmd->add_option("--tls-key", args->tls_key, "PEM private key for --tls-cert");
  cmd->add_option("--log", args->log_file,
                  "Append one JSON line per call received (service, method, arguments, time) "
                  "to this file; login tokens are logged by length only");
  cmd->add_option("--idle-timeout-s", args->idle_timeout_s,
                  "Close a connection that sends nothing for this long (0 = never); the TLS "
                  "handshake and login must finish within 5 s")
      ->check(CLI::Range(0.0, 86400.0))
      ->capture_default_str();
  cmd->add_option("--max-connections", args->max_connections,
                  "Connections served at once; more are closed on accept")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--rate", args->rate_hz, "Simulated camera frame rate, Hz (lockstep clock)")
      ->capture_default_str();
  cmd->add_option("--latency-ms", args->latency_ms, "Fault injection: delay every reply")
      ->capture_default_str();
  cmd->add_option("--drop-every", args->drop_every,
                  "Fault injection: every Nth image request returns the previous image (0 off)");
  cmd->add_option("--disconnect-after", args->disconnect_after,
                  "Fault injection: close each connection after N messages (0 off)");
  cmd->add_option("--malformed-every", args->malformed_every,
                  "Fault injection: corrupt every Nth non-empty reply (0 off)");
  cmd->add_flag("--lockstep", args->lockstep,
                "Serve frames as fast as they are requested (simulated time runs faster than real "
                "time) instead of at the subscribed fps");
  cmd->add_flag("--legacy-service-info", args->legacy_service_info,
                "Answer NAOqi 2.5's 6-field ServiceInfo instead of libqi 4's 7 fields");
  cmd->add_option("--naoqi-version", args->state.naoqi_version,
                  "Robot state: version reported by ALSystem.systemVersion")
      ->capture_default_str();
  cmd->add_option("--battery", args->state.battery_percent,
                  "Robot state: battery charge in percent (ALBattery.getBatteryCharge)")
      ->check(CLI::Range(0, 100))
      ->capture_default_str();
  cmd->add_flag("--charging", args->state.charging,
                "Robot state: charger plugged (power hatch open): moves are refused");
  cmd->add_flag("--asleep", args->asleep,
                "Robot state: resting (ALMotion.robotIsWakeUp false) until a client wakes it up");
  cmd->add_option("--autonomous-life", args->state.autonomous_life,
                  "Robot state: Autonomous Life state")
      ->check(CLI::IsMember({"solitary", "interactive", "disabled", "safeguard"}))
      ->capture_default_str();
  cmd->add_flag("--no-collision-protection", args->no_collision_protection,
                "Robot state: external collision protection of the move turned off");
  cmd->add_option("--without-service", args->state.missing_services,
                  "Robot state: leave this service out of the directory (repeatable), e.g. "
                  "ALBattery");
  cmd->add_option("--fail-moves", args->fail_moves,
                  "Simulation: every move fails with this cause (the base stays still and "
                  "ALMotion/MoveFailed is raised), as external collision protection near an "
                  "obstacle; from --fail-moves-after-s on");
  cmd->add_option("--fail-moves-after-s", args->fail_moves_after_s,
                  "Seconds after start-up when --fail-moves begins")
      ->check(CLI::Range(0.0, 86400.0))
      ->capture_default_str();
  cmd->add_option("--take-head-after-s", args->take_head_after_s,
                  "Simulation: this many seconds after start-up Autonomous Life takes the head "
                  "back (solitary, awareness on, head turned to a tracked person)")
      ->check(CLI::Range(0.0, 86400.0));
  cmd->add_flag("--take-head-sticky", args->take_head_sticky,
                "With --take-head-after-s: Autonomous Life and awareness cannot be turned off "
                "again, so the head lock cannot be held");
  cmd->footer(
      "Examples:\n"
      "  pepper_app mock-robot --listen tcp://127.0.0.1:9559\n"
      "  pepper_app mock-robot --listen tcp://127.0.0.1:9559 --world worlds/white_corridor.yaml\n"
      "  PEPPER_PASSWORD=pepper pepper_app mock-robot --listen tcps://127.0.0.1:9503 --user nao\n"
      "  pepper_app mock-robot --listen tcp://127.0.0.1:9559 --asleep --battery 12 "
      "--autonomous-life solitary");
  cmd->callback([args] {
    try {
      exit_code() = run_mock_robot(*args);
    } catch (const std::exception& e) {
      std::cerr << "pepper_app mock-robot: " << message_with_next_step(e) << "\n";
      exit_code() = 1;
    }
  });
}

}  // namespace pepper::app
