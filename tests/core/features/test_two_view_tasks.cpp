// FrameMatcher::compute_two_views (issue 22): the two-view results of several key images
// computed as concurrent tasks must be the very results of two_view() called for each in turn,
// on real Pepper images (shared/data/pepper_qut_tmap) with KLT priors, for a frame on the route
// and a frame of the opposite route (few true matches, RANSAC on outliers); ids already computed
// are kept, and errors surface as exceptions after the other tasks are done.
#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/features/image_features.hpp"
#include "core/features/matching.hpp"
#include "real_image_data.hpp"

namespace pepper::core::features {
namespace {

namespace fs = std::filesystem;

// OpenCV's thread count for one scope (compute_two_views runs its tasks concurrently only when
// it is above 1).
class CvThreads {
 public:
  explicit CvThreads(int n) : before_(cv::getNumThreads()) { cv::setNumThreads(n); }
  ~CvThreads() { cv::setNumThreads(before_); }
  CvThreads(const CvThreads&) = delete;
  CvThreads& operator=(const CvThreads&) = delete;

 private:
  int before_;
};

// The route's PNGs in name order, grey.
std::vector<cv::Mat> route_images(const std::string& route) {
  const fs::path dir = fs::path(test_data::kPepper) / route;
  std::vector<fs::path> files;
  if (fs::is_directory(dir))
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".png") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::vector<cv::Mat> out;
  for (const auto& f : files) out.push_back(to_gray(cv::imread(f.string(), cv::IMREAD_UNCHANGED)));
  return out;
}

struct Scene {
  std::vector<ImageFeatures> keys;  // Edge_01 images 0..5, all parts
  ImageFeatures previous;           // Edge_01 image 2 (the priors' frame)
  ImageFeatures on_route;           // Edge_01 image 3
  ImageFeatures clutter;            // Edge_10 image 12 (the opposite direction)
};

const Scene& scene() {
  static const Scene s = [] {
    const std::vector<cv::Mat> route = route_images("Edge_01");
    const std::vector<cv::Mat> opposite = route_images("Edge_10");
    if (route.size() < 6 || opposite.size() < 13)
      throw std::runtime_error("pepper_qut_tmap Edge_01 / Edge_10 missing under " +
                               test_data::kPepper);
    const FeatureExtractor ex(test_data::pepper_qvga());
    Scene r;
    for (int i = 0; i < 6; ++i) {
      r.keys.push_back(ex.extract(route[static_cast<size_t>(i)], kPartsAll));
      build_klt_pyramid(r.keys.back(), MatcherOptions{}.klt);
    }
    r.previous = ex.extract(route[2], kPartsCurrentFrame);
    r.on_route = ex.extract(route[3], kPartsCurrentFrame);
    r.clutter = ex.extract(opposite[12], kPartsCurrentFrame);
    return r;
  }();
  return s;
}

void expect_same(const TwoViewMatches& a, const TwoViewMatches& b, const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_EQ(a.line_candidates, b.line_candidates);
  EXPECT_EQ(a.point_candidates, b.point_candidates);
  EXPECT_EQ(a.essential_found, b.essential_found);
  EXPECT_EQ(a.points_from_orb, b.points_from_orb);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_EQ(a.E_b_a(i, j), b.E_b_a(i, j));
  ASSERT_EQ(a.lines.size(), b.lines.size());
  for (size_t i = 0; i < a.lines.size(); ++i) {
    EXPECT_EQ(a.lines[i].idx_a, b.lines[i].idx_a);
    EXPECT_EQ(a.lines[i].idx_b, b.lines[i].idx_b);
    EXPECT_EQ(a.lines[i].distance, b.lines[i].distance);
  }
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i].idx_a, b.points[i].idx_a);
    EXPECT_EQ(a.points[i].b_px, b.points[i].b_px);
    EXPECT_EQ(a.points[i].b_norm, b.points[i].b_norm);
  }
}

// Priors for every key image: its verified points in the previous frame.
std::vector<std::vector<PointMatch>> priors() {
  const Scene& s = scene();
  std::vector<std::vector<PointMatch>> out;
  for (const ImageFeatures& k : s.keys) out.push_back(match_two_view(k, s.previous).points);
  return out;
}

TEST(TwoViewTasks, ConcurrentResultsAreTheSequentialOnes) {
  const Scene& s = scene();
  const auto prior = priors();
  for (const ImageFeatures* current : {&s.on_route, &s.clutter}) {
    const std::string name = current == &s.on_route ? "on route" : "clutter";
    FrameMatcher one_by_one(*current);
    FrameMatcher tasks(*current);
    for (size_t k = 0; k < s.keys.size(); ++k) {
      one_by_one.set_klt_prior(static_cast<int64_t>(k), prior[k]);
      tasks.set_klt_prior(static_cast<int64_t>(k), prior[k]);
    }
    std::vector<FrameMatcher::KeyRef> refs;
    for (size_t k = 0; k < s.keys.size(); ++k) refs.push_back({static_cast<int64_t>(k), &s.keys[k]});
    {
      const CvThreads threads(2);
      ASSERT_GE(cv::getNumThreads(), 2);
      tasks.compute_two_views(refs);
    }
    int verified = 0;
    for (size_t k = 0; k < s.keys.size(); ++k) {
      const TwoViewMatches* concurrent = tasks.computed_two_view(static_cast<int64_t>(k));
      ASSERT_NE(concurrent, nullptr) << name << " key " << k;
      expect_same(one_by_one.two_view(static_cast<int64_t>(k), s.keys[k]), *concurrent,
                  name + " key " + std::to_string(k));
      verified += concurrent->n_points();
    }
    // The comparison means something: the route frame verifies points with its neighbours.
    if (current == &s.on_route) {
      EXPECT_GT(verified, 100);
    }
    // The telemetry split still adds up the tasks' stages.
    EXPECT_GT(tasks.timings().klt_ms, 0.0);
    EXPECT_GT(tasks.timings().essential_ms, 0.0);
  }
}

TEST(TwoViewTasks, ComputedIdsAreKeptAndRepeatedIdsComputedOnce) {
  const Scene& s = scene();
  const CvThreads threads(2);
  FrameMatcher fm(s.on_route);
  const TwoViewMatches& first = fm.two_view(1, s.keys[1]);
  const FrameMatcher::KeyRef refs[] = {{1, &s.keys[1]}, {2, &s.keys[2]}, {2, &s.keys[2]}};
  fm.compute_two_views(refs);
  EXPECT_EQ(fm.computed_two_view(1), &first);  // not recomputed, not moved
  ASSERT_NE(fm.computed_two_view(2), nullptr);
  expect_same(FrameMatcher(s.on_route).two_view(2, s.keys[2]), *fm.computed_two_view(2), "key 2");
}

TEST(TwoViewTasks, SpeculativeResultsAreHeldBackUntilAskedFor) {
  const Scene& s = scene();
  const FrameMatcher::KeyRef refs[] = {{1, &s.keys[1]}, {2, &s.keys[2], true}};
  {  // one thread: the speculative task is not computed at all
    const CvThreads threads(1);
    FrameMatcher fm(s.on_route);
    fm.compute_two_views(refs);
    EXPECT_NE(fm.computed_two_view(1), nullptr);
    EXPECT_EQ(fm.computed_two_view(2), nullptr);
    const double essential_ms = fm.timings().essential_ms;
    fm.two_view(2, s.keys[2]);
    EXPECT_GT(fm.timings().essential_ms, essential_ms);  // computed only now
  }
  const CvThreads threads(2);
  FrameMatcher fm(s.on_route);
  fm.compute_two_views(refs);
  EXPECT_NE(fm.computed_two_view(1), nullptr);
  EXPECT_EQ(fm.computed_two_view(2), nullptr);  // computed, held back
  const double essential_ms = fm.timings().essential_ms;
  const TwoViewMatches& asked = fm.two_view(2, s.keys[2]);
  EXPECT_EQ(fm.timings().essential_ms, essential_ms);  // not computed again
  EXPECT_EQ(fm.computed_two_view(2), &asked);
  expect_same(FrameMatcher(s.on_route).two_view(2, s.keys[2]), asked, "key 2");
  // Asked for by a later non-speculative mention.
  FrameMatcher again(s.on_route);
  again.compute_two_views(refs);
  const FrameMatcher::KeyRef now[] = {{2, &s.keys[2]}};
  again.compute_two_views(now);
  ASSERT_NE(again.computed_two_view(2), nullptr);
  expect_same(asked, *again.computed_two_view(2), "key 2 asked later");
}

TEST(TwoViewTasks, ErrorsAreThrownAfterTheOtherTasksAreDone) {
  const Scene& s = scene();
  const CvThreads threads(2);
  FrameMatcher fm(s.on_route);
  const FrameMatcher::KeyRef null_key[] = {{1, &s.keys[1]}, {2, nullptr}};
  EXPECT_THROW(fm.compute_two_views(null_key), std::invalid_argument);
  EXPECT_EQ(fm.computed_two_view(1), nullptr);  // refused before any work
  ImageFeatures no_image = s.keys[2];
  no_image.gray = cv::Mat();  // match_two_view refuses it (inside its task)
  const FrameMatcher::KeyRef bad_task[] = {{1, &s.keys[1]}, {2, &no_image}, {3, &s.keys[3]}};
  EXPECT_THROW(fm.compute_two_views(bad_task), std::invalid_argument);
  EXPECT_NE(fm.computed_two_view(1), nullptr);
  EXPECT_EQ(fm.computed_two_view(2), nullptr);
  EXPECT_NE(fm.computed_two_view(3), nullptr);
  // A speculative task's error waits until its key is asked for, as without the speculation.
  FrameMatcher held(s.on_route);
  const FrameMatcher::KeyRef speculative_bad[] = {{1, &s.keys[1]}, {2, &no_image, true}};
  EXPECT_NO_THROW(held.compute_two_views(speculative_bad));
  EXPECT_NE(held.computed_two_view(1), nullptr);
  EXPECT_THROW(held.two_view(2, no_image), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::features
