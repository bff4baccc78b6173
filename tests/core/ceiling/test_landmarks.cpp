// Ceiling landmarks: tracking a known image motion, the sign of the angle, the seen mask, and
// failures as values or errors.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/ceiling/landmarks.hpp"

namespace pepper::core::ceiling {
namespace {

// A textured canonical image: smoothed noise with a few bright blobs (lamps).
cv::Mat texture(int seed) {
  cv::Mat noise(300, 300, CV_8UC1);
  cv::RNG rng(static_cast<uint64_t>(seed));
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 2.0);
  cv::normalize(noise, noise, 0, 255, cv::NORM_MINMAX);
  for (int i = 0; i < 12; ++i)
    cv::circle(noise, cv::Point(rng.uniform(20, 280), rng.uniform(20, 280)), 5, cv::Scalar(255),
               cv::FILLED);
  return noise;
}

TEST(CeilingLandmarks, TracksAKnownTranslationAndRotation) {
  const cv::Mat a = texture(3);
  const CeilingLandmarks la = extract_landmarks(a, cv::Mat());
  ASSERT_GT(la.keypoints.size(), 100u);
  cv::Mat b;
  cv::warpAffine(a, b, cv::Matx23d(1, 0, 7.0, 0, 1, -4.0), a.size(), cv::INTER_LINEAR,
                 cv::BORDER_REFLECT);
  const CeilingMotion shifted = track_landmarks(la, extract_landmarks(b, cv::Mat()));
  ASSERT_TRUE(shifted.found);
  EXPECT_NEAR(shifted.A_b_a(0, 2), 7.0, 0.5);
  EXPECT_NEAR(shifted.A_b_a(1, 2), -4.0, 0.5);
  EXPECT_NEAR(shifted.angle_rad, 0.0, 0.005);
  EXPECT_NEAR(shifted.scale, 1.0, 0.005);
  // getRotationMatrix2D's positive angle turns the content counter-clockwise on the screen:
  // landmarks.hpp's convention makes that a negative angle_rad.
  cv::Mat c;
  cv::warpAffine(a, c, cv::getRotationMatrix2D(cv::Point2f(150, 150), 6.0, 1.0), a.size(),
                 cv::INTER_LINEAR, cv::BORDER_REFLECT);
  const CeilingMotion turned = track_landmarks(la, extract_landmarks(c, cv::Mat()));
  ASSERT_TRUE(turned.found);
  EXPECT_NEAR(turned.angle_rad, -6.0 * M_PI / 180.0, 0.005);
}

TEST(CeilingLandmarks, StayInsideTheSeenMaskAwayFromItsBorder) {
  const cv::Mat a = texture(5);
  cv::Mat seen(a.size(), CV_8UC1, cv::Scalar(0));
  cv::rectangle(seen, cv::Rect(100, 50, 150, 200), cv::Scalar(255), cv::FILLED);
  LandmarkOptions o;
  o.border_px = 10;
  const CeilingLandmarks l = extract_landmarks(a, seen, o);
  ASSERT_FALSE(l.keypoints.empty());
  for (const auto& k : l.keypoints) {
    EXPECT_GE(k.pt.x, 100 + 10 - 1);
    EXPECT_LE(k.pt.x, 250 - 10);
    EXPECT_GE(k.pt.y, 50 + 10 - 1);
    EXPECT_LE(k.pt.y, 250 - 10);
  }
}

TEST(CeilingLandmarks, NothingToTrackIsAValueBadInputIsAnError) {
  const cv::Mat flat(200, 200, CV_8UC1, cv::Scalar(128));
  const CeilingLandmarks none = extract_landmarks(flat, cv::Mat());
  EXPECT_TRUE(none.keypoints.empty());
  EXPECT_FALSE(track_landmarks(none, extract_landmarks(texture(1), cv::Mat())).found);
  // Two unrelated ceilings: no consensus.
  EXPECT_FALSE(track_landmarks(extract_landmarks(texture(1), cv::Mat()),
                               extract_landmarks(texture(2), cv::Mat()))
                   .found);
  LandmarkOptions bad;
  bad.max_landmarks = 0;
  EXPECT_THROW(extract_landmarks(flat, cv::Mat(), bad), std::invalid_argument);
  EXPECT_THROW(extract_landmarks(cv::Mat(10, 10, CV_32F), cv::Mat()), std::invalid_argument);
  EXPECT_THROW(extract_landmarks(flat, cv::Mat(5, 5, CV_8UC1)), std::invalid_argument);
  TrackOptions t;
  t.ransac_threshold_px = 0.0;
  EXPECT_THROW(track_landmarks(none, none, t), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::ceiling
