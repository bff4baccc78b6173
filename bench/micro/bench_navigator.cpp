// Navigator hot paths on synthetic VGA frames (tests/core/navigator/test_world.hpp: a textured
// box room built on sim and drawn by sim::Renderer, camera effects off), single-threaded.
//   BM_NavigatorStep       one Navigator::step on VGA while navigating (feature extraction,
//                          two-view matching with IN and INN, and when the switching rules need
//                          them n(IP, Ia) and the two three-view counts; control), key images
//                          every ~0.3 m on a straight run replayed on the taught frames.
//   BM_NavigatorStepTour   the same on the shared test tour (2.5 m, 60 deg left turn of 0.8 m
//                          radius, 1.5 m) taught offline at VGA, replayed 5 cm to the left with
//                          1.7 deg of heading offset: the turn, where key images are far apart
//                          in yaw, is the expensive part.
//   BM_InitialLocalization localisation of one VGA frame (ORB extraction + prefilter vote over
//                          all key images + geometric verification of the best) in a
//                          150-key-image map laid along a 24 m loop of the room.
//   BM_PrefilterVote       the vote alone over the 150 key images.
// Counters: mean wall-clock split of a step from the telemetry (extract_ms, match_ms,
// control_ms), the fraction of steps that computed n(IP, Ia) (prev_frac) and the three-view
// counts (three_view_frac), and the median / 90th percentile / maximum of the per-step CPU time
// of the thread (cpu_p50_ms, cpu_p90_ms, cpu_max_ms; one-core figures even on a shared machine).
// Run (numbers in docs/method/navigator.md):
//   taskset -c 0 build/bench/bench_navigator --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true   (one command line)
// The program calls cv::setNumThreads(1) itself.
#include <benchmark/benchmark.h>

#include <time.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/core/utility.hpp>

#include "../../tests/core/navigator/test_world.hpp"
#include "core/localization/initial_localizer.hpp"
#include "core/mapping/teacher.hpp"
#include "core/navigator/navigator.hpp"

namespace {
using namespace pepper;

const core::CameraIntrinsics& vga() {
  static const core::CameraIntrinsics k = core::CameraIntrinsics::pepper_top_vga();
  return k;
}

core::memory::KeyImage key_at(const test::BoxWorld& world, const sim::Pose2D& pose, int64_t i) {
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

double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// Steps the navigator over frames[first, last) once per iteration, restarting (not timed) with
// a fresh navigator localised on frames[first - 1] when the range is exhausted.
void step_frames(benchmark::State& state, const core::memory::VisualMemory& map,
                 const std::vector<core::Frame>& frames, size_t first, size_t last) {
  std::optional<core::navigator::Navigator> nav;
  size_t i = last;
  double extract_ms = 0, match_ms = 0, control_ms = 0;
  int n = 0, n_prev = 0, n_three_view = 0;
  std::vector<double> cpu_ms;
  for (auto _ : state) {
    if (i >= last) {
      state.PauseTiming();
      nav.emplace(map);
      nav->step(frames[first - 1]);
      i = first;
      state.ResumeTiming();
    }
    const double cpu0_ms = thread_cpu_ms();
    const auto r = nav->step(frames[i++]);
    cpu_ms.push_back(thread_cpu_ms() - cpu0_ms);
    benchmark::DoNotOptimize(r.command.omega_rad_s);
    extract_ms += r.telemetry.timings.extract_ms;
    match_ms += r.telemetry.timings.match_ms;
    control_ms += r.telemetry.timings.control_ms;
    n_prev += r.telemetry.n_prev >= 0;
    n_three_view += r.telemetry.n_three_view_next >= 0;
    ++n;
    if (r.command.stop) state.SkipWithError("navigator stopped during the benchmark run");
  }
  // Mean wall-clock split from telemetry (includes waiting when the core is shared).
  const double d = std::max(1, n);
  state.counters["extract_ms"] = extract_ms / d;
  state.counters["match_ms"] = match_ms / d;
  state.counters["control_ms"] = control_ms / d;
  state.counters["prev_frac"] = n_prev / d;
  state.counters["three_view_frac"] = n_three_view / d;
  // Per-step CPU time of this thread (the one-core figure even on a shared machine).
  std::sort(cpu_ms.begin(), cpu_ms.end());
  if (!cpu_ms.empty()) {
    state.counters["cpu_p50_ms"] = cpu_ms[cpu_ms.size() / 2];
    state.counters["cpu_p90_ms"] = cpu_ms[cpu_ms.size() * 9 / 10];
    state.counters["cpu_max_ms"] = cpu_ms.back();
  }
}

void BM_NavigatorStep(benchmark::State& state) {
  const StraightRun& run = straight_run();
  step_frames(state, run.map, run.frames, 3, run.frames.size() - 10);
}
BENCHMARK(BM_NavigatorStep)->Unit(benchmark::kMillisecond)->Iterations(60);

struct Tour {
  std::vector<core::Frame> frames;  // replay
  core::memory::VisualMemory map;
};
const Tour& tour() {
  static const Tour t = [] {
    const test::BoxWorld& world = test::shared_world();
    const auto path = test::straight_turn_straight(-3.0, -2.0, 2.5, 1.0472, 0.8, 1.5, 0.045);
    core::mapping::TeachOptions teach;
    // As the shared test tour: key images ~0.5 m apart, denser in the turn.
    teach.selector.epsilon = 120;
    Tour r;
    r.map = core::mapping::teach_offline(test::render_frames(world, path, vga()), vga(), teach);
    std::vector<sim::Pose2D> replay = path;
    for (auto& p : replay) {
      p.x_m -= 0.05 * std::sin(p.yaw_rad);
      p.y_m += 0.05 * std::cos(p.yaw_rad);
      p.yaw_rad += 0.03;
    }
    r.frames = test::render_frames(world, replay, vga());
    return r;
  }();
  return t;
}

void BM_NavigatorStepTour(benchmark::State& state) {
  const Tour& t = tour();
  // 108 frames; the last ones are skipped (the tour ends there, stop commands cost nothing).
  step_frames(state, t.map, t.frames, 3, t.frames.size() - 6);
}
BENCHMARK(BM_NavigatorStepTour)->Unit(benchmark::kMillisecond)->Iterations(99);

// Pose at key index i (may be fractional) of 150 along a rounded-square loop (half side 2.4 m,
// corner radius 1.0 m, perimeter ~21.8 m), counter-clockwise; `left_m` shifts it sideways.
sim::Pose2D loop_pose(double i, double left_m = 0.0) {
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
