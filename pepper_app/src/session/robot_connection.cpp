#include "session/robot_connection.hpp"

#include <unistd.h>

#include <stdexcept>

#include "naoqi_bridge/mock_bridge.hpp"
#include "naoqi_bridge/qi/qi_bridge.hpp"
#include "naoqi_bridge/qi/session.hpp"
#include "naoqi_bridge/qi/url.hpp"
#include "session/known_robots.hpp"
#include "sim/world.hpp"

namespace pepper::app {

namespace qi = naoqi_bridge::qi;

RobotUrl parse_robot_url(const std::string& text) {
  RobotUrl out;
  if (text.rfind("mock:", 0) == 0) {
    out.kind = RobotUrl::Kind::kMock;
    out.world_file = text.substr(5);
    if (out.world_file.empty()) {
      throw RobotUrlError("robot URL '" + text + "': mock: needs a world file, e.g. "
                                  "mock:worlds/robotics_room.yaml");
    }
    out.url = text;
    return out;
  }
  if (text.rfind("tcp://", 0) != 0 && text.rfind("tcps://", 0) != 0) {
    throw RobotUrlError("robot URL '" + text +
                                "': expected tcp://HOST[:9559], tcps://HOST[:9503] or mock:WORLD");
  }
  try {
    const qi::Url u = qi::parse_url(text);
    out.kind = u.tls ? RobotUrl::Kind::kTcps : RobotUrl::Kind::kTcp;
    out.url = u.to_string();
  } catch (const std::exception& e) {
    throw RobotUrlError("robot URL '" + text + "': " + e.what());
  }
  return out;
}

RobotConnection open_mock_robot(std::shared_ptr<const sim::World> world,
                                const sim::MockRobotOptions& robot_options,
                                naoqi_bridge::MockBridgeOptions bridge_options) {
  RobotConnection c;
  c.url.kind = RobotUrl::Kind::kMock;
  c.url.world_file = world->source;
  c.url.url = "mock:" + world->source.string();
  if (bridge_options.description.empty()) bridge_options.description = c.url.url;
  c.mock = std::make_shared<sim::MockRobot>(std::move(world), robot_options);
  c.bridge = std::make_unique<naoqi_bridge::MockBridge>(*c.mock, bridge_options);
  return c;
}

RobotLogin robot_login(bool tls, const std::string& user, const std::string& password_file,
                       bool allow_prompt, const std::string& url) {
  RobotLogin login;
  login.user = user.empty() && tls ? "nao" : user;
  if (login.user.empty()) return login;
  if (!password_file.empty()) {
    login.password = qi::read_password_file(password_file);
  } else if (auto env = qi::read_password_env("PEPPER_PASSWORD")) {
    login.password = *env;
  } else if (allow_prompt && ::isatty(STDIN_FILENO) != 0) {
    login.password = qi::prompt_password("Password for '" + login.user + "' on " + url + ": ");
  } else {
    throw naoqi_bridge::BridgeError(
        "no password for user '" + login.user +
        "': give --password-file FILE or set PEPPER_PASSWORD (no terminal to prompt on)");
  }
  return login;
}

RobotConnection open_robot(const std::string& url, const RobotConnectOptions& options) {
  const RobotUrl parsed = parse_robot_url(url);
  if (parsed.kind == RobotUrl::Kind::kMock) {
    auto world = std::make_shared<const sim::World>(sim::load_world(parsed.world_file));
    sim::MockRobotOptions ro;
    ro.frame_rate_hz = options.mock_frame_rate_hz;
    naoqi_bridge::MockBridgeOptions bo;
    bo.description = parsed.url;
    RobotConnection c = open_mock_robot(std::move(world), ro, bo);
    c.url = parsed;
    return c;
  }
  RobotConnection c;
  c.url = parsed;
  qi::QiBridgeOptions qo;
  qo.url = c.url.url;
  const RobotLogin login = robot_login(c.url.kind == RobotUrl::Kind::kTcps, options.user,
                                       options.password_file, options.allow_prompt, qo.url);
  qo.user = login.user;
  qo.password = login.password;
  qo.watchdog_timeout = std::chrono::milliseconds(options.watchdog_ms);
  qo.frame_stall_timeout = std::chrono::milliseconds(options.frame_stall_ms);
  qo.deadman_horizon = std::chrono::milliseconds(options.deadman_horizon_ms);
  if (c.url.kind == RobotUrl::Kind::kTcps) {
    qo.tls_pin_sha256 = options.tls_pin;
    if (options.tls_pin.empty()) {
      TrustOptions trust;
      trust.file = options.known_robots_file;
      trust.trust_new_robot = options.trust_new_robot;
      trust.allow_prompt = options.allow_prompt;
      qo.verify_certificate = known_robots_verifier(trust);
    }
  }
  const auto problems = qo.validate();
  if (!problems.empty()) {
    std::string all;
    for (const auto& p : problems) all += (all.empty() ? "" : "; ") + p;
    throw std::invalid_argument("robot connection options: " + all);
  }
  c.bridge = std::make_unique<qi::QiBridge>(std::move(qo));
  return c;
}

}  // namespace pepper::app
