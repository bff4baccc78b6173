#pragma once
// Simulated-Pepper fixtures shared by sim_tests (MockRobot) and naoqi_bridge_tests (MockBridge):
// the shipped robotics_room world, loaded once per test binary, and MockRobot options with a
// little less sensor noise than the default.
#include <filesystem>
#include <memory>

#include "sim/mock_robot.hpp"
#include "sim/world.hpp"

namespace pepper::test {

/// worlds/robotics_room.yaml (PEPPER_SOURCE_DIR is set by tests/CMakeLists.txt).
inline std::shared_ptr<const sim::World> room() {
  static const auto w = std::make_shared<const sim::World>(
      sim::load_world(std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds" / "robotics_room.yaml"));
  return w;
}

/// MockRobot defaults with sensor noise sigma 1 grey level (default 1.5).
inline sim::MockRobotOptions small_fast() {
  sim::MockRobotOptions o;
  o.render.noise_sigma_grey = 1.0;
  return o;
}

}  // namespace pepper::test
