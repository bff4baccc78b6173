// Mock robot renderer speed: frames per second for each shipped world at VGA and QVGA, one core.
// Each iteration renders the view from the next of 16 poses spread along the world's taught path
// (headings along the path), with the default RenderOptions (noise, optics blur, vignetting).
// Target (issue 4): >= 30 frames/s at VGA on one core.
//
//   taskset -c 0 build/bench/bench_render --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true   (one line)
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "sim/mock_robot.hpp"
#include "sim/renderer.hpp"
#include "sim/world.hpp"

namespace {

namespace sim = pepper::sim;

const std::vector<std::string> kWorlds = {"robotics_room", "room_corridor_room", "white_corridor",
                                          "window_corridor"};

const sim::World& world(size_t i) {
  static std::vector<std::unique_ptr<sim::World>> cache(kWorlds.size());
  if (!cache[i])
    cache[i] = std::make_unique<sim::World>(sim::load_world(
        std::filesystem::path(PEPPER_SOURCE_DIR) / "worlds" / (kWorlds[i] + ".yaml")));
  return *cache[i];
}

std::vector<Eigen::Isometry3d> poses_along_path(const sim::World& w, int n) {
  const auto& p = w.scenario.waypoints_m;
  const double total = w.scenario.path_length_m();
  std::vector<Eigen::Isometry3d> out;
  for (int k = 0; k < n; ++k) {
    double s = total * k / n;
    size_t i = 1;
    while (i + 1 < p.size() && s > (p[i] - p[i - 1]).norm()) {
      s -= (p[i] - p[i - 1]).norm();
      ++i;
    }
    const Eigen::Vector2d d = (p[i] - p[i - 1]).normalized();
    const Eigen::Vector2d q = p[i - 1] + s * d;
    Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();
    T_world_base.translation() = Eigen::Vector3d(q.x(), q.y(), 0.0);
    T_world_base.linear() =
        Eigen::AngleAxisd(std::atan2(d.y(), d.x()), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    out.push_back(T_world_base * sim::CameraMount{}.T_base_cam(0.0, 0.0));
  }
  return out;
}

// Renders world `wi` along its path with `intrinsics` once per iteration (fps counter, label).
void render_along_path(benchmark::State& state, size_t wi,
                       const pepper::core::CameraIntrinsics& intrinsics) {
  const sim::World& w = world(wi);
  const auto poses = poses_along_path(w, 16);
  sim::Renderer renderer;
  sim::ViewState view;
  view.intrinsics = intrinsics;
  cv::Mat img;
  size_t k = 0;
  for (auto _ : state) {
    view.T_world_cam = poses[k % poses.size()];
    view.frame_index = k++;
    renderer.render(w, view, img);
    benchmark::DoNotOptimize(img.data);
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.SetLabel(kWorlds[wi] + " " + std::to_string(intrinsics.width_px) + "x" +
                 std::to_string(intrinsics.height_px));
}

void BM_Render(benchmark::State& state) {
  const int width = static_cast<int>(state.range(1));
  render_along_path(state, static_cast<size_t>(state.range(0)),
                    pepper::core::CameraIntrinsics::pepper_top_vga().scaled_to(width, width * 3 / 4));
}

// The same with Pepper's lens (issue 31: intrinsics with ViSP's distortion model, kud 0.03): the
// extra cost is the per-frame remap of the radiance and depth (renderer.cpp).
void BM_RenderWithDistortion(benchmark::State& state) {
  const int width = static_cast<int>(state.range(0));
  auto intrinsics = pepper::core::CameraIntrinsics::pepper_top_vga().scaled_to(width, width * 3 / 4);
  intrinsics.model = pepper::core::ProjectionModel::kWithDistortion;
  intrinsics.kud = 0.03;
  intrinsics.kdu = -0.029;
  render_along_path(state, 0, intrinsics);
}

// Full MockRobot capture (clock, kinematics, render) at VGA while driving, for reference.
void BM_MockRobotCaptureVga(benchmark::State& state) {
  auto w = std::make_shared<const sim::World>(world(0));
  sim::MockRobot robot(w);
  robot.command_velocity({0.2, 0.0, 0.1});
  for (auto _ : state) {
    auto f = robot.capture(640, 480);
    benchmark::DoNotOptimize(f.gray.data);
    if (robot.collided()) robot.place(w->scenario.start_pose());
  }
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK(BM_Render)
    ->ArgsProduct({{0, 1, 2, 3}, {640, 320}})
    ->ArgNames({"world", "width"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RenderWithDistortion)->Arg(640)->Arg(320)->ArgName("width")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MockRobotCaptureVga)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
