#include "naoqi_bridge/robot_bridge.hpp"

namespace pepper::naoqi_bridge {

const char* to_string(ConnectionState state) {
  switch (state) {
    case ConnectionState::kDisconnected:
      return "disconnected";
    case ConnectionState::kConnecting:
      return "connecting";
    case ConnectionState::kConnected:
      return "connected";
    case ConnectionState::kLost:
      return "lost";
  }
  return "unknown";
}

}  // namespace pepper::naoqi_bridge
