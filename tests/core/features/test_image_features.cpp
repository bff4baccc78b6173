// Feature extraction: bad input, any size, textureless images, a drawn scene with known lines.
#include "core/features/image_features.hpp"

#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/features/matching.hpp"
#include "real_image_data.hpp"

namespace pepper::core::features {
namespace {

// A grey image with a few filled rectangles and a textured patch (deterministic).
cv::Mat drawn_scene(int w, int h, int dx_px = 0) {
  cv::Mat img(h, w, CV_8UC1, cv::Scalar(90));
  const double s = w / 640.0;
  auto R = [&](double x, double y, double rw, double rh, int grey) {
    cv::rectangle(img, cv::Rect(cv::Point(static_cast<int>(x * s) + dx_px, static_cast<int>(y * s)),
                                cv::Size(static_cast<int>(rw * s), static_cast<int>(rh * s))),
                  cv::Scalar(grey), cv::FILLED);
  };
  R(60, 60, 160, 300, 200);
  R(300, 100, 80, 250, 30);
  R(430, 40, 150, 120, 170);
  R(420, 300, 180, 120, 230);
  cv::RNG rng(7);
  // Small squares: FAST corners for KLT.
  for (int i = 0; i < 80; ++i) {
    const cv::Point c(static_cast<int>(rng.uniform(0.05, 0.9) * w) + dx_px, static_cast<int>(rng.uniform(0.05, 0.9) * h));
    const int side = std::max(3, static_cast<int>(rng.uniform(6, 14) * s));
    cv::rectangle(img, cv::Rect(c, cv::Size(side, side)), cv::Scalar(rng.uniform(0, 2) ? 10 : 250), cv::FILLED);
  }
  // A camera's blur (FAST finds few corners on perfectly crisp squares).
  cv::GaussianBlur(img, img, cv::Size(3, 3), 0.8);
  return img;
}

// Extraction on two threads (cv::getNumThreads() > 1: the lines beside the other parts, the
// descriptors in two halves) gives the very features of one thread, on a real Pepper image at
// QVGA and upscaled to VGA (over a hundred lines: both halves of the descriptors are used).
TEST(FeatureExtractor, TwoThreadsGiveTheFeaturesOfOne) {
  const std::string file = test_data::kPepper + "Edge_01/img_00014.png";
  const cv::Mat colour = cv::imread(file, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(colour.empty()) << "missing " << file;
  const cv::Mat qvga = to_gray(colour);
  cv::Mat vga;
  cv::resize(qvga, vga, cv::Size(640, 480), 0, 0, cv::INTER_LINEAR);
  const int threads_before = cv::getNumThreads();
  for (const cv::Mat& gray : {qvga, vga}) {
    const FeatureExtractor ex(test_data::pepper_qvga().scaled_to(gray.cols, gray.rows));
    for (const unsigned parts :
         {unsigned{kPartsAll}, unsigned{kPartsCurrentFrame}, unsigned{kPartLines}}) {
      SCOPED_TRACE(std::to_string(gray.cols) + " px, parts " + std::to_string(parts));
      cv::setNumThreads(1);
      const ImageFeatures one = ex.extract(gray, parts);
      cv::setNumThreads(2);
      const ImageFeatures two = ex.extract(gray, parts);
      cv::setNumThreads(threads_before);
      ASSERT_GT(one.lines.size(), gray.cols > 320 ? 60u : 20u);
      ASSERT_EQ(one.lines.size(), two.lines.size());
      for (size_t i = 0; i < one.lines.size(); ++i) {
        EXPECT_EQ(one.lines[i].p0_px, two.lines[i].p0_px);
        EXPECT_EQ(one.lines[i].p1_px, two.lines[i].p1_px);
      }
      ASSERT_EQ(one.line_descriptors.size(), two.line_descriptors.size());
      EXPECT_EQ(cv::norm(one.line_descriptors, two.line_descriptors, cv::NORM_INF), 0.0);
      EXPECT_EQ(one.corners_px, two.corners_px);
      ASSERT_EQ(one.keypoints.size(), two.keypoints.size());
      if (!one.keypoints.empty()) {
        EXPECT_EQ(cv::norm(one.keypoint_descriptors, two.keypoint_descriptors, cv::NORM_INF), 0.0);
      }
      ASSERT_EQ(one.klt_pyramid.size(), two.klt_pyramid.size());
      for (size_t l = 0; l < one.klt_pyramid.size(); ++l) {
        EXPECT_EQ(cv::norm(one.klt_pyramid[l], two.klt_pyramid[l], cv::NORM_INF), 0.0);
      }
    }
  }
}

TEST(FeatureExtractor, RejectsEmptyAndNonGreyImages) {
  const FeatureExtractor ex;
  EXPECT_THROW(ex.extract(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(ex.extract(cv::Mat(48, 64, CV_8UC3, cv::Scalar(1, 2, 3))), std::invalid_argument);
  EXPECT_THROW(ex.extract(cv::Mat(48, 64, CV_32FC1, cv::Scalar(1))), std::invalid_argument);
  try {
    ex.extract(cv::Mat(48, 64, CV_8UC3));
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("CV_8UC1"), std::string::npos);
  }
}

TEST(FeatureExtractor, InvalidOptionsNameTheField) {
  FeatureExtractorOptions o;
  o.max_lines = -1;
  o.klt.window_px = 4;
  try {
    FeatureExtractor ex(CameraIntrinsics::pepper_top_vga(), o);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_lines"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("klt.window_px"), std::string::npos);
  }
}

TEST(FeatureExtractor, TexturelessImagesGiveEmptyFeaturesAndZeroCounts) {
  const FeatureExtractor ex;
  for (const cv::Size size : {cv::Size(640, 480), cv::Size(1, 1), cv::Size(7, 3), cv::Size(33, 500)}) {
    const cv::Mat flat(size, CV_8UC1, cv::Scalar(128));
    const ImageFeatures f = ex.extract(flat);
    EXPECT_TRUE(f.lines.empty()) << size;
    EXPECT_TRUE(f.corners_px.empty()) << size;
    EXPECT_TRUE(f.keypoints.empty()) << size;
    EXPECT_EQ(f.line_descriptors.rows, 0);
    const TwoViewMatches m = match_two_view(f, f);
    EXPECT_EQ(m.total(), 0);
    FrameMatcher fm(f);
    EXPECT_EQ(fm.three_view(1, f, 2, f).total(), 0);
    EXPECT_EQ(fm.wide_baseline(1, f).total(), 0);
  }
}

TEST(FeatureExtractor, AnySizeWorksAndIntrinsicsAreScaled) {
  const FeatureExtractor ex;
  for (const cv::Size size : {cv::Size(320, 240), cv::Size(640, 480), cv::Size(800, 300), cv::Size(64, 64)}) {
    const ImageFeatures f = ex.extract(drawn_scene(size.width, size.height));
    EXPECT_EQ(f.image_size, size);
    EXPECT_EQ(f.intrinsics.width_px, size.width);
    EXPECT_EQ(f.line_descriptors.rows, static_cast<int>(f.lines.size()));
    EXPECT_EQ(f.keypoint_descriptors.rows, static_cast<int>(f.keypoints.size()));
    if (size.width >= 320) {
      EXPECT_GE(f.lines.size(), 8u) << size;
      EXPECT_GE(f.corners_px.size(), 20u) << size;
    }
    for (const auto& l : f.lines) {
      // Stored normalised endpoints and (rho, theta) agree with the pixel endpoints.
      const cv::Point2d p0 = f.intrinsics.normalize(cv::Point2d(l.p0_px));
      EXPECT_NEAR(p0.x, l.p0_norm.x, 1e-9);
      EXPECT_NEAR(p0.x * std::cos(l.line.theta_rad) + p0.y * std::sin(l.line.theta_rad), l.line.rho, 1e-6);
      EXPECT_GT(l.line.theta_rad, -M_PI_2);
      EXPECT_LE(l.line.theta_rad, M_PI_2);
    }
  }
  EXPECT_EQ(ex.extract(drawn_scene(320, 240)).intrinsics, CameraIntrinsics::pepper_top_vga().scaled_to(320, 240));
}

TEST(FeatureExtractor, FindsTheDrawnVerticalEdges) {
  const ImageFeatures f = FeatureExtractor().extract(drawn_scene(640, 480));
  // Left edge of the first rectangle: x = 60 (the edge lies between 59 and 60), y 60..360.
  bool found = false;
  for (const auto& l : f.lines) {
    const bool vertical = std::abs(l.line.theta_rad) < 0.02;
    if (vertical && std::abs(l.p0_px.x - 59.5) < 1.5 && l.length_px > 100) found = true;
  }
  EXPECT_TRUE(found);
}

TEST(FeatureExtractor, PartsSelectWhatIsComputed) {
  const FeatureExtractor ex;
  const ImageFeatures f = ex.extract(drawn_scene(640, 480), kPartsCurrentFrame);
  EXPECT_FALSE(f.lines.empty());
  EXPECT_TRUE(f.corners_px.empty());
  EXPECT_TRUE(f.keypoints.empty());
  EXPECT_FALSE(f.klt_pyramid.empty());
}

// The normalised image's definition, written out per pixel (image_features.hpp): klt_image
// computes it with SIMD lanes and must give every pixel the same value.
cv::Mat normalised_by_formula(const cv::Mat& gray, int window_px) {
  cv::Mat f, mean, mean_sq;
  gray.convertTo(f, CV_32F);
  cv::boxFilter(f, mean, CV_32F, cv::Size(window_px, window_px), cv::Point(-1, -1), true,
                cv::BORDER_REFLECT);
  cv::boxFilter(f.mul(f), mean_sq, CV_32F, cv::Size(window_px, window_px), cv::Point(-1, -1), true,
                cv::BORDER_REFLECT);
  cv::Mat out(gray.size(), CV_8UC1);
  for (int y = 0; y < gray.rows; ++y)
    for (int x = 0; x < gray.cols; ++x) {
      const float m = mean.at<float>(y, x);
      const float sigma = std::max(std::sqrt(std::max(mean_sq.at<float>(y, x) - m * m, 0.0f)), 6.0f);
      out.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(128.0f + 32.0f * (f.at<float>(y, x) - m) / sigma);
    }
  return out;
}

TEST(NormalisedImage, SimdMatchesTheScalarFormula) {
  const KltOptions klt;
  cv::RNG rng(11);
  // Odd widths exercise the scalar tail; noise, hard edges and flat areas (sigma floor) and
  // saturation (isolated extreme pixels in a flat area) exercise every branch of the formula.
  for (const cv::Size size : {cv::Size(320, 240), cv::Size(640, 480), cv::Size(97, 61), cv::Size(33, 17)}) {
    cv::Mat g = drawn_scene(size.width, size.height);
    cv::Mat noise(size, CV_8UC1);
    rng.fill(noise, cv::RNG::UNIFORM, 0, 40);
    g(cv::Rect(0, 0, size.width / 2, size.height)) += noise(cv::Rect(0, 0, size.width / 2, size.height));
    for (int i = 0; i < 20; ++i)
      g.at<uint8_t>(rng.uniform(0, size.height), rng.uniform(0, size.width)) = rng.uniform(0, 2) ? 0 : 255;
    const cv::Mat simd = klt_image(g, klt);
    const cv::Mat ref = normalised_by_formula(g, klt.normalise_window_px(size.width));
    ASSERT_EQ(simd.type(), CV_8UC1);
    EXPECT_EQ(cv::countNonZero(simd != ref), 0) << size;
    if (size.width < 97) continue;  // too few pixels to be sure of reaching both bounds
    double lo = 0, hi = 0;
    cv::minMaxLoc(ref, &lo, &hi);
    EXPECT_EQ(lo, 0) << "the test image must reach the lower saturation, at " << size;
    EXPECT_EQ(hi, 255) << "the test image must reach the upper saturation, at " << size;
  }
}

TEST(NormalisedImage, ExtractBuildsThePyramidOnTheSameImage) {
  const FeatureExtractor ex;
  const cv::Mat g = drawn_scene(640, 480);
  ImageFeatures once = ex.extract(g, kPartsCurrentFrame);
  ImageFeatures separate = once;
  build_klt_pyramid(separate, FeatureExtractorOptions{}.klt, false);
  ASSERT_EQ(once.klt_pyramid.size(), separate.klt_pyramid.size());
  for (size_t i = 0; i < once.klt_pyramid.size(); ++i)
    EXPECT_EQ(cv::norm(once.klt_pyramid[i], separate.klt_pyramid[i], cv::NORM_INF), 0.0) << i;
}

TEST(Matching, ShiftedImageMatchesLinesAndPoints) {
  const FeatureExtractor ex;
  const ImageFeatures a = ex.extract(drawn_scene(640, 480));
  const ImageFeatures b = ex.extract(drawn_scene(640, 480, 6));
  const TwoViewMatches m = match_two_view(a, b);
  EXPECT_GE(m.n_lines(), 6);
  EXPECT_GE(m.n_points(), 20);
  for (const auto& p : m.points) EXPECT_NEAR(p.b_px.x - p.a_px.x, 6.0, 1.0);
  for (const auto& l : m.lines) {
    EXPECT_NEAR(std::cos(a.lines[l.idx_a].line.theta_rad), std::cos(b.lines[l.idx_b].line.theta_rad), 0.05);
  }
  FrameMatcher fm(b);
  const TwoViewMatches& first = fm.two_view(7, a);
  const TwoViewMatches& again = fm.two_view(7, a);
  EXPECT_EQ(&first, &again);  // cached: computed once per frame
  EXPECT_EQ(first.total(), m.total());
}

// The per-stage timings (issue 22's telemetry split) grow with the work each stage did, and a
// cached result adds nothing.
TEST(Matching, FrameMatcherTimesEachStage) {
  const FeatureExtractor ex;
  ImageFeatures a = ex.extract(drawn_scene(640, 480));
  const ImageFeatures c = ex.extract(drawn_scene(640, 480, 3));
  const ImageFeatures b = ex.extract(drawn_scene(640, 480, 6));
  FrameMatcher fm(c);
  EXPECT_EQ(fm.timings().klt_ms, 0.0);
  fm.two_view(1, a);
  const MatchTimings after_one = fm.timings();
  EXPECT_GT(after_one.lines_ms, 0.0);
  EXPECT_GT(after_one.klt_ms, 0.0);
  EXPECT_GT(after_one.essential_ms, 0.0);
  EXPECT_EQ(after_one.three_view_ms, 0.0);
  fm.two_view(1, a);  // cached
  EXPECT_EQ(fm.timings().klt_ms, after_one.klt_ms);
  fm.three_view(1, a, 2, b);  // computes two_view(2, b), then the three views
  EXPECT_GT(fm.timings().klt_ms, after_one.klt_ms);
  EXPECT_GT(fm.timings().three_view_ms, 0.0);
  EXPECT_EQ(fm.timings().wide_baseline_ms, 0.0);
}

}  // namespace
}  // namespace pepper::core::features
