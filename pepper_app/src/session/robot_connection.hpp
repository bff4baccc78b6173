#pragma once
// Robot connection factory: a robot URL from the command line becomes a RobotBridge.
//
//   tcp://HOST[:9559]    NAOqi 2.5, or a running `pepper_app mock-robot` (tcp://127.0.0.1:PORT)
//   tcps://HOST[:9503]   NAOqi 2.9+ (TLS, login): user from RobotConfig::user / --user,
//                        password from --password-file, else $PEPPER_PASSWORD, else an
//                        interactive prompt without echo when stdin is a terminal. Never from the
//                        command line, never logged.
//   mock:WORLD_FILE      in-process simulated Pepper (MockRobot + MockBridge); the connection
//                        also exposes the MockRobot (ground truth, top view, placement).
//
// Ownership: RobotConnection owns the bridge and (for mock:) the simulated robot; the bridge is
// destroyed first (it refers to the robot). Errors: a malformed URL throws std::invalid_argument
// naming it; a missing world file throws sim::WorldError; a missing password throws
// naoqi_bridge::BridgeError. Nothing connects here: the session calls bridge->connect().

#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "naoqi_bridge/mock_bridge.hpp"
#include "naoqi_bridge/robot_bridge.hpp"
#include "sim/mock_robot.hpp"

namespace pepper::app {

struct RobotUrl {
  enum class Kind { kTcp, kTcps, kMock };
  Kind kind = Kind::kMock;
  std::string url;                   ///< normalised (default port added for tcp/tcps)
  std::filesystem::path world_file;  ///< kMock only
};

/// A robot URL that names no robot (unknown scheme, `mock:` without a world, a bad port): a usage
/// error, exit code 2 like a bad --set (docs/errors.md), refused before anything connects.
class RobotUrlError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Parses and normalises a robot URL. Throws RobotUrlError naming the URL.
RobotUrl parse_robot_url(const std::string& text);

struct RobotConnectOptions {
  std::string user;                 ///< login user (tcps; "nao" on NAOqi 2.9)
  std::string password_file;        ///< first line is the password
  bool allow_prompt = true;         ///< prompt on the terminal when no file/env password
  std::string tls_pin;              ///< tcps: required fingerprint; empty: the known-robots file
  bool trust_new_robot = false;     ///< tcps: first contact trusted and saved without asking
  std::filesystem::path known_robots_file;  ///< empty: default_known_robots_file()
  int watchdog_ms = 300;            ///< QiBridge: stop without a fresh move() this long
  int frame_stall_ms = 1000;        ///< QiBridge: stop when moving and frames stall this long
  int deadman_horizon_ms = 250;     ///< QiBridge: robot-side end of each command; 0 = off
  double mock_frame_rate_hz = 15.0; ///< mock: simulated camera rate (lockstep)
};

struct RobotConnection {
  RobotUrl url;
  std::shared_ptr<sim::MockRobot> mock;               ///< set for mock: URLs only
  std::unique_ptr<naoqi_bridge::RobotBridge> bridge;  ///< declared last: destroyed first
};

/// An in-process simulated Pepper over an already loaded world, with the simulated robot's and
/// the WiFi link's options (lighting, camera noise seed, command latency, frame drops). The
/// evaluation and `replay --robot mock:... --mock-start K` build their robot with it, so the same
/// world, start and seed give the same replay. Does not connect.
RobotConnection open_mock_robot(std::shared_ptr<const sim::World> world,
                                const sim::MockRobotOptions& robot_options,
                                naoqi_bridge::MockBridgeOptions bridge_options);

/// The login for a robot: none for tcp:// without a user; for tcps:// (NAOqi 2.9) the user
/// defaults to "nao" (Pepper's user). The password comes from `password_file`, else the
/// PEPPER_PASSWORD environment variable, else a prompt without echo (when `allow_prompt` and
/// standard input is a terminal). Throws naoqi_bridge::BridgeError when none is available.
struct RobotLogin {
  std::string user;      ///< empty: no login
  std::string password;
};
RobotLogin robot_login(bool tls, const std::string& user, const std::string& password_file,
                       bool allow_prompt, const std::string& url);

/// Builds the bridge for `url` (does not connect). tcps:// robots are checked at connect(),
/// before the login is sent: against `tls_pin` when given, else against the known-robots file
/// (trust on first use, session/known_robots.hpp).
RobotConnection open_robot(const std::string& url, const RobotConnectOptions& options);

}  // namespace pepper::app
