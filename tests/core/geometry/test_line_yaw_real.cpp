// The yaw from matched lines on Pepper's own key images (shared/data/pepper_qut_tmap, taken on a
// real Pepper, not tuned on): it must agree with the yaw of the verified points' essential matrix
// (an independent estimate from the other feature kind) for neighbouring and next-but-one key
// images of both routes.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "core/features/image_features.hpp"
#include "core/features/matching.hpp"
#include "core/features/real_image_data.hpp"
#include "core/geometry/essential_ransac.hpp"
#include "core/geometry/line_yaw.hpp"

namespace pepper::core::geometry {
namespace {

using features::test_data::kPepper;

std::vector<std::string> route(const std::string& edge) {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(kPepper + edge)) files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

features::ImageFeatures load(const features::FeatureExtractor& ex, const std::string& path) {
  const cv::Mat img = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (img.empty()) throw std::runtime_error("cannot read " + path);
  return ex.extract(features::to_gray(img));
}

TEST(LineYawReal, AgreesWithThePointsOnPepperKeyImages) {
  if (!std::filesystem::exists(kPepper + "Edge_01")) GTEST_SKIP() << "shared data missing";
  const features::FeatureExtractor ex;
  std::vector<double> diffs;
  int pairs = 0, with_points = 0;
  for (const std::string edge : {"Edge_01", "Edge_10"}) {
    const auto files = route(edge);
    std::vector<features::ImageFeatures> f;
    for (const auto& p : files) f.push_back(load(ex, p));
    for (size_t i = 0; i < f.size(); ++i) {
      for (size_t gap : {1u, 2u}) {
        if (i + gap >= f.size()) continue;
        const features::TwoViewMatches m = features::match_two_view(f[i], f[i + gap]);
        if (!m.essential_found || m.n_points() < 20) continue;
        ++with_points;
        std::vector<cv::Point2d> a, b;
        for (const auto& p : m.points) {
          a.push_back(p.a_norm);
          b.push_back(p.b_norm);
        }
        const RelativePose rp = recover_relative_pose(m.E_b_a, a, b);
        const double yaw_points = std::atan2(rp.R_b_a(0, 2), rp.R_b_a(2, 2));
        std::vector<std::pair<NormSegment, NormSegment>> lines;
        for (const auto& lm : m.lines) {
          const auto& la = f[i].lines[static_cast<size_t>(lm.idx_a)];
          const auto& lb = f[i + gap].lines[static_cast<size_t>(lm.idx_b)];
          lines.push_back({{la.p0_norm, la.p1_norm}, {lb.p0_norm, lb.p1_norm}});
        }
        const auto yaw_lines = estimate_line_yaw(lines, 0.0);
        ++pairs;
        if (!yaw_lines) continue;
        diffs.push_back(std::abs(yaw_lines->yaw_rad - yaw_points));
      }
    }
  }
  ASSERT_GT(pairs, 20);
  ASSERT_FALSE(diffs.empty());
  std::sort(diffs.begin(), diffs.end());
  const double median = diffs[diffs.size() / 2], p90 = diffs[diffs.size() * 9 / 10];
  std::cout << "line yaw on " << diffs.size() << " of " << pairs << " pairs; |lines - points|: median "
            << median << " rad, p90 " << p90 << ", max " << diffs.back() << "\n";
  // Measured when written: 55 of 64 pairs, median 0.011 rad, p90 0.036, max 0.12 (the points'
  // yaw errs too). Counting agreeing lines instead of weighing them by information gave a p90 of
  // 0.21 and a max of 1.07 on the same pairs.
  EXPECT_GE(diffs.size(), static_cast<size_t>(pairs) * 3 / 4);
  EXPECT_LT(median, 0.015);
  EXPECT_LT(p90, 0.05);
}

}  // namespace
}  // namespace pepper::core::geometry
