// Ceiling landmarks and their frame-to-frame tracking (see landmarks.hpp).
#include "core/ceiling/landmarks.hpp"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

namespace pepper::core::ceiling {

CeilingLandmarks extract_landmarks(const cv::Mat& canonical, const cv::Mat& seen,
                                   const LandmarkOptions& options) {
  if (options.max_landmarks <= 0)
    throw std::invalid_argument("extract_landmarks: max_landmarks must be > 0");
  if (options.fast_threshold <= 0)
    throw std::invalid_argument("extract_landmarks: fast_threshold must be > 0");
  if (options.border_px < 0)
    throw std::invalid_argument("extract_landmarks: border_px must be >= 0");
  if (options.subpixel_window_px < 0)
    throw std::invalid_argument("extract_landmarks: subpixel_window_px must be >= 0");
  if (canonical.empty() || canonical.type() != CV_8UC1)
    throw std::invalid_argument("extract_landmarks: the canonical image must be non-empty CV_8UC1");
  if (!seen.empty() && (seen.size() != canonical.size() || seen.type() != CV_8UC1))
    throw std::invalid_argument(
        "extract_landmarks: the seen mask must be CV_8UC1 of the image's size");
  cv::Mat mask = seen.empty() ? cv::Mat(canonical.size(), CV_8UC1, cv::Scalar(255)) : seen.clone();
  // The image border counts as unseen too: ORB's descriptor patch must lie on the ceiling.
  cv::rectangle(mask, cv::Rect(0, 0, mask.cols, mask.rows), cv::Scalar(0), 1);
  if (options.border_px > 0) {
    const int k = 2 * options.border_px + 1;
    cv::erode(mask, mask, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)));
  }
  // The canonical view has a fixed metric scale, so one pyramid level would do; a few levels
  // keep the corners of blurred far-away parts of the image.
  auto orb = cv::ORB::create(options.max_landmarks, 1.2f, 4, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31,
                             options.fast_threshold);
  CeilingLandmarks out;
  orb->detectAndCompute(canonical, mask, out.keypoints, out.descriptors);
  if (options.subpixel_window_px > 0 && !out.keypoints.empty()) {
    // ORB's corners are whole pixels of their pyramid level (up to 1.7 px at the fourth); the
    // mosaic chains positions from frame to frame, so their quantisation becomes drift
    // (docs/method/ceiling.md: 0.66 -> 0.40 % of the test tour at 120 px/m). A refined point
    // that moved more than kMaxRefineShiftPx was not a corner (a blob or an edge): it keeps
    // ORB's position.
    constexpr double kMaxRefineShiftPx = 1.5;
    std::vector<cv::Point2f> refined;
    refined.reserve(out.keypoints.size());
    for (const cv::KeyPoint& k : out.keypoints) refined.push_back(k.pt);
    const int w = options.subpixel_window_px;
    cv::cornerSubPix(canonical, refined, cv::Size(w, w), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 10, 0.01));
    for (size_t i = 0; i < refined.size(); ++i)
      if (cv::norm(refined[i] - out.keypoints[i].pt) < kMaxRefineShiftPx)
        out.keypoints[i].pt = refined[i];
  }
  return out;
}

CeilingMotion track_landmarks(const CeilingLandmarks& a, const CeilingLandmarks& b,
                              const TrackOptions& options) {
  if (!(options.ransac_threshold_px > 0.0))
    throw std::invalid_argument("track_landmarks: ransac_threshold_px must be > 0");
  if (options.min_inliers < 2)
    throw std::invalid_argument("track_landmarks: min_inliers must be >= 2");
  CeilingMotion motion;
  if (a.keypoints.size() < 2 || b.keypoints.size() < 2) return motion;
  cv::BFMatcher matcher(cv::NORM_HAMMING, /*crossCheck=*/true);
  std::vector<cv::DMatch> matches;
  matcher.match(a.descriptors, b.descriptors, matches);
  motion.matches = static_cast<int>(matches.size());
  if (motion.matches < options.min_inliers) return motion;
  std::vector<cv::Point2f> pa, pb;
  for (const cv::DMatch& m : matches) {
    pa.push_back(a.keypoints[static_cast<size_t>(m.queryIdx)].pt);
    pb.push_back(b.keypoints[static_cast<size_t>(m.trainIdx)].pt);
  }
  std::vector<uchar> inlier;
  const cv::Mat A = cv::estimateAffinePartial2D(pa, pb, inlier, cv::RANSAC,
                                                options.ransac_threshold_px, 2000, 0.999, 10);
  if (A.empty()) return motion;
  for (size_t i = 0; i < matches.size(); ++i)
    if (inlier[i] != 0) motion.inlier_matches.push_back(matches[i]);
  motion.inliers = static_cast<int>(motion.inlier_matches.size());
  if (motion.inliers < options.min_inliers) return motion;
  motion.A_b_a = cv::Matx23d(A);
  motion.angle_rad = std::atan2(motion.A_b_a(1, 0), motion.A_b_a(0, 0));
  motion.scale = std::hypot(motion.A_b_a(0, 0), motion.A_b_a(1, 0));
  motion.found = true;
  return motion;
}

}  // namespace pepper::core::ceiling
