#pragma once
// The robot's own view during a session, once per loop iteration (teach and replay): asks the
// bridge to supervise (RobotBridge::supervise: read-backs of the executed velocity and of the
// head lock), tells the operator each new warning (a JSON "robot_warning" event and the UI's
// state key "robot_warning"), and hands the loop what to record and whether it must stop.
// A head lock that cannot be held ends the session: the bridge has already stopped the base; the
// loop stops it again on its own stop path and reports `stop_reason`.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "naoqi_bridge/robot_bridge.hpp"
#include "session/session_link.hpp"

namespace pepper::app {

struct SupervisionStep {
  /// Set when the session must end: why, and what the operator should do.
  std::optional<std::string> stop_reason;
  /// For the per-frame telemetry ("robot" key): the robot's read-back velocity, moveIsActive and
  /// whether a move failure is in progress; null before the first read-back.
  nlohmann::json telemetry;
  std::vector<std::string> warnings;  ///< new this iteration (already sent to the link)
};

SupervisionStep supervise_robot(naoqi_bridge::RobotBridge& bridge, SessionLink& link);

}  // namespace pepper::app
