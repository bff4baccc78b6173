// Ceiling mode in closed loop (issue 24): part of the ceiling test hall's tour
// (tests/worlds/ceiling_hall.yaml: 2.5 m straight, the left turn, 1 m after it) is taught in
// ceiling mode at QVGA and replayed from one perturbed start through the product's sessions
// (teach_tour, evaluate: run_teach_session, run_replay_session with the ceiling navigator); the
// replay must complete the tour near the taught path.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "config/app_config.hpp"
#include "evaluation/closed_loop.hpp"
#include "session/session_cli.hpp"
#include "sim/world.hpp"
#include "support/temp_dir.hpp"

namespace pepper::app::evaluation {
namespace {

std::shared_ptr<const sim::World> hall_part() {
  sim::World w = sim::load_world(std::string(PEPPER_SOURCE_DIR) + "/tests/worlds/ceiling_hall.yaml");
  w.scenario.waypoints_m = {{-1.5, -1.2}, {1.0, -1.2}, {2.2, 0.0}, {2.2, 1.0}};
  w.scenario.teach_start.reset();  // the first waypoint, facing the second
  return std::make_shared<const sim::World>(std::move(w));
}

// Bounds from the measured run, with margin: this start (seed 1, 518 frames) measured lateral
// RMS 1.1 cm, max 2.5 cm (converged part), end error 4.5 cm (printed below; deterministic: the
// same in two runs). The bounds: RMS < 3 cm, max < 8 cm, end < 15 cm (the targets are
// 5 cm RMS and 15 cm max). docs/method/ceiling.md "Replay in ceiling mode".
TEST(CeilingClosedLoop, PartOfTheHallTourCompletesNearTheTaughtPath) {
  const test::TempDir tmp("ceiling_loop");
  EvaluationOptions o;
  o.width_px = 320;
  o.height_px = 240;
  o.starts = 1;
  o.seed = 1;
  o.mode = core::NavMode::kCeiling;
  o.head = head_request(AppConfig{}, core::NavMode::kCeiling);
  o.map_dir = tmp.path() / "map";
  const auto world = hall_part();
  const TeachResult teach = teach_tour(world, o);
  EXPECT_EQ(teach.map.mode, core::NavMode::kCeiling);
  ASSERT_GE(teach.map.key_images.size(), 3u);
  const Evaluation ev = evaluate(teach, world, o);
  ASSERT_EQ(ev.runs.size(), 1u);
  const RunResult& r = ev.runs[0];
  SCOPED_TRACE(r.outcome + " " + r.detail);
  // The figures the bounds below come from (printed, docs/method/ceiling.md).
  std::printf("ceiling closed loop: %s, %d frames, lateral rms %.1f cm, max %.1f cm, end error "
              "%.1f cm, step p50 %.1f ms\n",
              r.outcome.c_str(), r.frames, 100 * r.lateral_rms_m, 100 * r.lateral_max_m,
              100 * r.final_error_m, r.step_ms_median);
  EXPECT_EQ(ev.mode, "ceiling");
  EXPECT_TRUE(r.success);
  EXPECT_EQ(r.outcome, "complete");
  EXPECT_EQ(r.lost_frames, 0);
  EXPECT_GT(r.frames, 100);
  EXPECT_LT(r.lateral_rms_m, 0.03);
  EXPECT_LT(r.lateral_max_m, 0.08);
  EXPECT_LT(r.final_error_m, 0.15);

  // The same start traced: each frame's line carries the ceiling navigator's telemetry (the
  // pose in the mosaic, the fix), which the forward telemetry does not have.
  EvaluationOptions traced = o;
  traced.trace_dir = tmp.path() / "trace";
  evaluate(teach, world, traced);
  std::ifstream trace(traced.trace_dir / (teach.world_name + "_ceiling_none_run1.jsonl"));
  ASSERT_TRUE(trace);
  int frames = 0, posed = 0;
  for (std::string line; std::getline(trace, line);) {
    const nlohmann::json j = nlohmann::json::parse(line);
    if (!j.contains("telemetry")) continue;
    ++frames;
    ASSERT_TRUE(j.contains("ceiling"));
    if (j["ceiling"].at("pose_known").get<bool>()) {
      ++posed;
      EXPECT_TRUE(j["ceiling"].at("T_mosaic_base").contains("x_m"));
    }
  }
  EXPECT_GT(frames, 100);
  EXPECT_GT(posed, frames / 2);
}

}  // namespace
}  // namespace pepper::app::evaluation
