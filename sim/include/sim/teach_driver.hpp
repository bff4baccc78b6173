#pragma once
// TeachDriver: drives the simulated robot along a scenario's taught path during a simulated teach
// (the operator's joystick in the real experiments). Uses ground truth, so it belongs to the
// evaluation, never to the navigator.
//
// Waypoints: pure pursuit on the polyline (look-ahead point, curvature 2 y / L^2), speed reduced
// so that |omega| stays within max_omega_rad_s, turning on the spot when the heading error exceeds
// turn_in_place_rad; done within goal_tolerance_m of the last waypoint.
// Script: the velocity steps of the scenario, each for its duration; done after the last one.
// Units: robot-frame velocities (core::BaseVelocity), world poses (Pose2D), seconds.
// Thread-safety: none.

#include <string>
#include <vector>

#include "core/base_velocity.hpp"
#include "sim/world.hpp"

namespace pepper::sim {

struct TeachDriverOptions {
  double lookahead_m = 0.6;
  double max_omega_rad_s = 0.5;
  double turn_in_place_rad = 1.0;
  double goal_tolerance_m = 0.08;

  std::vector<std::string> validate() const;
};

class TeachDriver {
 public:
  /// Follows the scenario's waypoints if it has any, else its velocity script. Throws
  /// std::invalid_argument when the scenario has neither, or for invalid options.
  explicit TeachDriver(const Scenario& scenario, TeachDriverOptions options = {});

  /// Command for the current ground-truth pose at elapsed teach time t_s (script mode).
  core::BaseVelocity command(const Pose2D& pose, double t_s);
  bool done() const { return done_; }
  /// Distance driven along the path so far (waypoint mode), metres.
  double progress_m() const { return progress_m_; }

 private:
  Scenario scenario_;
  TeachDriverOptions options_;
  std::vector<double> cum_m_;
  double progress_m_ = 0.0;
  bool done_ = false;
};

}  // namespace pepper::sim
