#include "commands/error_advice.hpp"

#include <iostream>

#include "config/app_config.hpp"
#include "core/ceiling/ceiling_tour.hpp"
#include "core/ceiling/mosaic.hpp"
#include "core/memory/visual_memory.hpp"
#include "naoqi_bridge/qi/errors.hpp"
#include "session/console.hpp"
#include "session/recording.hpp"
#include "session/robot_connection.hpp"
#include "session/session_cli.hpp"
#include "sim/world.hpp"

namespace pepper::app {

namespace qi = naoqi_bridge::qi;

std::string next_step_for(const std::exception& e) {
  // Their messages say what to do (the other --mode, or another map): no generic advice.
  if (dynamic_cast<const ModeUnavailableError*>(&e) != nullptr) return "";
  if (const auto* map_error = dynamic_cast<const core::memory::MapError*>(&e);
      map_error != nullptr && map_error->kind() == core::memory::MapError::Kind::kModeMismatch) {
    return "";
  }
  if (dynamic_cast<const core::memory::MapError*>(&e) != nullptr) {
    return "give a map folder written by `pepper_app teach` or `pepper_app map build` "
           "(`pepper_app map info DIR` checks one); a damaged map can be rebuilt from its "
           "recording with `pepper_app map build`";
  }
  if (dynamic_cast<const core::ceiling::MosaicError*>(&e) != nullptr ||
      dynamic_cast<const core::ceiling::CeilingTourError*>(&e) != nullptr) {
    return "the ceiling-mode map is damaged: rebuild it from its recording with `pepper_app map "
           "build --recording MAP.recording --map MAP`, or teach it again with `pepper_app teach "
           "--mode ceiling`";
  }
  if (dynamic_cast<const sim::WorldError*>(&e) != nullptr) {
    return "give a world file that exists and parses, e.g. worlds/robotics_room.yaml "
           "(`pepper_app world check --world FILE` checks one)";
  }
  if (dynamic_cast<const RecordingError*>(&e) != nullptr) {
    return "give a recording folder written by `pepper_app teach` (MAP.recording) or by "
           "`--record DIR`";
  }
  if (dynamic_cast<const MapConflictError*>(&e) != nullptr) return "";  // says what to drop
  if (dynamic_cast<const ConfigError*>(&e) != nullptr) {
    return "fix the value given with --set or in the --config file (`pepper_app config doc` "
           "lists every key, its unit and its range)";
  }
  if (dynamic_cast<const qi::ConnectError*>(&e) != nullptr) {
    return "check that the robot is on, on this network and that the URL's host and port are "
           "right (`pepper_app doctor --robot URL` tests the connection)";
  }
  if (dynamic_cast<const qi::AuthenticationError*>(&e) != nullptr) {
    return "check the user (--user) and the password file (--password-file)";
  }
  return "";
}

std::string next_step_for(const std::exception_ptr& e) {
  if (!e) return "";
  try {
    std::rethrow_exception(e);
  } catch (const std::exception& x) {
    return next_step_for(x);
  } catch (...) {
    return "";
  }
}

std::string message_with_next_step(const std::exception& e) {
  const std::string step = next_step_for(e);
  return step.empty() ? std::string(e.what()) : std::string(e.what()) + ": " + step;
}

int report_exception(const std::exception& e, int code) {
  // Through the console: on a terminal it first clears a progress line of a running session.
  terminal_console().line("pepper_app: error: " + message_with_next_step(e));
  // Usage errors, refused before anything moved: a bad setting or a robot URL that names no robot.
  const bool usage = dynamic_cast<const ConfigError*>(&e) != nullptr ||
                     dynamic_cast<const RobotUrlError*>(&e) != nullptr;
  return usage ? 2 : code;
}

}  // namespace pepper::app
