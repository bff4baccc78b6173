// Ceiling-mode per-frame cost at QVGA on one core (issue 24 target: <= 10 ms per frame): the
// canonical warp, landmark extraction (ORB + sub-pixel), the mosaic builder's step during teach,
// the localiser with and without a prior, and the replay's whole step (CeilingNavigator::step:
// warp, landmarks, localisation with a prior, law). Frames: 32 renders of tests/worlds/ceiling_hall.yaml
// along a straight 2 m drive with the head at -0.7 rad (rendered once, outside the timing).
//
//   taskset -c 0 build/bench/bench_ceiling --benchmark_repetitions=3
//       --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>
#include <vector>

#include "core/ceiling/canonical_view.hpp"
#include "core/ceiling/ceiling_navigator.hpp"
#include "core/ceiling/landmarks.hpp"
#include "core/ceiling/mosaic_builder.hpp"
#include "core/ceiling/mosaic_localiser.hpp"
#include "core/ceiling/observation.hpp"
#include "sim/mock_robot.hpp"
#include "sim/world.hpp"

namespace {

namespace ceiling = pepper::core::ceiling;
namespace sim = pepper::sim;

constexpr double kPitchRad = -0.7;
constexpr double kPxPerM = 120.0;  // as tests/sim/test_ceiling_mosaic.cpp

struct Fixture {
  std::unique_ptr<ceiling::CanonicalView> view;
  cv::Point2d cam_in_base_m;
  std::vector<cv::Mat> images;
  std::vector<ceiling::CeilingObservation> observations;
  ceiling::Mosaic mosaic;
  ceiling::CeilingTour tour;  ///< the 2 m drive's first and last frames as relay images
};

ceiling::CeilingObservation observe(const Fixture& f, const cv::Mat& image) {
  cv::Mat seen;
  const cv::Mat canonical = f.view->warp(image, &seen);
  return ceiling::observe(*f.view, f.cam_in_base_m, ceiling::extract_landmarks(canonical, seen));
}

const Fixture& fixture() {
  static const Fixture* f = [] {
    auto* out = new Fixture;
    auto world = std::make_shared<const sim::World>(sim::load_world(
        std::filesystem::path(PEPPER_SOURCE_DIR) / "tests" / "worlds" / "ceiling_hall.yaml"));
    sim::MockRobot robot(world);
    robot.set_joint_angles({"HeadPitch"}, {kPitchRad});
    ceiling::CeilingCamera camera;
    camera.intrinsics = robot.intrinsics(320, 240);
    camera.head_pitch_rad = kPitchRad;
    camera.ceiling_above_cam_m =
        world->ceiling_height_m - robot.ground_truth().T_world_cam.translation().z();
    out->view =
        std::make_unique<ceiling::CanonicalView>(camera, ceiling::fit_frame(camera, kPxPerM, 3.5));
    const Eigen::Vector3d t = robot.options().mount.T_base_cam(0.0, kPitchRad).translation();
    out->cam_in_base_m = {t.x(), t.y()};
    ceiling::MosaicBuilderOptions options;
    options.px_per_m = kPxPerM;
    ceiling::MosaicBuilder builder(options);
    for (int k = 0; k < 120; ++k) {  // 2 m at 0.25 m/s, 15 Hz
      robot.command_velocity({0.25, 0.0, 0.0});
      const cv::Mat image = robot.capture(320, 240).gray;
      out->observations.push_back(observe(*out, image));
      builder.add_frame(out->observations.back());
      if (k % 4 == 0) out->images.push_back(image);
    }
    robot.stop_move();
    out->mosaic = builder.mosaic();
    out->tour.frames = 120;
    for (const size_t k : {size_t{0}, size_t{119}}) {
      ceiling::RelayImageRecord r;
      r.frame = static_cast<int64_t>(k);
      r.T_mosaic_base = builder.frames()[k].T_mosaic_base;
      out->tour.relay_images.push_back(r);
    }
    return out;
  }();
  return *f;
}

void BM_CeilingWarpAndLandmarks(benchmark::State& state) {
  const Fixture& f = fixture();
  size_t k = 0;
  for (auto _ : state) {
    auto o = observe(f, f.images[k++ % f.images.size()]);
    benchmark::DoNotOptimize(o);
  }
}
BENCHMARK(BM_CeilingWarpAndLandmarks)->Unit(benchmark::kMillisecond);

void BM_CeilingMosaicBuilderStep(benchmark::State& state) {
  const Fixture& f = fixture();
  ceiling::MosaicBuilderOptions options;
  options.px_per_m = kPxPerM;
  auto builder = std::make_unique<ceiling::MosaicBuilder>(options);
  size_t k = 0;
  for (auto _ : state) {
    if (k == f.observations.size()) {  // a new teach, outside the timing
      state.PauseTiming();
      builder = std::make_unique<ceiling::MosaicBuilder>(options);
      k = 0;
      state.ResumeTiming();
    }
    auto r = builder->add_frame(f.observations[k++]);
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_CeilingMosaicBuilderStep)->Unit(benchmark::kMillisecond);

void BM_CeilingLocaliseNoPrior(benchmark::State& state) {
  const Fixture& f = fixture();
  const ceiling::MosaicLocaliser loc(f.mosaic);
  size_t k = 0;
  for (auto _ : state) {
    auto fix = loc.localise(f.observations[(k++ * 7) % f.observations.size()]);
    benchmark::DoNotOptimize(fix);
  }
  state.counters["landmarks"] = static_cast<double>(f.mosaic.landmarks.size());
}
BENCHMARK(BM_CeilingLocaliseNoPrior)->Unit(benchmark::kMillisecond);

void BM_CeilingLocaliseWithPrior(benchmark::State& state) {
  const Fixture& f = fixture();
  const ceiling::MosaicLocaliser loc(f.mosaic);
  std::vector<ceiling::PlanarPose> priors;
  for (const auto& o : f.observations) priors.push_back(loc.localise(o).T_mosaic_base);
  size_t k = 0;
  for (auto _ : state) {
    const size_t i = (k++ * 7) % f.observations.size();
    auto fix = loc.localise(f.observations[i], priors[i]);
    benchmark::DoNotOptimize(fix);
  }
}
BENCHMARK(BM_CeilingLocaliseWithPrior)->Unit(benchmark::kMillisecond);

void BM_CeilingNavigatorStep(benchmark::State& state) {
  const Fixture& f = fixture();
  const auto make = [&f] {
    return std::make_unique<ceiling::CeilingNavigator>(f.mosaic, f.tour, f.view->camera(),
                                                       f.cam_in_base_m);
  };
  auto nav = make();
  size_t k = 0;
  for (auto _ : state) {
    if (k == f.images.size()) {  // a new replay, outside the timing
      state.PauseTiming();
      nav = make();
      k = 0;
      state.ResumeTiming();
    }
    pepper::core::Frame frame;
    frame.gray = f.images[k];
    frame.t_ns = static_cast<int64_t>(k) * 266'666'667;  // every 4th frame at 15 Hz
    frame.index = static_cast<int64_t>(k++);
    auto r = nav->step(frame);
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_CeilingNavigatorStep)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
