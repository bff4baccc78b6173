// Verified counts on real images nobody here made: a hand-held sequence of Debian's
// visp-images-data (mbt/cube, 640x480 grey) and Pepper's own key images (shared/data,
// pepper_qut_tmap, 320x240 colour). Counts must be non-zero for neighbours and fall with distance.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "core/features/image_features.hpp"
#include "core/features/matching.hpp"
#include "core/features/real_image_data.hpp"

namespace pepper::core::features {
namespace {

using test_data::cube_camera;
using test_data::kPepper;
using test_data::kVispCube;

ImageFeatures load(const FeatureExtractor& ex, const std::string& path) {
  const cv::Mat img = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (img.empty()) throw std::runtime_error("cannot read " + path);
  return ex.extract(to_gray(img));
}

std::string cube_frame(int i) {
  char name[32];
  std::snprintf(name, sizeof(name), "image%04d.pgm", i);
  return kVispCube + name;
}

class VispSequenceData : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(cube_frame(0))) GTEST_SKIP() << "visp-images-data not installed";
  }
};

TEST_F(VispSequenceData, NeighboursMatchAndCountsFallWithDistance) {
  const FeatureExtractor ex(cube_camera());
  const ImageFeatures f0 = load(ex, cube_frame(0));
  std::vector<int> totals;
  for (int gap : {1, 40, 160}) {
    const TwoViewMatches m = match_two_view(f0, load(ex, cube_frame(gap)));
    EXPECT_GT(m.n_lines(), 10) << "gap " << gap;
    EXPECT_GT(m.n_points(), 10) << "gap " << gap;
    totals.push_back(m.total());
  }
  // Measured: 154, 123, 81.
  EXPECT_GT(totals[0], totals[1]);
  EXPECT_GT(totals[1], totals[2]);
}

TEST_F(VispSequenceData, ConsecutiveFramesVerifyOverThreeViews) {
  const FeatureExtractor ex(cube_camera());
  const ImageFeatures f0 = load(ex, cube_frame(0));
  const ImageFeatures f1 = load(ex, cube_frame(1));
  const ImageFeatures f2 = load(ex, cube_frame(2));
  FrameMatcher fm(f1);  // hub: the middle frame, as the navigator's current image
  const ThreeViewMatches& t = fm.three_view(0, f0, 2, f2);
  EXPECT_GT(t.n_lines(), 10);
  EXPECT_GT(t.n_points(), 10);
  EXPECT_LE(t.n_lines(), t.line_candidates);
  // Wide baseline also finds the neighbour (f1 extracted with ORB keypoints).
  EXPECT_GT(fm.wide_baseline(0, f0).n_points(), 20);
}

// The light halved between a key image and the current one. On locally normalised grey levels
// (klt.normalise_window_frac, the default) KLT keeps its points, so the ORB fallback has nothing
// to do. On raw grey levels (normalise_window_frac = 0) KLT's patch error rejects most tracks and ORB (intensity
// comparisons within a patch) keeps matching: the fallback's mechanism is checked there. With
// orb_fallback_below_points above KLT's count and at most ORB's, FrameMatcher::
// two_view_for_control returns the ORB points (flagged: their idx_a are keypoints) and
// two_view() still KLT's; above ORB's count too (too few either way), KLT's; below KLT's, KLT's.
// Measured (frames 0 and 1 of mbt/cube, frame 1 x0.5): raw KLT 0 points, ORB 165; normalised
// KLT 182 (of 190 in the same light).
TEST_F(VispSequenceData, NormalisedKltKeepsPointsWhenTheLightHalves) {
  const FeatureExtractorOptions normalised_ex;
  const MatcherOptions normalised;
  ASSERT_GT(normalised.klt.normalise_window_frac, 0.0);
  const FeatureExtractor ex(cube_camera(), normalised_ex);
  const ImageFeatures key = load(ex, cube_frame(0));
  cv::Mat dim;
  to_gray(cv::imread(cube_frame(1), cv::IMREAD_UNCHANGED)).convertTo(dim, CV_8U, 0.5);
  const TwoViewMatches dimmed = match_two_view(key, ex.extract(dim), normalised);
  const TwoViewMatches same = match_two_view(key, load(ex, cube_frame(1)), normalised);
  EXPECT_GE(dimmed.n_points(), 0.8 * same.n_points());
  MatcherOptions raw;
  raw.klt.normalise_window_frac = 0;
  FeatureExtractorOptions raw_ex;
  raw_ex.klt.normalise_window_frac = 0;
  const FeatureExtractor ex_raw(cube_camera(), raw_ex);
  EXPECT_LT(match_two_view(load(ex_raw, cube_frame(0)), ex_raw.extract(dim), raw).n_points(),
            0.2 * same.n_points());
}

TEST_F(VispSequenceData, OrbFallbackKeepsPointsWhenTheLightHalves) {
  FeatureExtractorOptions raw;
  raw.klt.normalise_window_frac = 0;  // raw grey levels: KLT loses the points (see above)
  const FeatureExtractor ex(cube_camera(), raw);
  const ImageFeatures key = load(ex, cube_frame(0));
  cv::Mat dim;
  to_gray(cv::imread(cube_frame(1), cv::IMREAD_UNCHANGED)).convertTo(dim, CV_8U, 0.5);
  const ImageFeatures current = ex.extract(dim);
  const ImageFeatures bright = load(ex, cube_frame(1));

  MatcherOptions o;
  o.klt.normalise_window_frac = 0;
  FrameMatcher klt_only(current, o);
  const TwoViewMatches& k = klt_only.two_view(0, key);
  o.orb_fallback_below_points = 100;
  FrameMatcher with_orb(current, o);
  const TwoViewMatches& w = with_orb.two_view_for_control(0, key);
  EXPECT_EQ(with_orb.two_view(0, key).n_points(), k.n_points());  // switching counts unchanged
  EXPECT_FALSE(k.points_from_orb);
  EXPECT_TRUE(w.points_from_orb);
  EXPECT_GT(w.n_points(), 2 * k.n_points());
  EXPECT_EQ(w.n_lines(), k.n_lines());  // lines are not affected
  for (const PointMatch& p : w.points) {
    ASSERT_GE(p.idx_a, 0);
    ASSERT_LT(p.idx_a, static_cast<int>(key.keypoints.size()));
  }
  // More than ORB has: ORB's few are no better than KLT's few, KLT's stay.
  o.orb_fallback_below_points = 1000;
  FrameMatcher too_few(current, o);
  EXPECT_FALSE(too_few.two_view_for_control(0, key).points_from_orb);
  EXPECT_EQ(too_few.two_view_for_control(0, key).n_points(), k.n_points());
  // Same light: KLT has plenty, the fallback (below 20) does not start.
  o.orb_fallback_below_points = 20;
  FrameMatcher same_light(bright, o);
  const TwoViewMatches& b = same_light.two_view_for_control(0, key);
  EXPECT_GE(b.n_points(), 20);
  EXPECT_FALSE(b.points_from_orb);
}

// The current frame's ORB keypoints extracted only when the fallback needs them (FrameMatcher
// given the extractor): the same matches as with keypoints extracted up front, and no ORB on a
// frame where KLT verifies enough.
TEST_F(VispSequenceData, OrbKeypointsOfTheCurrentFrameOnlyWhenTheFallbackNeedsThem) {
  FeatureExtractorOptions raw;
  raw.klt.normalise_window_frac = 0;
  const FeatureExtractor ex(cube_camera(), raw);
  const ImageFeatures key = load(ex, cube_frame(0));
  cv::Mat dim;
  to_gray(cv::imread(cube_frame(1), cv::IMREAD_UNCHANGED)).convertTo(dim, CV_8U, 0.5);
  MatcherOptions o;
  o.klt.normalise_window_frac = 0;
  o.orb_fallback_below_points = 100;
  FrameMatcher eager(ex.extract(dim, kPartsCurrentFrame | kPartWideBaseline), o);
  FrameMatcher lazy(ex.extract(dim, kPartsCurrentFrame), o, &ex);
  EXPECT_TRUE(lazy.current().keypoints.empty());
  lazy.two_view(0, key);  // the switching counts need no ORB
  EXPECT_TRUE(lazy.current().keypoints.empty());
  const TwoViewMatches& e = eager.two_view_for_control(0, key);
  const TwoViewMatches& l = lazy.two_view_for_control(0, key);
  ASSERT_TRUE(e.points_from_orb);
  EXPECT_TRUE(l.points_from_orb);
  EXPECT_EQ(lazy.current().keypoints.size(), eager.current().keypoints.size());
  ASSERT_EQ(l.n_points(), e.n_points());
  for (size_t i = 0; i < e.points.size(); ++i) {
    EXPECT_EQ(l.points[i].idx_a, e.points[i].idx_a);
    EXPECT_EQ(l.points[i].idx_b, e.points[i].idx_b);
  }
  EXPECT_EQ(lazy.wide_baseline(0, key).n_points(), eager.wide_baseline(0, key).n_points());
  EXPECT_GT(lazy.timings().wide_baseline_ms, 0.0);  // the extraction counts there
  // Same light: KLT has plenty, the fallback (below 20) never asks for ORB.
  o.orb_fallback_below_points = 20;
  FrameMatcher bright(ex.extract(to_gray(cv::imread(cube_frame(1), cv::IMREAD_UNCHANGED)),
                                 kPartsCurrentFrame),
                      o, &ex);
  EXPECT_FALSE(bright.two_view_for_control(0, key).points_from_orb);
  EXPECT_TRUE(bright.current().keypoints.empty());
}

// Lines only / points only (METHOD.md): a kind switched off is not matched in two, three or
// wide-baseline views, and the other kind is matched as before except for what the switched-off
// kind would have lent it (lines: no epipolar check without points; points: no KLT start from
// the lines' shift, which frames 0 and 40 do not need).
TEST_F(VispSequenceData, SingleModalityMatchesOnlyItsKind) {
  const FeatureExtractor ex(cube_camera());
  const ImageFeatures f0 = load(ex, cube_frame(0));
  const ImageFeatures f1 = load(ex, cube_frame(1));
  const ImageFeatures f40 = load(ex, cube_frame(40));
  const TwoViewMatches both = match_two_view(f0, f40);
  MatcherOptions lines_only, points_only;
  lines_only.match_points = false;
  points_only.match_lines = false;
  const TwoViewMatches l = match_two_view(f0, f40, lines_only);
  const TwoViewMatches p = match_two_view(f0, f40, points_only);
  EXPECT_EQ(l.n_points(), 0);
  EXPECT_EQ(l.point_candidates, 0);
  EXPECT_FALSE(l.essential_found);
  EXPECT_GE(l.n_lines(), both.n_lines());  // no epipolar check can drop a line
  EXPECT_GT(l.n_lines(), 10);
  EXPECT_EQ(p.n_lines(), 0);
  EXPECT_EQ(p.line_candidates, 0);
  EXPECT_EQ(p.n_points(), both.n_points());

  FrameMatcher lm(f1, lines_only), pm(f1, points_only);
  EXPECT_EQ(lm.three_view(0, f0, 40, f40).n_points(), 0);
  EXPECT_GT(lm.three_view(0, f0, 40, f40).n_lines(), 0);
  EXPECT_EQ(pm.three_view(0, f0, 40, f40).n_lines(), 0);
  EXPECT_GT(pm.three_view(0, f0, 40, f40).n_points(), 0);
  EXPECT_EQ(lm.wide_baseline(0, f0).n_points(), 0);
  EXPECT_GT(lm.wide_baseline(0, f0).n_lines(), 0);
  EXPECT_EQ(pm.wide_baseline(0, f0).n_lines(), 0);
  EXPECT_GT(pm.wide_baseline(0, f0).n_points(), 20);

  MatcherOptions neither = lines_only;
  neither.match_lines = false;
  EXPECT_FALSE(neither.validate().empty());
  EXPECT_THROW(match_two_view(f0, f40, neither), std::invalid_argument);
}

class PepperQutData : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(kPepper + "Edge_01")) GTEST_SKIP() << "shared data missing";
  }
  static std::vector<std::string> route(const std::string& edge) {
    std::vector<std::string> files;
    for (const auto& e : std::filesystem::directory_iterator(kPepper + edge)) files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    return files;
  }
};

TEST_F(PepperQutData, NeighbouringKeyImagesMatchAndCountsFallOff) {
  const FeatureExtractor ex;  // Pepper VGA calibration, scaled to QVGA
  const auto files = route("Edge_01");
  ASSERT_GE(files.size(), 6u);
  const ImageFeatures f0 = load(ex, files[0]);
  EXPECT_EQ(f0.image_size, cv::Size(320, 240));
  std::vector<int> totals;
  for (size_t gap : {1u, 2u, 5u}) {
    const TwoViewMatches m = match_two_view(f0, load(ex, files[gap]));
    totals.push_back(m.total());
    if (gap == 1) {
      EXPECT_GT(m.n_lines(), 20);
      EXPECT_GT(m.n_points(), 30);
    }
  }
  // Measured: 188, 102, 27.
  EXPECT_GT(totals[0], totals[1]);
  EXPECT_GT(totals[1], totals[2]);
}

TEST_F(PepperQutData, ThreeConsecutiveKeyImagesShareVerifiedLinesAndPoints) {
  const FeatureExtractor ex;
  const auto files = route("Edge_01");
  const ImageFeatures a = load(ex, files[3]), b = load(ex, files[4]), c = load(ex, files[5]);
  FrameMatcher fm(b);
  const ThreeViewMatches& t = fm.three_view(3, a, 5, c);
  EXPECT_GT(t.n_lines(), 0);
  EXPECT_GT(t.n_points(), 0);
}

}  // namespace
}  // namespace pepper::core::features
