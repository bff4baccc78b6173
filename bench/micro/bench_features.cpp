// Perception hot paths on real VGA frames (visp-images-data mbt/cube, a hand-held 640x480
// sequence): (a) feature extraction of one frame, (b) everything the navigator does per new frame
// against two key images, plus a breakdown. OpenCV is forced to one thread (one-core figure).
//
// Run (one line): taskset -c 0 build-perception/bench/bench_features
//   --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <stdexcept>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/line_descriptor.hpp>

#include "core/features/band_descriptor.hpp"
#include "core/features/image_features.hpp"
#include "core/features/matching.hpp"

namespace {

using namespace pepper::core;
using namespace pepper::core::features;

cv::Mat frame(int i) {
  char name[96];
  std::snprintf(name, sizeof(name), "/usr/share/visp-images-data/ViSP-images/mbt/cube/image%04d.pgm", i);
  cv::Mat g = cv::imread(name, cv::IMREAD_GRAYSCALE);
  if (g.empty()) throw std::runtime_error(std::string("cannot read ") + name);
  return g;
}

struct Scene {
  FeatureExtractor ex;
  cv::Mat current_gray;
  ImageFeatures ip, in;  // key images, as loaded from a map (+ pyramids built at load)
  Scene() : current_gray(frame(8)) {
    ip = ex.extract(frame(0));
    in = ex.extract(frame(16));
  }
};

Scene& scene() {
  static Scene s;
  return s;
}

// (a) One frame, the parts the replay loop needs (lines + descriptors + KLT pyramid).
void BM_ExtractCurrentFrame(benchmark::State& state) {
  auto& s = scene();
  for (auto _ : state) benchmark::DoNotOptimize(s.ex.extract(s.current_gray, kPartsCurrentFrame));
}
BENCHMARK(BM_ExtractCurrentFrame)->Unit(benchmark::kMillisecond);

// (a') A key image: everything (lines, FAST corners, ORB, pyramid).
void BM_ExtractKeyImage(benchmark::State& state) {
  auto& s = scene();
  for (auto _ : state) benchmark::DoNotOptimize(s.ex.extract(s.current_gray, kPartsAll));
}
BENCHMARK(BM_ExtractKeyImage)->Unit(benchmark::kMillisecond);

// (b) Per new frame: extraction + n(IP,Ia), n(Ia,IN) (LBD matching, KLT of the key images'
// corners into Ia, essential RANSAC) + three-view lines/points over (IP, Ia, IN).
void BM_NavigatorFrame(benchmark::State& state) {
  auto& s = scene();
  int n = 0;
  for (auto _ : state) {
    FrameMatcher fm(s.ex.extract(s.current_gray, kPartsCurrentFrame));
    const ThreeViewMatches& t = fm.three_view(0, s.ip, 1, s.in);
    n = t.total() + fm.two_view(0, s.ip).total() + fm.two_view(1, s.in).total();
    benchmark::DoNotOptimize(n);
  }
  state.counters["verified"] = n;
}
BENCHMARK(BM_NavigatorFrame)->Unit(benchmark::kMillisecond);

// Breakdown.
void BM_LinesAndDescriptors(benchmark::State& state) {
  auto& s = scene();
  for (auto _ : state) benchmark::DoNotOptimize(s.ex.extract(s.current_gray, kPartLines));
}
BENCHMARK(BM_LinesAndDescriptors)->Unit(benchmark::kMillisecond);

void BM_KltPyramid(benchmark::State& state) {
  auto& s = scene();
  for (auto _ : state) benchmark::DoNotOptimize(s.ex.extract(s.current_gray, kPartPyramid));
}
BENCHMARK(BM_KltPyramid)->Unit(benchmark::kMillisecond);

void BM_TwoViewKeyToCurrent(benchmark::State& state) {
  auto& s = scene();
  const ImageFeatures cur = s.ex.extract(s.current_gray, kPartsCurrentFrame);
  for (auto _ : state) benchmark::DoNotOptimize(match_two_view(s.ip, cur));
}
BENCHMARK(BM_TwoViewKeyToCurrent)->Unit(benchmark::kMillisecond);

// The ORB fallback's matching (FrameMatcher::wide_baseline): a key image's ORB keypoints against
// the current frame's, all pairs by Hamming distance, then the essential RANSAC and the lines.
void BM_WideBaselineKeyToCurrent(benchmark::State& state) {
  auto& s = scene();
  const ImageFeatures cur = s.ex.extract(s.current_gray, kPartsCurrentFrame | kPartWideBaseline);
  int n = 0;
  for (auto _ : state) {
    const TwoViewMatches m = match_wide_baseline(s.ip, cur);
    n = m.n_points();
    benchmark::DoNotOptimize(m);
  }
  state.counters["points"] = n;
  state.counters["keypoints"] = static_cast<double>(cur.keypoints.size());
}
BENCHMARK(BM_WideBaselineKeyToCurrent)->Unit(benchmark::kMillisecond);

void BM_ThreeViewVerification(benchmark::State& state) {
  auto& s = scene();
  const ImageFeatures cur = s.ex.extract(s.current_gray, kPartsCurrentFrame);
  const TwoViewMatches a = match_two_view(s.ip, cur), b = match_two_view(s.in, cur);
  int n = 0;
  for (auto _ : state) {
    const ThreeViewMatches t = verify_three_view(s.ip, a, cur, s.in, b);
    n = t.n_lines();
    benchmark::DoNotOptimize(t);
  }
  state.counters["lines"] = n;
}
BENCHMARK(BM_ThreeViewVerification)->Unit(benchmark::kMillisecond);

void BM_BandDescriptorOurs(benchmark::State& state) {
  auto& s = scene();
  const ImageFeatures f = s.ex.extract(s.current_gray, kPartLines);
  std::vector<std::pair<cv::Point2f, cv::Point2f>> segs;
  for (const auto& l : f.lines) segs.emplace_back(l.p0_px, l.p1_px);
  for (auto _ : state) benchmark::DoNotOptimize(compute_band_descriptors(s.current_gray, segs));
  state.counters["lines"] = static_cast<double>(segs.size());
}
BENCHMARK(BM_BandDescriptorOurs)->Unit(benchmark::kMillisecond);

// OpenCV's LBD (BinaryDescriptor::compute) on its own detections, for comparison.
void BM_OpenCvLbdCompute(benchmark::State& state) {
  auto& s = scene();
  auto bd = cv::line_descriptor::BinaryDescriptor::createBinaryDescriptor();
  std::vector<cv::line_descriptor::KeyLine> kl;
  bd->detect(s.current_gray, kl);
  for (auto _ : state) {
    std::vector<cv::line_descriptor::KeyLine> k = kl;
    cv::Mat d;
    bd->compute(s.current_gray, k, d);
    benchmark::DoNotOptimize(d);
  }
  state.counters["lines"] = static_cast<double>(kl.size());
}
BENCHMARK(BM_OpenCvLbdCompute)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(1);  // honest one-core figures
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
