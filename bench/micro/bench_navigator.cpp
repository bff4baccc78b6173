// Navigator hot paths on synthetic VGA frames (tests/core/navigator/test_world.hpp: a textured
// box room rendered by ray casting), single-threaded.
//   BM_NavigatorStep       one Navigator::step on VGA while navigating (feature extraction,
//                          3 two-view + 2 three-view verifications, control), key images every
//                          ~0.3 m on a straight run.
//   BM_InitialLocalization localisation of one VGA frame (ORB extraction + prefilter vote over
//                          all key images + geometric verification of the best) in a
//                          150-key-image map laid along a 24 m loop of the room.
//   BM_PrefilterVote       the vote alone over the 150 key images.
// Run (numbers in docs/method/navigator.md):
//   taskset -c 0 build-nav/bench/bench_navigator --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true   (one command line)
// The program calls cv::setNumThreads(1) itself.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/core/utility.hpp>

#include "../../tests/core/navigator/test_world.hpp"
#include "core/localization/initial_localizer.hpp"
#include "core/navigator/navigator.hpp"

namespace {
using namespace pepper;

const core::CameraIntrinsics& vga() {
  static const core::CameraIntrinsics k = core::CameraIntrinsics::pepper_top_vga();
  return k;
}

core::memory::KeyImage key_at(const test::BoxWorld& world, const test::Pose2d& pose, int64_t i) {
  static const core::features::FeatureExtractor extractor(vga());
  core::memory::KeyImage k;
  k.source_frame_index = i;
  k.t_ns = i * 200'000'000LL;
  k.features = extractor.extract(world.render(pose, vga()), core::features::kPartsAll);
  return k;
}

// Straight run along +x at y = -2 (4.5 cm per frame), key image every 7th frame (~0.3 m).
struct StraightRun {
  std::vector<core::Frame> frames;
  core::memory::VisualMemory map;
};
const StraightRun& straight_run() {
  static const StraightRun run = [] {
    StraightRun r;
    const test::BoxWorld& world = test::shared_world();
    const auto path = test::straight_turn_straight(-3.0, -2.0, 4.0, 0.0, 1.0, 0.0, 0.045);
    r.map.camera = vga();
    for (size_t i = 0; i < path.size(); ++i) {
      if (i % 7 == 0) r.map.key_images.push_back(key_at(world, path[i], static_cast<int64_t>(i)));
      core::Frame f;
      f.gray = world.render(path[i], vga());
      f.t_ns = static_cast<int64_t>(i) * 200'000'000LL;
      f.index = static_cast<int64_t>(i);
      r.frames.push_back(f);
    }
    return r;
  }();
  return run;
}

void BM_NavigatorStep(benchmark::State& state) {
  const StraightRun& run = straight_run();
  const size_t first = 3, last = run.frames.size() - 10;
  std::optional<core::navigator::Navigator> nav;
  size_t i = last;
  double extract_ms = 0, match_ms = 0, control_ms = 0;
  int n = 0;
  for (auto _ : state) {
    if (i >= last) {  // restart the run (not timed): fresh navigator, localised on one frame
      state.PauseTiming();
      nav.emplace(run.map);
      nav->step(run.frames[first - 1]);
      i = first;
      state.ResumeTiming();
    }
    const auto r = nav->step(run.frames[i++]);
    benchmark::DoNotOptimize(r.command.omega_rad_s);
    extract_ms += r.telemetry.timings.extract_ms;
    match_ms += r.telemetry.timings.match_ms;
    control_ms += r.telemetry.timings.control_ms;
    ++n;
    if (r.command.stop) state.SkipWithError("navigator stopped during the benchmark run");
  }
  // Mean wall-clock split from telemetry (includes waiting when the core is shared).
  state.counters["extract_ms"] = extract_ms / std::max(1, n);
  state.counters["match_ms"] = match_ms / std::max(1, n);
  state.counters["control_ms"] = control_ms / std::max(1, n);
}
BENCHMARK(BM_NavigatorStep)->Unit(benchmark::kMillisecond)->Iterations(60);

// Pose at key index i (may be fractional) of 150 along a rounded-square loop (half side 2.4 m,
// corner radius 1.0 m, perimeter ~21.8 m), counter-clockwise; `left_m` shifts it sideways.
test::Pose2d loop_pose(double i, double left_m = 0.0) {
  const double h = 2.4, rc = 1.0, side = 2 * (h - rc), arc = std::numbers::pi / 2 * rc;
  double s = 4 * (side + arc) * i / 150.0;
  const int quarter = static_cast<int>(s / (side + arc));
  s -= quarter * (side + arc);
  double x, y, yaw;  // quarter 0: along +x at y = -h, then a left turn
  if (s < side) {
    x = -(h - rc) + s;
    y = -h;
    yaw = 0;
  } else {
    const double a = (s - side) / rc;
    x = (h - rc) + rc * std::sin(a);
    y = -h + rc * (1 - std::cos(a));
    yaw = a;
  }
  x -= left_m * std::sin(yaw);
  y += left_m * std::cos(yaw);
  const double q = quarter * std::numbers::pi / 2;
  return {x * std::cos(q) - y * std::sin(q), x * std::sin(q) + y * std::cos(q), yaw + q};
}

const core::memory::VisualMemory& long_map() {
  static const core::memory::VisualMemory map = [] {
    core::memory::VisualMemory m;
    m.camera = vga();
    for (int i = 0; i < 150; ++i)
      m.key_images.push_back(key_at(test::shared_world(), loop_pose(i), i));
    return m;
  }();
  return map;
}

void BM_InitialLocalization(benchmark::State& state) {
  const auto& map = long_map();
  const core::features::FeatureExtractor extractor(vga());
  // A view between key images 70 and 71, 5 cm left of the loop.
  const cv::Mat gray = test::shared_world().render(loop_pose(70.5, 0.05), vga());
  core::localization::InitialLocalizationReport report;
  for (auto _ : state) {
    core::features::FrameMatcher fm(extractor.extract(gray, core::features::kPartsAll));
    report = core::localization::localize_in_map(fm, map);
    benchmark::DoNotOptimize(report.result.best);
  }
  state.counters["best"] = report.result.best;  // expected 70 or 71
  state.counters["verified"] = report.verified;
  if (!report.result.segment) state.SkipWithError("not localised");
}
BENCHMARK(BM_InitialLocalization)->Unit(benchmark::kMillisecond)->Iterations(10);

void BM_PrefilterVote(benchmark::State& state) {
  const auto& map = long_map();
  const core::features::FeatureExtractor extractor(vga());
  const auto current =
      extractor.extract(map.key_images[77].features.gray, core::features::kPartWideBaseline);
  for (auto _ : state) {
    benchmark::DoNotOptimize(core::localization::prefilter_votes(current, map));
  }
}
BENCHMARK(BM_PrefilterVote)->Unit(benchmark::kMillisecond)->Iterations(10);

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
