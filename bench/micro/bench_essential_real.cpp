// Two-view verification on real Pepper key images (issue 22): match_two_view between key images
// of routes Edge_01, Edge_12 and Edge_45 of shared/data/pepper_qut_tmap (QVGA, default
// FeatureExtractor), 1 and 2 key images apart, and Edge_01 image i against the opposite route's
// Edge_10 image 12 - (12 * i) / 21 (the clutter frames of bench_navigator_real), with
//   five_point/cap       the five-point model alone (features.matcher.essential.planar false,
//                        the default until session 31) with max_iterations = cap (1000: the cap
//                        OpenCV 4.6 used whatever was asked);
//   planar/factor        the planar 2-point model with only the linear refinement
//                        (general_refit false), camera pitch 0.18 rad (this data's, see
//                        bench_navigator_real.cpp), planar_threshold_factor = factor;
//   planar_general/...   the default path: the planar model at factor x the threshold, camera
//                        pitch pitch_crad / 100 rad, seeding the refined general model (the
//                        five-point refit on its candidates with at most refit_cap samples,
//                        general_refit_max_iterations, is one of its two hypotheses).
//   fast                 the app's `fast` preset: planar_general/5/0/25 with a 9 px KLT window.
// The KLT options are the defaults (window_px 15) except in `fast`.
// One iteration matches all pairs once. Counters: verified points and lines summed over the
// neighbour pairs (points_gap1, lines_gap1), the pairs two apart (points_gap2, lines_gap2) and
// the clutter pairs (points_clutter, e_found_clutter: pairs with an essential matrix), and
// cpu_ms: thread CPU time per iteration (one-core figure on a shared machine).
// Run: taskset -c 0 build/bench/bench_essential_real --benchmark_repetitions=3
//          --benchmark_report_aggregates_only=true   (one command line)
#include <benchmark/benchmark.h>

#include <time.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/features/image_features.hpp"
#include "core/features/matching.hpp"
#include "real_data_dir.hpp"

namespace {
using namespace pepper;
namespace fs = std::filesystem;

fs::path data_dir() { return bench::real_data_dir(); }

std::vector<core::features::ImageFeatures> load(const std::string& route) {
  std::vector<fs::path> files;
  const fs::path dir = data_dir() / route;
  if (fs::is_directory(dir))
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".png") files.push_back(e.path());
  if (files.empty()) throw std::runtime_error("no PNG images in " + dir.string());
  std::sort(files.begin(), files.end());
  const core::features::FeatureExtractor ex;  // Pepper calibration scaled to QVGA
  std::vector<core::features::ImageFeatures> out;
  for (const auto& f : files) {
    const cv::Mat img = cv::imread(f.string(), cv::IMREAD_UNCHANGED);
    if (img.empty()) throw std::runtime_error("cannot read " + f.string());
    out.push_back(ex.extract(core::features::to_gray(img)));
  }
  return out;
}

struct Data {
  std::vector<std::vector<core::features::ImageFeatures>> routes;  // Edge_01, Edge_12, Edge_45
  std::vector<core::features::ImageFeatures> opposite;             // Edge_10
};

const Data& data() {
  static const Data d = [] {
    Data x;
    for (const char* r : {"Edge_01", "Edge_12", "Edge_45"}) x.routes.push_back(load(r));
    x.opposite = load("Edge_10");
    return x;
  }();
  return d;
}

double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

void run(benchmark::State& state, const core::features::MatcherOptions& mo) {
  const Data& d = data();
  int points[2] = {0, 0}, lines[2] = {0, 0}, points_clutter = 0, found_clutter = 0;
  double cpu_ms = 0.0;
  int n = 0;
  for (auto _ : state) {
    const double t0 = thread_cpu_ms();
    points[0] = points[1] = lines[0] = lines[1] = points_clutter = found_clutter = 0;
    for (const auto& r : d.routes) {
      for (size_t gap = 1; gap <= 2; ++gap) {
        for (size_t i = 0; i + gap < r.size(); ++i) {
          const auto m = core::features::match_two_view(r[i], r[i + gap], mo);
          points[gap - 1] += m.n_points();
          lines[gap - 1] += m.n_lines();
        }
      }
    }
    const auto& route = d.routes[0];
    for (size_t i = 0; i < route.size() && !d.opposite.empty(); ++i) {
      const size_t j = std::min(d.opposite.size() - 1, 12 - (12 * i) / 21);
      const auto m = core::features::match_two_view(route[i], d.opposite[j], mo);
      points_clutter += m.n_points();
      found_clutter += m.essential_found ? 1 : 0;
    }
    cpu_ms += thread_cpu_ms() - t0;
    ++n;
  }
  state.counters["points_gap1"] = points[0];
  state.counters["points_gap2"] = points[1];
  state.counters["lines_gap1"] = lines[0];
  state.counters["lines_gap2"] = lines[1];
  state.counters["points_clutter"] = points_clutter;
  state.counters["e_found_clutter"] = found_clutter;
  state.counters["cpu_ms"] = cpu_ms / std::max(1, n);
}

void BM_FivePoint(benchmark::State& state) {
  core::features::MatcherOptions mo;
  mo.essential.planar = false;
  mo.essential.max_iterations = static_cast<int>(state.range(0));
  run(state, mo);
}
BENCHMARK(BM_FivePoint)->ArgName("cap")->Arg(1000)->Arg(300)->Unit(benchmark::kMillisecond)->Iterations(1);

void BM_Planar(benchmark::State& state) {
  core::features::MatcherOptions mo;
  mo.essential.planar = true;
  mo.essential.general_refit = false;
  mo.essential.camera_pitch_rad = 0.18;
  mo.essential.planar_threshold_factor = static_cast<double>(state.range(0));
  run(state, mo);
}
BENCHMARK(BM_Planar)->ArgName("factor")->Arg(1)->Arg(3)->Arg(5)->Unit(benchmark::kMillisecond)->Iterations(1);

// The planar model seeding the refined general model (essential_ransac.hpp; the default).
void BM_PlanarGeneral(benchmark::State& state) {
  core::features::MatcherOptions mo;
  mo.essential.planar = true;  // the default, as general_refit
  mo.essential.planar_threshold_factor = static_cast<double>(state.range(0));
  mo.essential.camera_pitch_rad = static_cast<double>(state.range(1)) / 100.0;
  mo.essential.general_refit_max_iterations = static_cast<int>(state.range(2));
  run(state, mo);
}
BENCHMARK(BM_PlanarGeneral)
    ->ArgNames({"factor", "pitch_crad", "refit_cap"})
    ->Args({5, 0, 25})
    ->Args({5, 18, 25})
    ->Args({8, 0, 25})
    ->Args({5, 0, 10})
    ->Args({5, 0, 100})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

// The app's `fast` preset: planar + refit and a 9 px KLT window (the features were
// extracted with the default options: KLT pyramids are built on the fly for other windows).
void BM_Fast(benchmark::State& state) {
  core::features::MatcherOptions mo;
  mo.essential.planar = true;
  mo.klt.window_px = 9;
  mo.klt.prior_window_px = 9;
  run(state, mo);
}
BENCHMARK(BM_Fast)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

int main(int argc, char** argv) {
  return pepper::bench::run_real_benchmarks(argc, argv, "bench_essential_real", [] {
    data();
  });
}
