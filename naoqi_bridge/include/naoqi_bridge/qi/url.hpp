#pragma once
// Robot URLs: `tcp://HOST[:PORT]` (default port 9559) and `tcps://HOST[:PORT]` (default 9503).
// IPv6 hosts go in brackets: tcp://[::1]:9559. parse_url() throws BridgeError naming the URL.

#include <cstdint>
#include <string>

namespace pepper::naoqi_bridge::qi {

struct Url {
  bool tls = false;
  std::string host;
  std::uint16_t port = 9559;

  std::string to_string() const;
};

Url parse_url(const std::string& text);

}  // namespace pepper::naoqi_bridge::qi
