// The current frame's feature extraction on real Pepper images, part by part (issue 22): the
// navigator extracts lines + descriptors and the KLT pyramid on every frame, and ORB keypoints
// on every frame while the ORB fallback is on (features.matcher.orb_fallback_below_points > 0,
// the default). Images: route Edge_01 of shared/data/pepper_qut_tmap (22 top-camera images,
// 320x240; VGA: the same upscaled, as bench_navigator_real does). One iteration processes all
// 22 images; the time per image is reported as the counter cpu_per_image_ms (thread CPU).
//   BM_ExtractReal{Qvga,Vga}/part   part: 0 kPartsCurrentFrame | kPartWideBaseline (what a
//                                   navigator step extracts with the ORB fallback on),
//                                   1 kPartsCurrentFrame (lines, descriptors, pyramid),
//                                   2 lines + descriptors, 3 ORB alone, 4 the pyramid alone.
// Run: taskset -c 0 build/bench/bench_extract_real --benchmark_repetitions=3
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
#include <opencv2/imgproc.hpp>

#include "core/camera/intrinsics.hpp"
#include "core/features/image_features.hpp"
#include "real_data_dir.hpp"

namespace {
using namespace pepper;
namespace fs = std::filesystem;

fs::path data_dir() { return bench::real_data_dir(); }

std::vector<cv::Mat> load(const cv::Size& size) {
  std::vector<fs::path> files;
  const fs::path dir = data_dir() / "Edge_01";
  if (fs::is_directory(dir))
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".png") files.push_back(e.path());
  if (files.empty()) throw std::runtime_error("no PNG images in " + dir.string());
  std::sort(files.begin(), files.end());
  std::vector<cv::Mat> out;
  for (const auto& f : files) {
    cv::Mat g = core::features::to_gray(cv::imread(f.string(), cv::IMREAD_UNCHANGED));
    if (g.size() != size) cv::resize(g, g, size, 0, 0, cv::INTER_LINEAR);
    out.push_back(g);
  }
  return out;
}

double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

unsigned parts_of(int64_t which) {
  using namespace core::features;
  switch (which) {
    case 0: return kPartsCurrentFrame | kPartWideBaseline;
    case 1: return kPartsCurrentFrame;
    case 2: return kPartLines;
    case 3: return kPartWideBaseline;
    default: return kPartPyramid;
  }
}

void run(benchmark::State& state, const cv::Size& size) {
  const std::vector<cv::Mat> images = load(size);
  const core::features::FeatureExtractor ex(
      core::CameraIntrinsics::pepper_top_vga().scaled_to(size.width, size.height));
  const unsigned parts = parts_of(state.range(0));
  double cpu_ms = 0.0;
  int64_t n = 0;
  for (auto _ : state) {
    const double t0 = thread_cpu_ms();
    for (const cv::Mat& g : images) {
      const auto f = ex.extract(g, parts);
      benchmark::DoNotOptimize(f.lines.size());
    }
    cpu_ms += thread_cpu_ms() - t0;
    n += static_cast<int64_t>(images.size());
  }
  state.counters["cpu_per_image_ms"] = cpu_ms / static_cast<double>(std::max<int64_t>(1, n));
}

void BM_ExtractRealQvga(benchmark::State& state) { run(state, cv::Size(320, 240)); }
BENCHMARK(BM_ExtractRealQvga)->DenseRange(0, 4)->Unit(benchmark::kMillisecond);
void BM_ExtractRealVga(benchmark::State& state) { run(state, cv::Size(640, 480)); }
BENCHMARK(BM_ExtractRealVga)->DenseRange(0, 4)->Unit(benchmark::kMillisecond);

// The locally normalised grey image alone (klt_image with the default window), which the lines
// and the KLT pyramid of every current frame are computed on.
void normalise(benchmark::State& state, const cv::Size& size) {
  const std::vector<cv::Mat> images = load(size);
  const core::features::KltOptions klt;
  double cpu_ms = 0.0;
  int64_t n = 0;
  for (auto _ : state) {
    const double t0 = thread_cpu_ms();
    for (const cv::Mat& g : images) benchmark::DoNotOptimize(core::features::klt_image(g, klt).data);
    cpu_ms += thread_cpu_ms() - t0;
    n += static_cast<int64_t>(images.size());
  }
  state.counters["cpu_per_image_ms"] = cpu_ms / static_cast<double>(std::max<int64_t>(1, n));
}
void BM_NormaliseRealQvga(benchmark::State& state) { normalise(state, cv::Size(320, 240)); }
BENCHMARK(BM_NormaliseRealQvga)->Unit(benchmark::kMillisecond);
void BM_NormaliseRealVga(benchmark::State& state) { normalise(state, cv::Size(640, 480)); }
BENCHMARK(BM_NormaliseRealVga)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  return pepper::bench::run_real_benchmarks(argc, argv, "bench_extract_real", [] {
    load(cv::Size(320, 240));
  });
}
