#pragma once
// Per-image features, computed once per image (key images: once at teach time, then stored in
// the map), and the extractor that computes them.
//
// What is in an ImageFeatures (METHOD.md "Features and verification"):
//  - lines: EDLines segments (cv::ximgproc::EdgeDrawing), at most `max_lines` longest, each with
//    pixel endpoints and canonical normalised (rho, theta) (line_segment.hpp);
//  - line_descriptors: our LBD-style band descriptor (CV_32F, one row per line, kLbdDims
//    columns, L2 matching). We use our own band descriptor rather than
//    cv::line_descriptor::BinaryDescriptor::compute because the latter is measured ~3x slower per
//    line (docs/perception.md, bench_features BM_OpenCvLbdCompute);
//  - corners_px: FAST corners spread over a grid, the points tracked by KLT *from* this image;
//  - keypoints + keypoint_descriptors: ORB (binary, 32 bytes, Hamming) for wide-baseline
//    matching in initial localisation. ORB because Debian's OpenCV has no SURF, ORB is the fastest
//    of ORB/AKAZE/SIFT (a few ms at VGA) and the views compared are taken facing roughly the same
//    direction at similar scale, where ORB's weaker scale invariance costs little;
//  - gray: the image (CV_8UC1) itself, needed to track corners from this image;
//  - klt_pyramid: DERIVED data (cv::buildOpticalFlowPyramid of gray; extract() adds the
//    derivatives when it computes corners, i.e. when the image will be tracked from), not
//    serialised: rebuild with build_klt_pyramid() after loading. It is optional: tracking from an
//    image without pyramid works, only slower.
// Serialise: image_size, intrinsics, lines, line_descriptors, corners_px, keypoints,
// keypoint_descriptors, gray (PNG). Loading these needs no recomputation except the pyramid.
//
// Units: pixels (`_px`) in the image of `image_size`; normalised coordinates use `intrinsics`,
// which is the extractor's camera scaled to the image size (CameraIntrinsics::scaled_to).
// Thread-safety: FeatureExtractor::extract is const and reentrant.

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>

#include "core/camera/intrinsics.hpp"
#include "core/features/line_segment.hpp"

namespace pepper::core::features {

/// Number of columns of a line descriptor: 9 bands x (mean, std) x 4 gradient sums.
inline constexpr int kLbdDims = 72;

/// Pyramidal KLT parameters (shared by the pyramid builder and the tracker: they must agree).
struct KltOptions {
  int window_px = 15;          ///< square search window side at each level (odd, >= 5)
  int max_level = 3;           ///< pyramid levels above the base (0..6)
  /// The iteration budget per level: LK stops at max_iterations or when an update moves the
  /// track by less than epsilon. Measured and not kept (docs/perception.md "KLT iteration
  /// budget"): 10 iterations cut the real-image step's median by a fifth at QVGA and left the
  /// generated screening unchanged, but in the shipped matrix room_corridor_room with its
  /// furniture moved went over the 15 cm target in 4 of 10 runs (max 19.6-25.2 cm, from 7-9).
  int max_iterations = 20;     ///< per level
  double epsilon = 0.03;       ///< convergence threshold, px
  double min_eig_threshold = 1e-4;  ///< OpenCV minEigThreshold
  float max_error = 30.0f;     ///< reject tracks whose mean patch error exceeds this (grey levels)
  /// Tracking from a prior position (the corner's verified position in the previous frame,
  /// matching.hpp): all priors are first shifted by the image motion measured on `prior_probes`
  /// of them tracked with max_level (0..1000; 0: no shift), then tracked with
  /// `prior_max_level` levels (-1..6, capped at max_level; -1: priors are ignored) and a
  /// `prior_window_px` window (odd, 5..101, capped at window_px). Tracking only: the pyramids
  /// use the fields above.
  /// Measured (docs/perception.md "Speed"): 1 level and an 11 px window track ~2x faster than
  /// from scratch with as few wrong tracks on rendered images with ground truth; 0 levels is a
  /// little faster but leaves wrong tracks where parallax exceeds the window.
  int prior_max_level = 1;
  int prior_probes = 16;
  int prior_window_px = 11;
  /// A key image's corner that KLT did not track into the previous frame (the track failed, or
  /// it was not tried) is tracked from scratch again on one frame in `retry_untracked_frames`
  /// only, staggered by corner index (klt_corners_to_skip; the navigator applies it, 1..1000;
  /// 1: every frame). Tracking from scratch with every level is most of KLT's cost, and a corner
  /// that failed a frame ago seldom succeeds in the next (docs/perception.md "Retrying untracked
  /// corners").
  int retry_untracked_frames = 4;
  /// KLT and the line detector work on photometrically normalised images (klt_image): each
  /// pixel's grey level minus the mean of a square window around it, divided by that window's
  /// standard deviation (floored). A light change multiplies the grey levels (a global gain, or
  /// one that varies slowly across the image); within a window it cancels out, so the patch
  /// error stays that of the unchanged images. Why: on raw grey levels a light change of x0.6
  /// left 8 of 1073 verified points on Pepper's key images, x1.4 239 (test_illumination.cpp),
  /// and the generated worlds under light x0.7 completed 10 of 40 replays (docs/perception.md).
  /// The window's side is this fraction of the image width (rounded to an odd number of pixels:
  /// 0.095 gives 31 px at QVGA, 61 px at VGA), so that it covers the same part of the view at
  /// both sizes. 0: raw grey levels. Measured in the closed loop (docs/perception.md): a window
  /// of 61 px at QVGA (0.19) drove worse than raw grey levels without a light change; a window
  /// of 31 px at VGA (0.048) loses the prior-seeded tracks (test_klt_prior.cpp).
  double normalise_window_frac = 0.095;
  /// The normalisation window's side in pixels for an image `width_px` wide (0: off).
  int normalise_window_px(int width_px) const;
  std::vector<std::string> validate() const;
};

/// The image KLT tracks on (KltOptions::normalise_window_frac): CV_8UC1, 128 + 32 x the locally
/// standardised grey level, saturated; `gray` itself when normalisation is off.
cv::Mat klt_image(const cv::Mat& gray, const KltOptions& options);

struct ImageFeatures {
  cv::Size image_size;                 ///< width x height, px
  CameraIntrinsics intrinsics;         ///< camera at image_size (normalisation of everything here)
  std::vector<LineSegment> lines;      ///< EDLines segments, longest first
  cv::Mat line_descriptors;            ///< CV_32F, lines.size() x kLbdDims (empty if no lines)
  std::vector<cv::Point2f> corners_px; ///< FAST corners for KLT, strongest first per grid cell
  std::vector<cv::KeyPoint> keypoints; ///< ORB keypoints (wide baseline)
  cv::Mat keypoint_descriptors;        ///< CV_8U, keypoints.size() x 32 (empty if none)
  cv::Mat gray;                        ///< CV_8UC1 image (shared buffer, treat as read-only)

  // ---- derived, not serialised ----
  std::vector<cv::Mat> klt_pyramid;    ///< buildOpticalFlowPyramid(klt_image(gray)), see build_klt_pyramid
  KltOptions klt_pyramid_options;      ///< the options the pyramid was built with

  /// Normalised coordinates of corners_px (computed, not stored).
  std::vector<cv::Point2d> corners_norm() const;
};

/// (Re)builds features.klt_pyramid from features.gray. Throws std::invalid_argument if gray is
/// empty. Memory: about 5 bytes per pixel x 4/3 (image + Scharr derivatives per level), 1 byte
/// per pixel x 4/3 without derivatives. The derivatives serve tracking *from* this image (its
/// corners); an image only tracked into (the navigator's current frame) needs none.
void build_klt_pyramid(ImageFeatures& features, const KltOptions& options = {},
                       bool with_derivatives = true);

/// Drops the derived pyramid (to save memory on key images far from the robot).
void release_klt_pyramid(ImageFeatures& features);

/// Which parts extract() computes. The replay loop needs only kLines | kPyramid for the current
/// frame; key images need kAll (teach) and wide-baseline keypoints are for localisation.
enum FeatureParts : unsigned {
  kPartLines = 1u,
  kPartCorners = 2u,
  kPartWideBaseline = 4u,
  kPartPyramid = 8u,
  kPartsCurrentFrame = kPartLines | kPartPyramid,
  kPartsAll = 15u,
};

struct FeatureExtractorOptions {
  // Lines (EDLines via cv::ximgproc::EdgeDrawing).
  int max_lines = 150;                   ///< keep the longest N segments (bounds descriptor cost)
  double min_line_length_frac = 0.04;    ///< minimum segment length as a fraction of image width
                                         ///< (0.04 -> 25.6 px at VGA)
  int ed_gradient_threshold = 20;        ///< EdgeDrawing GradientThresholdValue (grey levels)
  int ed_anchor_threshold = 8;           ///< EdgeDrawing AnchorThresholdValue
  double ed_sigma = 1.0;                 ///< EdgeDrawing Gaussian sigma, px
  double ed_line_fit_error_px = 1.0;     ///< EdgeDrawing LineFitErrorThreshold
  // LBD-style band descriptor.
  int lbd_band_width_px = 5;             ///< width of each of the 9 bands, px (at any image size)
  int lbd_samples_along = 32;            ///< max samples along the segment
  // FAST corners.
  int fast_threshold = 20;               ///< grey levels
  int max_corners = 300;
  int corner_grid_cols = 8;              ///< corners are spread: at most max_corners/(cols*rows)
  int corner_grid_rows = 6;              ///< per cell (strongest kept)
  // Wide baseline (ORB).
  int orb_max_features = 500;
  // KLT pyramid.
  KltOptions klt;

  std::vector<std::string> validate() const;
};

class FeatureExtractor {
 public:
  /// `camera`: intrinsics for normalisation; scaled to each image's size when it differs.
  /// Throws std::invalid_argument when options or intrinsics are invalid (message names fields).
  explicit FeatureExtractor(const CameraIntrinsics& camera = CameraIntrinsics::pepper_top_vga(),
                            const FeatureExtractorOptions& options = {});

  /// Computes the requested parts of `gray`. Throws std::invalid_argument when `gray` is empty or
  /// not CV_8UC1 (message gives the type). Any size works; a textureless image gives empty
  /// feature lists. `gray` is shared (not copied) into the result. With cv::getNumThreads() > 1
  /// the lines are computed on the calling thread (their descriptors in two halves, one on a
  /// second thread) while the other parts run on a thread of their own, all joined before the
  /// call returns: the same features, bit for bit, as with cv::setNumThreads(1).
  ImageFeatures extract(const cv::Mat& gray, unsigned parts = kPartsAll) const;

  /// Adds the wide-baseline part (ORB keypoints and descriptors) to features extracted without
  /// it, from their own image: the same keypoints as extract() with kPartWideBaseline would
  /// have given (none on images under 80 px or with orb_max_features 0). Throws
  /// std::invalid_argument when `features` holds no CV_8UC1 image.
  void add_wide_baseline(ImageFeatures& features) const;

  const FeatureExtractorOptions& options() const { return options_; }
  const CameraIntrinsics& camera() const { return camera_; }

 private:
  CameraIntrinsics camera_;
  FeatureExtractorOptions options_;
};

/// Converts any 8-bit image (grey, BGR, BGRA) to CV_8UC1; throws std::invalid_argument otherwise.
cv::Mat to_gray(const cv::Mat& image);

}  // namespace pepper::core::features
