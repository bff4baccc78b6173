#include "commands/doctor_robot_state.hpp"

#include <cmath>
#include <optional>
#include <string>
#include <utility>

#include "naoqi_bridge/qi/errors.hpp"

namespace pepper::app::doctor {

namespace qi = pepper::naoqi_bridge::qi;

namespace {

constexpr int kBatteryFailBelowPercent = 20;  // a tour may end in a rest or a shutdown
constexpr int kBatteryWarnBelowPercent = 40;  // enough for a short session only

/// The service, or nullopt after a WARN that names it and what was not checked.
std::optional<qi::ServiceHandle> optional_service(qi::QiSession& session, const char* name,
                                                  Report& report, const std::string& check,
                                                  const std::string& todo) {
  try {
    return session.service(name);
  } catch (const qi::ServiceNotFound&) {
    report.warn(check, std::string("not checked: the robot has no ") + name + " service", todo);
  } catch (const std::exception& e) {
    report.warn(check, std::string("not checked: ") + name + ": " + classify(e), todo);
  }
  return std::nullopt;
}

bool has_method(const qi::ServiceHandle& h, const char* name, const char* sig) {
  return h.meta.find(name, sig) != nullptr;
}

void check_version(qi::QiSession& session, Report& report, std::chrono::milliseconds t) {
  const std::string check = "naoqi version";
  std::string version, source;
  using Source = std::pair<const char*, const char*>;  // service, method
  for (const auto& [svc, method] : {Source{"ALSystem", "systemVersion"}, {"ALMotion", "version"}}) {
    try {
      const auto h = session.service(svc);
      if (!has_method(h, method, "()")) continue;
      version = session.call(h, method, "()", {}, t).as_string();
      source = std::string(svc) + "." + method;
      break;
    } catch (const std::exception&) {
    }
  }
  if (version.empty()) {
    report.warn(check, "unknown: neither ALSystem.systemVersion nor ALMotion.version answered",
                "read it on the robot's web page; this client was written for NAOqi 2.5 and 2.9");
  } else if (version.rfind("2.5.", 0) == 0 || version.rfind("2.9.", 0) == 0) {
    report.ok(check, "NAOqi " + version + " (" + source +
                         "), a version this client was "
                         "written for (2.5: tcp://ROBOT:9559, 2.9: tcps://ROBOT:9503 with login)");
  } else {
    report.warn(check, "NAOqi " + version + " (" + source + "), not 2.5 or 2.9",
                "methods are resolved by name and signature, but watch the first session "
                "closely (stop with Ctrl-C or the UI's STOP)");
  }
}

void check_battery(qi::QiSession& session, Report& report, std::chrono::milliseconds t) {
  const std::string check = "battery";
  const auto h = optional_service(session, "ALBattery", report, check,
                                  "look at the charge on the robot's tablet or web page");
  if (!h) return;
  try {
    const long pct = static_cast<long>(session.call(*h, "getBatteryCharge", "()", {}, t).as_int());
    const std::string msg = std::to_string(pct) + " % charged";
    if (pct < kBatteryFailBelowPercent) {
      report.fail(check, msg + " (below " + std::to_string(kBatteryFailBelowPercent) + " %)",
                  "charge Pepper before driving: at this charge a tour may end in a rest or a "
                  "shutdown");
    } else if (pct < kBatteryWarnBelowPercent) {
      report.warn(check, msg + " (below " + std::to_string(kBatteryWarnBelowPercent) + " %)",
                  "enough for a short session only; charge it soon");
    } else {
      report.ok(check, msg);
    }
  } catch (const std::exception& e) {
    report.warn(check, "ALBattery.getBatteryCharge: " + classify(e),
                "look at the charge on the robot's tablet or web page");
  }
}

void check_charging(qi::QiSession& session, Report& report, std::chrono::milliseconds t) {
  const std::string check = "charger";
  const std::string todo_unknown =
      "make sure the charger is unplugged and the power hatch closed (Pepper does not move "
      "while it is open)";
  const auto h = optional_service(session, "ALMemory", report, check, todo_unknown);
  if (!h) return;
  // The battery current (A) is positive while the charger feeds the battery; NAOqi 2.5 keeps it
  // in ALMemory under the device key below.
  const char* key = "Device/SubDeviceList/Battery/Current/Sensor/Value";
  try {
    const double amps =
        session.call(*h, "getData", "(s)", {qi::Value::string(key)}, t).unwrapped().as_double();
    const std::string msg = "battery current " + fmt(amps, 2) + " A";
    if (amps > 0.05) {
      report.fail(check, "plugged in, charging (" + msg + ")",
                  "unplug the charger and close the power hatch: Pepper refuses to move while "
                  "it is open");
    } else {
      report.ok(check, "not charging (" + msg + "): the power hatch can be closed");
    }
  } catch (const std::exception& e) {
    report.warn(check, std::string("unknown: ALMemory.getData(\"") + key + "\"): " + classify(e),
                todo_unknown);
  }
}

void check_wake(qi::QiSession& session, Report& report, std::chrono::milliseconds t) {
  const std::string check = "wake state";
  try {
    const auto h = session.service("ALMotion");
    if (!has_method(h, "robotIsWakeUp", "()")) {
      report.warn(check, "not checked: ALMotion has no robotIsWakeUp()",
                  "look at the robot: resting means head down, motors off");
      return;
    }
    if (session.call(h, "robotIsWakeUp", "()", {}, t).as_bool()) {
      report.ok(check, "awake (motors on)");
    } else {
      report.warn(check, "resting (motors off): it cannot drive like this",
                  "teach and replay wake it up (ALMotion.wakeUp) and it stands up, and so does "
                  "this doctor's head-lock check below: keep the space around it clear");
    }
  } catch (const std::exception& e) {
    report.warn(check, "ALMotion.robotIsWakeUp: " + classify(e),
                "look at the robot: resting means head down, motors off");
  }
}

void check_autonomous_life(qi::QiSession& session, Report& report, std::chrono::milliseconds t) {
  const std::string check = "autonomous life";
  const auto h = optional_service(
      session, "ALAutonomousLife", report, check,
      "nothing turns autonomous behaviour off for the session: make sure the robot runs none");
  if (!h) return;
  try {
    const std::string state = session.call(*h, "getState", "()", {}, t).as_string();
    if (state == "disabled") {
      report.ok(check, "disabled: nothing moves the head or the base on its own");
    } else if (state == "solitary" || state == "interactive") {
      report.warn(check,
                  "'" + state +
                      "': Pepper turns its head and base towards people (basic "
                      "awareness) and may start activities by itself",
                  "teach and replay set it to disabled for the session and restore it after; "
                  "if a session stops with 'head lock lost', set it to disabled on the robot "
                  "first");
    } else {
      report.warn(check, "'" + state + "': the robot is handling a safety event",
                  "check the robot and its tablet, then set Autonomous Life to disabled");
    }
  } catch (const std::exception& e) {
    report.warn(check, "ALAutonomousLife.getState: " + classify(e),
                "check Autonomous Life on the robot's web page");
  }
}

void check_collision_protection(qi::QiSession& session, Report& report,
                                std::chrono::milliseconds t) {
  const std::string check = "collision protection";
  try {
    const auto h = session.service("ALMotion");
    if (!has_method(h, "getExternalCollisionProtectionEnabled", "(s)")) {
      report.warn(check, "not checked: ALMotion has no getExternalCollisionProtectionEnabled(s)",
                  "assume nothing on the robot stops the base before obstacles");
      return;
    }
    const bool on =
        session
            .call(h, "getExternalCollisionProtectionEnabled", "(s)", {qi::Value::string("Move")}, t)
            .as_bool();
    if (on) {
      report.ok(check,
                "external collision protection on for the move: the base stops before "
                "obstacles (a session reports such a stop as 'move failed')");
    } else {
      report.warn(check,
                  "external collision protection off for the move: nothing on the robot "
                  "stops the base before an obstacle",
                  "turn it on (ALMotion.setExternalCollisionProtectionEnabled(\"Move\", true)) "
                  "unless the taught path passes closer to obstacles than it allows");
    }
  } catch (const std::exception& e) {
    report.warn(check, "ALMotion.getExternalCollisionProtectionEnabled: " + classify(e),
                "assume nothing on the robot stops the base before obstacles");
  }
}

void check_odometry(qi::QiSession& session, Report& report, std::chrono::milliseconds t) {
  const std::string check = "odometry";
  const std::string todo = "sessions then measure the map's distances by the commanded speeds";
  try {
    const auto h = session.service("ALMotion");
    if (!has_method(h, "getRobotPosition", "(b)")) {
      report.warn(check, "ALMotion has no getRobotPosition(b)", todo);
      return;
    }
    const auto v = session.call(h, "getRobotPosition", "(b)", {qi::Value::boolean(true)}, t);
    const auto& e = v.elements();
    bool finite = e.size() == 3;
    for (const auto& x : e) finite = finite && std::isfinite(x.as_double());
    if (finite) {
      report.ok(check, "ALMotion.getRobotPosition(true) answers [" + fmt(e[0].as_double(), 3) +
                           ", " + fmt(e[1].as_double(), 3) + ", " + fmt(e[2].as_double(), 3) +
                           "] (x m, y m, theta rad)");
    } else {
      report.warn(check,
                  "ALMotion.getRobotPosition(true) returned " + v.to_debug_string() +
                      ", not three finite numbers",
                  todo);
    }
  } catch (const std::exception& e) {
    report.warn(check, "ALMotion.getRobotPosition(true): " + classify(e), todo);
  }
}

}  // namespace

const std::vector<const char*>& robot_state_checks() {
  static const std::vector<const char*> names = {
      "naoqi version",        "battery", "charger", "wake state", "autonomous life",
      "collision protection", "odometry"};
  return names;
}

void check_robot_state(qi::QiSession& session, Report& report, std::chrono::milliseconds t) {
  check_version(session, report, t);
  check_battery(session, report, t);
  check_charging(session, report, t);
  check_wake(session, report, t);
  check_autonomous_life(session, report, t);
  check_collision_protection(session, report, t);
  check_odometry(session, report, t);
}

}  // namespace pepper::app::doctor
