// The navigator with its two-view matches as concurrent tasks (issue 22: IN and INN matched at
// once, FrameMatcher::compute_two_views) gives the same commands and telemetry as with
// everything on one thread (cv::setNumThreads(1)), on real Pepper images: a map of route
// Edge_01's key images (shared/data/pepper_qut_tmap) replayed with each image twice followed by
// an image of the opposite route Edge_10 (the clutter frames of bench_navigator_real), so that
// switches, holds and RANSAC on outliers all occur.
#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/camera/intrinsics.hpp"
#include "core/features/image_features.hpp"
#include "core/navigator/navigator.hpp"

namespace pepper::core::navigator {
namespace {

namespace fs = std::filesystem;

std::vector<cv::Mat> route_images(const std::string& route) {
  const fs::path dir = fs::path(PEPPER_SHARED_DIR) / "data" / "pepper_qut_tmap" / route;
  std::vector<fs::path> files;
  if (fs::is_directory(dir))
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".png") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::vector<cv::Mat> out;
  for (const auto& f : files)
    out.push_back(features::to_gray(cv::imread(f.string(), cv::IMREAD_UNCHANGED)));
  return out;
}

struct Replay {
  memory::VisualMemory map;
  std::vector<Frame> frames;
};

// The first `keys` images of Edge_01 as the map; frames: each of them twice, then one Edge_10
// image (the opposite route walked backwards), 1/3 s apart.
Replay make_replay(int keys) {
  const std::vector<cv::Mat> route = route_images("Edge_01");
  const std::vector<cv::Mat> opposite = route_images("Edge_10");
  if (static_cast<int>(route.size()) < keys || opposite.size() != 13)
    throw std::runtime_error("pepper_qut_tmap Edge_01 / Edge_10 missing");
  Replay r;
  r.map.camera = CameraIntrinsics::pepper_top_vga().scaled_to(320, 240);
  const features::FeatureExtractor ex(r.map.camera);
  for (int k = 0; k < keys; ++k) {
    memory::KeyImage key;
    key.source_frame_index = k;
    key.t_ns = static_cast<int64_t>(k) * 1'000'000'000;
    key.features = ex.extract(route[static_cast<size_t>(k)], features::kPartsAll);
    r.map.key_images.push_back(std::move(key));
  }
  int64_t t_ns = 0;
  auto add = [&](const cv::Mat& gray) {
    Frame f;
    f.gray = gray;
    f.t_ns = t_ns;
    f.index = static_cast<int64_t>(r.frames.size());
    t_ns += 333'333'333;
    r.frames.push_back(f);
  };
  for (int i = 0; i < keys; ++i) {
    add(route[static_cast<size_t>(i)]);
    add(route[static_cast<size_t>(i)]);
    add(opposite[static_cast<size_t>(12 - (12 * i) / 21)]);
  }
  return r;
}

std::vector<StepResult> replay_with_threads(const Replay& r, int threads) {
  const int before = cv::getNumThreads();
  cv::setNumThreads(threads);
  std::vector<StepResult> out;
  try {
    Navigator nav(r.map);
    for (const Frame& f : r.frames) out.push_back(nav.step(f));
  } catch (...) {
    cv::setNumThreads(before);
    throw;
  }
  cv::setNumThreads(before);
  return out;
}

TEST(NavigatorTasks, ConcurrentMatchingGivesTheSameCommandsAsOneThread) {
  const Replay r = make_replay(12);
  const std::vector<StepResult> one = replay_with_threads(r, 1);
  const std::vector<StepResult> two = replay_with_threads(r, 2);
  ASSERT_EQ(one.size(), two.size());
  int switches = 0, navigating = 0;
  for (size_t i = 0; i < one.size(); ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    const Command& a = one[i].command;
    const Command& b = two[i].command;
    EXPECT_EQ(a.v_m_s, b.v_m_s);
    EXPECT_EQ(a.omega_rad_s, b.omega_rad_s);
    EXPECT_EQ(a.stop, b.stop);
    EXPECT_EQ(a.reason, b.reason);
    const Telemetry& ta = one[i].telemetry;
    const Telemetry& tb = two[i].telemetry;
    EXPECT_EQ(ta.state, tb.state);
    EXPECT_EQ(ta.ip, tb.ip);
    EXPECT_EQ(ta.in, tb.in);
    EXPECT_EQ(ta.inn, tb.inn);
    EXPECT_EQ(ta.switched, tb.switched);
    EXPECT_EQ(ta.n_lines_next, tb.n_lines_next);
    EXPECT_EQ(ta.n_points_next, tb.n_points_next);
    EXPECT_EQ(ta.n_lines_next_next, tb.n_lines_next_next);
    EXPECT_EQ(ta.n_points_next_next, tb.n_points_next_next);
    EXPECT_EQ(ta.n_prev, tb.n_prev);
    EXPECT_EQ(ta.n_three_view_next, tb.n_three_view_next);
    EXPECT_EQ(ta.n_three_view_prev, tb.n_three_view_prev);
    switches += ta.switched;
    navigating += ta.state == NavState::kNavigating;
  }
  // The replay exercises what it is meant to: the navigator follows the route.
  EXPECT_GE(switches, 5);
  EXPECT_GE(navigating, static_cast<int>(one.size()) / 2);
}

}  // namespace
}  // namespace pepper::core::navigator
