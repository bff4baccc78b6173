#pragma once
// Ceiling-mode replay (issue 24; docs/method/ceiling.md "Replay"): the core's CeilingNavigator
// over a ceiling-mode map folder, as the replay loop's step (run_replay_session's StepFunction),
// so that `replay`, `demo` and `evaluate` in ceiling mode run the one replay loop with all its
// stop paths.
//
// The camera geometry is the simulated robot's where there is one (its world's ceiling), else a
// real Pepper's with the configured ceiling height (ceiling_camera_for, as in ceiling teach);
// without a height the callers refuse real robots before anything connects.
// Errors: a map that is not in ceiling mode, a damaged or missing mosaic or tour (MosaicError,
// CeilingTourError, std::runtime_error naming the file), or a world without a ceiling above the
// camera throw before anything moves. Not thread-safe (one replay).

#include <filesystem>
#include <memory>

#include "core/ceiling/ceiling_navigator.hpp"
#include "core/memory/visual_memory.hpp"
#include "session/replay_session.hpp"
#include "sim/mock_robot.hpp"

namespace pepper::app {

/// The replay step of a ceiling map taught in `map_dir` (whose loaded map is `map`), for the
/// mock `robot` (nullptr: a real robot, the ceiling `ceiling_height_m` above the floor) with the
/// head at `head_pitch_rad`. The navigator is shared with the returned
/// function (telemetry and tests may read it).
struct CeilingReplay {
  std::shared_ptr<core::ceiling::CeilingNavigator> navigator;
  StepFunction step;
};
CeilingReplay make_ceiling_replay(const sim::MockRobot* robot, double ceiling_height_m,
                                  const std::filesystem::path& map_dir,
                                  const core::memory::VisualMemory& map, double head_pitch_rad,
                                  const core::ceiling::CeilingNavigatorOptions& options = {});

}  // namespace pepper::app
