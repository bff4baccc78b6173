#pragma once
// Ceiling landmarks on the canonical view (issue 24, first step towards the mosaic): ORB corners
// with binary descriptors (cv::ORB), refined to sub-pixel positions, and frame-to-frame
// tracking by descriptor matching and a
// robust planar similarity (cv::estimateAffinePartial2D, RANSAC). In the canonical view
// (canonical_view.hpp) the ceiling moves rigidly with the base, so the fitted transform is a
// rotation and a translation; its scale stays 1 within noise, which is reported as a check.
//
// Units and frames: pixels of the canonical image (u right = robot left, v down = robot back);
// angle_rad is the rotation of the fitted transform in image coordinates (x right, y down), so a
// left turn of the base (content counter-clockwise on the screen) gives angle_rad < 0.
// Failure: too few landmarks or matches, or no consensus, is a value (found = false), not an
// exception; bad options throw std::invalid_argument naming the field. Pure, no state.

#include <opencv2/core/mat.hpp>
#include <opencv2/core/matx.hpp>
#include <opencv2/core/types.hpp>
#include <vector>

namespace pepper::core::ceiling {

struct LandmarkOptions {
  int max_landmarks = 400;  ///< ORB's feature budget, > 0
  int fast_threshold = 10;  ///< FAST threshold of ORB's detector, grey levels, > 0
  int border_px = 16;       ///< kept away from the unseen area, so descriptors see only ceiling
  /// Sub-pixel corner refinement (cv::cornerSubPix) half-window, px; 0 = ORB's whole pixels.
  int subpixel_window_px = 2;
};

struct CeilingLandmarks {
  std::vector<cv::KeyPoint> keypoints;  ///< canonical pixels
  cv::Mat descriptors;                  ///< one 32-byte ORB row per keypoint (CV_8U)
};

/// Landmarks of a canonical image (CV_8UC1) inside the seen mask (CV_8UC1, 255 = seen; empty:
/// everywhere), shrunk by border_px. Throws std::invalid_argument for bad options or images.
CeilingLandmarks extract_landmarks(const cv::Mat& canonical, const cv::Mat& seen,
                                   const LandmarkOptions& options = {});

struct TrackOptions {
  double ransac_threshold_px = 2.0;  ///< inlier distance, > 0
  int min_inliers = 12;              ///< fewer: not found
};

/// The rigid motion of the ceiling content from frame a to frame b.
struct CeilingMotion {
  bool found = false;
  cv::Matx23d A_b_a = cv::Matx23d(1, 0, 0, 0, 1, 0);  ///< canonical px of a -> px of b
  double angle_rad = 0.0;                             ///< rotation of A_b_a (see above)
  double scale = 1.0;                                 ///< ~1 for a ceiling at the given height
  int matches = 0;                                    ///< cross-checked descriptor matches
  int inliers = 0;
  std::vector<cv::DMatch> inlier_matches;  ///< queryIdx in a, trainIdx in b
};

/// Matches a's landmarks to b's (Hamming, cross-checked) and fits the motion robustly.
CeilingMotion track_landmarks(const CeilingLandmarks& a, const CeilingLandmarks& b,
                              const TrackOptions& options = {});

}  // namespace pepper::core::ceiling
