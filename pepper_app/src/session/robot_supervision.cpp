#include "session/robot_supervision.hpp"

namespace pepper::app {

SupervisionStep supervise_robot(naoqi_bridge::RobotBridge& bridge, SessionLink& link) {
  SupervisionStep step;
  const naoqi_bridge::RobotSupervision s = bridge.supervise();
  for (const auto& w : s.warnings) {
    link.event({{"event", "robot_warning"}, {"message", w}});
    link.warning("robot: " + w);
    link.publish_state({{"robot_warning", w}});
    step.warnings.push_back(w);
  }
  if (s.measured_velocity) {
    step.telemetry = {
        {"v_x_m_s", s.measured_velocity->v_x_m_s},
        {"v_y_m_s", s.measured_velocity->v_y_m_s},
        {"omega_rad_s", s.measured_velocity->omega_rad_s},
        {"move_active", s.move_active ? nlohmann::json(*s.move_active) : nlohmann::json(nullptr)},
        {"move_failing", s.move_failing}};
  }
  if (s.head_lock_lost) {
    step.stop_reason = s.head_lock_detail +
                       ". The base was stopped. Set Autonomous Life to \"disabled\" on the robot "
                       "(its web page or ALAutonomousLife.setState), check that nothing "
                       "re-enables it, and start again";
  }
  return step;
}

}  // namespace pepper::app
