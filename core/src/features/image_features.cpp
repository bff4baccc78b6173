// Feature extraction: EDLines + band descriptors, FAST corners, ORB, KLT pyramid.
#include "core/features/image_features.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <opencv2/ximgproc/edge_drawing.hpp>

#include "core/camera/distortion.hpp"
#include "core/features/band_descriptor.hpp"
#include "core/features/concurrent_tasks.hpp"

namespace pepper::core::features {
namespace {

template <typename T>
void check_range(std::vector<std::string>& errors, const char* name, T value, T lo, T hi) {
  if (!(value >= lo && value <= hi)) {
    std::ostringstream os;
    os << name << " = " << value << " must be in [" << lo << ", " << hi << "]";
    errors.push_back(os.str());
  }
}

std::string join(const std::vector<std::string>& errors) {
  std::string s;
  for (const auto& e : errors) s += (s.empty() ? "" : "; ") + e;
  return s;
}

// Smallest image side on which EdgeDrawing and the descriptors are run (below: no lines).
constexpr int kMinSideForLines = 16;
// Smallest image side on which ORB runs (2 x its 31 px edge threshold + 1, and a margin).
constexpr int kMinSideForOrb = 80;

std::vector<LineSegment> detect_lines(const cv::Mat& gray, const CameraIntrinsics& k,
                                      const FeatureExtractorOptions& o, cv::Mat& descriptors,
                                      int descriptor_threads) {
  std::vector<LineSegment> out;
  descriptors = cv::Mat(0, kLbdDims, CV_32F);
  if (gray.cols < kMinSideForLines || gray.rows < kMinSideForLines) return out;
  auto ed = cv::ximgproc::createEdgeDrawing();
  cv::ximgproc::EdgeDrawing::Params p;
  p.GradientThresholdValue = o.ed_gradient_threshold;
  p.AnchorThresholdValue = o.ed_anchor_threshold;
  p.Sigma = static_cast<float>(o.ed_sigma);
  p.LineFitErrorThreshold = o.ed_line_fit_error_px;
  const int min_len = std::max(8, static_cast<int>(std::lround(o.min_line_length_frac * gray.cols)));
  p.MinLineLength = min_len;
  p.MinPathLength = std::max(10, min_len / 2);
  ed->setParams(p);
  ed->detectEdges(gray);
  std::vector<cv::Vec4f> raw;
  ed->detectLines(raw);

  std::vector<std::pair<float, cv::Vec4f>> by_len;
  by_len.reserve(raw.size());
  for (const auto& l : raw) {
    const float len = std::hypot(l[2] - l[0], l[3] - l[1]);
    if (len >= static_cast<float>(min_len)) by_len.emplace_back(len, l);
  }
  std::stable_sort(by_len.begin(), by_len.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  if (static_cast<int>(by_len.size()) > o.max_lines) by_len.resize(o.max_lines);

  std::vector<std::pair<cv::Point2f, cv::Point2f>> segs;
  segs.reserve(by_len.size());
  out.reserve(by_len.size());
  for (const auto& [len, l] : by_len) {
    cv::Point2f p0(l[0], l[1]), p1(l[2], l[3]);
    orient_segment(gray, p0, p1);
    LineSegment s;
    s.p0_px = p0;
    s.p1_px = p1;
    // The endpoints through the lens model (pixel_to_norm): the segment's line is then that of
    // the undistorted endpoints (docs/perception.md "Lens distortion").
    s.p0_norm = camera::pixel_to_norm(k, cv::Point2d(p0));
    s.p1_norm = camera::pixel_to_norm(k, cv::Point2d(p1));
    s.line = rho_theta_from_points(s.p0_norm, s.p1_norm);
    s.length_px = len;
    out.push_back(s);
    segs.emplace_back(p0, p1);
  }
  descriptors = compute_band_descriptors(gray, segs, o.lbd_band_width_px, o.lbd_samples_along,
                                         descriptor_threads);
  return out;
}

std::vector<cv::Point2f> detect_corners(const cv::Mat& gray, const FeatureExtractorOptions& o) {
  std::vector<cv::KeyPoint> kps;
  cv::FAST(gray, kps, o.fast_threshold, true);
  std::vector<cv::Point2f> out;
  if (kps.empty()) return out;
  const int cols = o.corner_grid_cols, rows = o.corner_grid_rows;
  const int per_cell = std::max(1, (o.max_corners + cols * rows - 1) / (cols * rows));
  std::vector<std::vector<const cv::KeyPoint*>> cells(static_cast<size_t>(cols * rows));
  for (const auto& kp : kps) {
    const int cx = std::min(cols - 1, static_cast<int>(kp.pt.x * cols / gray.cols));
    const int cy = std::min(rows - 1, static_cast<int>(kp.pt.y * rows / gray.rows));
    cells[static_cast<size_t>(cy * cols + cx)].push_back(&kp);
  }
  std::vector<const cv::KeyPoint*> kept;
  for (auto& cell : cells) {
    std::stable_sort(cell.begin(), cell.end(),
                     [](const cv::KeyPoint* a, const cv::KeyPoint* b) { return a->response > b->response; });
    for (int i = 0; i < std::min<int>(per_cell, static_cast<int>(cell.size())); ++i) kept.push_back(cell[i]);
  }
  std::stable_sort(kept.begin(), kept.end(),
                   [](const cv::KeyPoint* a, const cv::KeyPoint* b) { return a->response > b->response; });
  if (static_cast<int>(kept.size()) > o.max_corners) kept.resize(o.max_corners);
  out.reserve(kept.size());
  for (const auto* kp : kept) out.push_back(kp->pt);
  return out;
}

}  // namespace

std::vector<std::string> KltOptions::validate() const {
  std::vector<std::string> e;
  check_range(e, "klt.window_px", window_px, 5, 101);
  if (window_px % 2 == 0) e.push_back("klt.window_px = " + std::to_string(window_px) + " must be odd");
  check_range(e, "klt.max_level", max_level, 0, 6);
  check_range(e, "klt.max_iterations", max_iterations, 1, 1000);
  check_range(e, "klt.epsilon", epsilon, 1e-6, 10.0);
  check_range(e, "klt.min_eig_threshold", min_eig_threshold, 0.0, 1.0);
  check_range(e, "klt.max_error", max_error, 0.0f, 255.0f);
  check_range(e, "klt.prior_max_level", prior_max_level, -1, 6);
  check_range(e, "klt.prior_probes", prior_probes, 0, 1000);
  check_range(e, "klt.retry_untracked_frames", retry_untracked_frames, 1, 1000);
  check_range(e, "klt.prior_window_px", prior_window_px, 5, 101);
  if (prior_window_px % 2 == 0)
    e.push_back("klt.prior_window_px = " + std::to_string(prior_window_px) + " must be odd");
  check_range(e, "klt.normalise_window_frac", normalise_window_frac, 0.0, 0.3);
  return e;
}

int KltOptions::normalise_window_px(int width_px) const {
  if (normalise_window_frac <= 0.0) return 0;
  const int half = static_cast<int>(std::lround(normalise_window_frac * width_px / 2.0));
  return 2 * std::max(half, 1) + 1;
}

cv::Mat klt_image(const cv::Mat& gray, const KltOptions& options) {
  const int window_px = options.normalise_window_px(gray.cols);
  if (window_px == 0) return gray;
  // Standard deviations below this (grey levels) are taken as this: a uniform wall with sensor
  // noise (sigma ~2-3) is not amplified into texture. 6 is below the contrast of the weakest
  // corners FAST keeps (threshold 20 on a 16-pixel ring) even at x0.6.
  constexpr float kMinSigma = 6.0f;
  // Output scale: 32 grey levels per standard deviation keeps +-4 sigma inside 0..255.
  constexpr float kScale = 32.0f;
  cv::Mat f, sq, mean, mean_sq;
  gray.convertTo(f, CV_32F);
  cv::multiply(f, f, sq);
  const cv::Size win(window_px, window_px);
  cv::boxFilter(f, mean, CV_32F, win, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
  cv::boxFilter(sq, mean_sq, CV_32F, win, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
  cv::Mat out(gray.size(), CV_8UC1);
  // Per pixel: 128 + kScale (f - m) / max(sqrt(max(q - m^2, 0)), kMinSigma), rounded half to
  // even and saturated to 0..255. The SIMD body and the scalar tail compute the same float
  // operations in the same order (no fused multiply-add), so every pixel is the same either way
  // (the test NormalisedImage.SimdMatchesTheScalarFormula). A VGA frame is 300 k pixels: the
  // scalar loop alone was about a millisecond per frame.
  for (int y = 0; y < gray.rows; ++y) {
    const float* pf = f.ptr<float>(y);
    const float* pm = mean.ptr<float>(y);
    const float* pq = mean_sq.ptr<float>(y);
    uint8_t* po = out.ptr<uint8_t>(y);
    int x = 0;
#if CV_SIMD
    constexpr int kLanes = cv::v_float32::nlanes;
    const cv::v_float32 zero = cv::vx_setzero_f32(), min_sigma = cv::vx_setall_f32(kMinSigma),
                        scale = cv::vx_setall_f32(kScale), mid = cv::vx_setall_f32(128.0f);
    auto lane = [&](int at) {
      const cv::v_float32 m = cv::vx_load(pm + at), v = cv::vx_load(pf + at);
      const cv::v_float32 var = cv::v_max(cv::vx_load(pq + at) - m * m, zero);
      const cv::v_float32 sigma = cv::v_max(cv::v_sqrt(var), min_sigma);
      return cv::v_round(mid + (scale * (v - m)) / sigma);
    };
    for (; x + 4 * kLanes <= gray.cols; x += 4 * kLanes) {
      const cv::v_uint16 lo = cv::v_pack_u(lane(x), lane(x + kLanes));
      const cv::v_uint16 hi = cv::v_pack_u(lane(x + 2 * kLanes), lane(x + 3 * kLanes));
      cv::v_store(po + x, cv::v_pack(lo, hi));
    }
#endif
    for (; x < gray.cols; ++x) {
      const float var = std::max(pq[x] - pm[x] * pm[x], 0.0f);
      const float sigma = std::max(std::sqrt(var), kMinSigma);
      po[x] = cv::saturate_cast<uint8_t>(128.0f + kScale * (pf[x] - pm[x]) / sigma);
    }
  }
  return out;
}

std::vector<std::string> FeatureExtractorOptions::validate() const {
  std::vector<std::string> e;
  check_range(e, "max_lines", max_lines, 0, 100000);
  check_range(e, "min_line_length_frac", min_line_length_frac, 0.0, 1.0);
  check_range(e, "ed_gradient_threshold", ed_gradient_threshold, 1, 255);
  check_range(e, "ed_anchor_threshold", ed_anchor_threshold, 0, 255);
  check_range(e, "ed_sigma", ed_sigma, 0.1, 10.0);
  check_range(e, "ed_line_fit_error_px", ed_line_fit_error_px, 0.1, 10.0);
  check_range(e, "lbd_band_width_px", lbd_band_width_px, 1, 20);
  check_range(e, "lbd_samples_along", lbd_samples_along, 2, 1000);
  check_range(e, "fast_threshold", fast_threshold, 1, 255);
  check_range(e, "max_corners", max_corners, 0, 100000);
  check_range(e, "corner_grid_cols", corner_grid_cols, 1, 100);
  check_range(e, "corner_grid_rows", corner_grid_rows, 1, 100);
  check_range(e, "orb_max_features", orb_max_features, 0, 100000);
  for (auto& s : klt.validate()) e.push_back(s);
  return e;
}

std::vector<cv::Point2d> ImageFeatures::corners_norm() const {
  std::vector<cv::Point2d> out;
  out.reserve(corners_px.size());
  for (const auto& p : corners_px) out.push_back(camera::pixel_to_norm(intrinsics, cv::Point2d(p)));
  return out;
}

namespace {
// The pyramid from `tracked`, which is klt_image(f.gray, options) already computed.
void build_klt_pyramid_on(ImageFeatures& f, const cv::Mat& tracked, const KltOptions& options,
                          bool with_derivatives) {
  f.klt_pyramid.clear();
  cv::buildOpticalFlowPyramid(tracked, f.klt_pyramid,
                              cv::Size(options.window_px, options.window_px),
                              options.max_level, with_derivatives);
  f.klt_pyramid_options = options;
}
}  // namespace

void build_klt_pyramid(ImageFeatures& f, const KltOptions& options, bool with_derivatives) {
  if (f.gray.empty()) throw std::invalid_argument("build_klt_pyramid: the features hold no image");
  const auto errors = options.validate();
  if (!errors.empty()) throw std::invalid_argument("build_klt_pyramid: " + join(errors));
  build_klt_pyramid_on(f, klt_image(f.gray, options), options, with_derivatives);
}

void release_klt_pyramid(ImageFeatures& f) { f.klt_pyramid.clear(); }

cv::Mat to_gray(const cv::Mat& image) {
  if (image.empty()) throw std::invalid_argument("to_gray: empty image");
  if (image.depth() != CV_8U) {
    throw std::invalid_argument("to_gray: expected an 8-bit image, got depth " +
                                std::to_string(image.depth()));
  }
  cv::Mat gray;
  switch (image.channels()) {
    case 1: return image;
    case 3: cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY); return gray;
    case 4: cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY); return gray;
    default:
      throw std::invalid_argument("to_gray: unsupported channel count " +
                                  std::to_string(image.channels()));
  }
}

FeatureExtractor::FeatureExtractor(const CameraIntrinsics& camera,
                                   const FeatureExtractorOptions& options)
    : camera_(camera), options_(options) {
  auto errors = options.validate();
  for (const auto& s : camera.validate()) errors.push_back("camera." + s);
  if (!errors.empty()) throw std::invalid_argument("FeatureExtractor: " + join(errors));
}

ImageFeatures FeatureExtractor::extract(const cv::Mat& gray, unsigned parts) const {
  if (gray.empty()) throw std::invalid_argument("FeatureExtractor::extract: empty image");
  if (gray.type() != CV_8UC1) {
    throw std::invalid_argument("FeatureExtractor::extract: expected CV_8UC1 (8-bit grey), got " +
                                std::to_string(gray.channels()) + " channel(s) of depth " +
                                std::to_string(gray.depth()) + " (convert with to_gray())");
  }
  ImageFeatures f;
  f.image_size = gray.size();
  f.intrinsics = (camera_.width_px == gray.cols && camera_.height_px == gray.rows)
                     ? camera_
                     : camera_.scaled_to(gray.cols, gray.rows);
  f.gray = gray;
  // The lines and the KLT pyramid both work on the normalised image: computed once.
  cv::Mat normalised;
  if (parts & (kPartLines | kPartPyramid)) normalised = klt_image(gray, options_.klt);
  // Everything but the lines; each part writes its own fields of f.
  auto other_parts = [&] {
    if (parts & kPartCorners) f.corners_px = detect_corners(gray, options_);
    if (parts & kPartWideBaseline) add_wide_baseline(f);
    // Scharr derivatives only for images tracked from (they have corners).
    if (parts & kPartPyramid)
      build_klt_pyramid_on(f, normalised, options_.klt, (parts & kPartCorners) != 0);
  };
  if (!(parts & kPartLines)) {
    f.line_descriptors = cv::Mat(0, kLbdDims, CV_32F);
    other_parts();
    return f;
  }
  // The lines are most of an extraction (EdgeDrawing, then the descriptors): with a second core
  // (cv::getNumThreads() > 1, as FrameMatcher::concurrent()), the other parts run on a thread
  // of their own meanwhile, and the descriptors are computed in two halves. The same features
  // as on one thread, bit for bit (test_image_features.cpp).
  const bool concurrent = cv::getNumThreads() > 1;
  if (!concurrent || !(parts & ~kPartLines)) {
    f.lines = detect_lines(normalised, f.intrinsics, options_, f.line_descriptors,
                           concurrent ? 2 : 1);
    other_parts();
    return f;
  }
  run_concurrently(2, [&](size_t task) {
    if (task == 0) {
      f.lines = detect_lines(normalised, f.intrinsics, options_, f.line_descriptors, 2);
    } else {
      other_parts();
    }
  });
  return f;
}

void FeatureExtractor::add_wide_baseline(ImageFeatures& f) const {
  if (f.gray.empty() || f.gray.type() != CV_8UC1)
    throw std::invalid_argument("FeatureExtractor::add_wide_baseline: the features hold no grey image");
  f.keypoints.clear();
  f.keypoint_descriptors = cv::Mat();
  // ORB needs room for its 31 px patches on its pyramid (smaller images: no keypoints).
  if (options_.orb_max_features > 0 && std::min(f.gray.cols, f.gray.rows) >= kMinSideForOrb) {
    auto orb = cv::ORB::create(options_.orb_max_features);
    orb->detectAndCompute(f.gray, cv::noArray(), f.keypoints, f.keypoint_descriptors);
  }
}

}  // namespace pepper::core::features
