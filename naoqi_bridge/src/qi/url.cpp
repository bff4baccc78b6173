// Robot URL parsing.
#include "naoqi_bridge/qi/url.hpp"

#include "naoqi_bridge/robot_bridge.hpp"

namespace pepper::naoqi_bridge::qi {

std::string Url::to_string() const {
  const bool v6 = host.find(':') != std::string::npos;
  return std::string(tls ? "tcps://" : "tcp://") + (v6 ? "[" + host + "]" : host) + ":" +
         std::to_string(port);
}

Url parse_url(const std::string& text) {
  auto bad = [&](const std::string& why) -> BridgeError {
    return BridgeError("bad robot URL '" + text + "': " + why +
                       " (expected tcp://HOST[:PORT] or tcps://HOST[:PORT])");
  };
  Url url;
  std::string rest;
  if (text.rfind("tcp://", 0) == 0) {
    rest = text.substr(6);
    url.port = 9559;
  } else if (text.rfind("tcps://", 0) == 0) {
    rest = text.substr(7);
    url.tls = true;
    url.port = 9503;
  } else {
    throw bad("unknown scheme");
  }
  while (!rest.empty() && rest.back() == '/') rest.pop_back();
  std::string port_text;
  if (!rest.empty() && rest.front() == '[') {
    const auto close = rest.find(']');
    if (close == std::string::npos) throw bad("unterminated '['");
    url.host = rest.substr(1, close - 1);
    const std::string after = rest.substr(close + 1);
    if (!after.empty()) {
      if (after.front() != ':') throw bad("unexpected text after ']'");
      port_text = after.substr(1);
    }
  } else {
    const auto colon = rest.rfind(':');
    if (colon != std::string::npos) {
      url.host = rest.substr(0, colon);
      port_text = rest.substr(colon + 1);
    } else {
      url.host = rest;
    }
  }
  if (url.host.empty()) throw bad("empty host");
  if (!port_text.empty()) {
    if (port_text.size() > 5 || port_text.find_first_not_of("0123456789") != std::string::npos) {
      throw bad("port '" + port_text + "' is not a number");
    }
    const unsigned long p = std::stoul(port_text);
    if (p > 65535) throw bad("port " + port_text + " out of range");
    url.port = static_cast<std::uint16_t>(p);
  }
  return url;
}

}  // namespace pepper::naoqi_bridge::qi
