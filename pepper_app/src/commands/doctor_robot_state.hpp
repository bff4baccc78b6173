#pragma once
// `pepper_app doctor`'s robot-state checks (issue 30 item 7): NAOqi version, battery, charger,
// wake state, Autonomous Life, external collision protection and odometry, read only, through
// the services a NAOqi 2.5 / 2.9 robot offers (docs/naoqi_bridge.md "doctor's robot-state checks"
// gives each method and its source). A missing optional service or method is a WARN naming it.

#include <chrono>
#include <vector>

#include "commands/doctor_report.hpp"
#include "naoqi_bridge/qi/session.hpp"

namespace pepper::app::doctor {

/// The names of the checks below, in their order (for the "not checked" lines).
const std::vector<const char*>& robot_state_checks();

/// Runs every robot-state check on a connected session, `call_timeout` per call.
void check_robot_state(naoqi_bridge::qi::QiSession& session, Report& report,
                       std::chrono::milliseconds call_timeout);

}  // namespace pepper::app::doctor
