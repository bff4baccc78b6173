// Canonical ceiling view (see canonical_view.hpp).
#include "core/ceiling/canonical_view.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/camera/distortion.hpp"

namespace pepper::core::ceiling {

namespace {

constexpr double kPi = 3.14159265358979323846;
// A ray must rise by at least this much (per unit of depth along the optical axis) to meet the
// ceiling, and a ceiling point must be at least this far in front of the image plane (normalised):
// both keep the homography away from the horizon's singularity.
constexpr double kMinRise = 1e-9;
constexpr double kMinDepth = 1e-9;
// A canonical image bigger than this is a unit mistake (px_per_m in px/cm, say), not a view.
constexpr int kMaxSidePx = 8192;

std::string num(double x) {
  std::ostringstream os;
  os << x;
  return os.str();
}

cv::Matx33d rot_x(double angle_rad) {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  return {1, 0, 0, 0, c, -s, 0, s, c};
}

bool has_lens(const CameraIntrinsics& k) {
  return k.model == ProjectionModel::kWithDistortion && (k.kud != 0.0 || k.kdu != 0.0);
}

void validate_camera(const CeilingCamera& c) {
  const auto errors = c.intrinsics.validate();
  if (!errors.empty()) throw CeilingViewError("ceiling view: intrinsics: " + errors.front());
  if (!(std::isfinite(c.ceiling_above_cam_m) && c.ceiling_above_cam_m > 0.0))
    throw CeilingViewError("ceiling view: ceiling_above_cam_m = " + num(c.ceiling_above_cam_m) +
                           " must be a finite height > 0 m above the camera's optical centre");
  if (!(std::isfinite(c.head_pitch_rad) && std::abs(c.head_pitch_rad) < kPi / 2))
    throw CeilingViewError("ceiling view: head_pitch_rad = " + num(c.head_pitch_rad) +
                           " must be finite and within (-pi/2, pi/2)");
  const double max_pitch = max_ceiling_pitch_rad(c.intrinsics);
  if (!(c.head_pitch_rad < max_pitch)) {
    const double below_deg = (c.head_pitch_rad - max_pitch) * 180.0 / kPi;
    throw CeilingViewError("ceiling view: head_pitch_rad = " + num(c.head_pitch_rad) +
                           " does not see the ceiling: the top image row looks " + num(below_deg) +
                           " deg below the horizon; a ceiling view needs head_pitch_rad < " +
                           num(max_pitch) + " (pitch > 0 looks down, docs/conventions.md)");
  }
}

}  // namespace

std::vector<std::string> CanonicalFrame::validate() const {
  std::vector<std::string> errors;
  if (!(width_px > 0 && width_px <= kMaxSidePx))
    errors.push_back("width_px = " + std::to_string(width_px) + " must be in [1, " +
                     std::to_string(kMaxSidePx) + "]");
  if (!(height_px > 0 && height_px <= kMaxSidePx))
    errors.push_back("height_px = " + std::to_string(height_px) + " must be in [1, " +
                     std::to_string(kMaxSidePx) + "]");
  if (!(std::isfinite(px_per_m) && px_per_m > 0.0))
    errors.push_back("px_per_m = " + num(px_per_m) + " must be finite and > 0");
  if (!std::isfinite(center_forward_m))
    errors.push_back("center_forward_m = " + num(center_forward_m) + " must be finite");
  if (!std::isfinite(center_left_m))
    errors.push_back("center_left_m = " + num(center_left_m) + " must be finite");
  return errors;
}

double max_ceiling_pitch_rad(const CameraIntrinsics& intrinsics) {
  // The top row (v = 0) has y_norm = -cy/fy; pitched by p it rises while p < atan(cy / fy). The
  // rise does not depend on the column (the pitch axis is the camera's x axis).
  return std::atan2(intrinsics.cy_px, intrinsics.fy_px);
}

CanonicalView::CanonicalView(const CeilingCamera& camera, const CanonicalFrame& frame)
    : camera_(camera), frame_(frame) {
  validate_camera(camera_);
  const auto frame_errors = frame_.validate();
  if (!frame_errors.empty())
    throw CeilingViewError("ceiling view: canonical frame: " + frame_errors.front());

  // Level camera frame L: the camera at pitch 0 (x right, y down, z forward, horizontal). The
  // head pitches about base +y (left) = camera -x, so R_level_cam = Rx(-pitch): pitch > 0 turns
  // the optical axis towards +y_L (down).
  R_level_cam_ = rot_x(-camera_.head_pitch_rad);
  const double h = camera_.ceiling_above_cam_m;
  // (forward, left, 1) -> ceiling point in L: (-left, -h, forward).
  const cv::Matx33d M_level_ceil(0, -1, 0, 0, 0, -h, 1, 0, 0);
  const CameraIntrinsics& k = camera_.intrinsics;
  const cv::Matx33d K(k.fx_px, 0, k.cx_px, 0, k.fy_px, k.cy_px, 0, 0, 1);
  H_img_ceil_ = K * R_level_cam_.t() * M_level_ceil;

  const double s = frame_.px_per_m;
  const double u0 = (frame_.width_px - 1) / 2.0, v0 = (frame_.height_px - 1) / 2.0;
  A_canon_ceil_ = cv::Matx33d(0, s, u0 - s * frame_.center_left_m,      //
                              -s, 0, v0 + s * frame_.center_forward_m,  //
                              0, 0, 1);
  H_canon_img_ = A_canon_ceil_ * H_img_ceil_.inv();
  H_canon_img_ *= 1.0 / H_canon_img_(2, 2);
  H_img_canon_ = H_canon_img_.inv();
  H_img_canon_ *= 1.0 / H_img_canon_(2, 2);

  // The depth along the optical axis is affine on the ceiling plane, so the frame is in front of
  // the image plane iff its four outer corners are.
  const double w = frame_.width_px, hh = frame_.height_px;
  for (const cv::Point2d& corner : {cv::Point2d(-0.5, -0.5), cv::Point2d(w - 0.5, -0.5),
                                    cv::Point2d(-0.5, hh - 0.5), cv::Point2d(w - 0.5, hh - 0.5)}) {
    const cv::Point2d fl = ceiling_of_canonical(corner);
    const cv::Vec3d X_cam = R_level_cam_.t() * cv::Vec3d(-fl.y, -h, fl.x);
    if (!(X_cam[2] > kMinDepth))
      throw CeilingViewError(
          "ceiling view: canonical frame reaches ceiling points behind the camera's image plane "
          "(corner at forward " +
          num(fl.x) + " m, left " + num(fl.y) +
          " m); move center_forward_m ahead or make the frame smaller (px_per_m, width_px, "
          "height_px)");
  }

  if (has_lens(k)) {
    // Through the lens: every canonical pixel samples the distorted camera pixel of its ceiling
    // point (a homography cannot express the radial term).
    lens_map_x_.create(frame_.height_px, frame_.width_px, CV_32FC1);
    lens_map_y_.create(frame_.height_px, frame_.width_px, CV_32FC1);
    for (int v = 0; v < frame_.height_px; ++v) {
      for (int u = 0; u < frame_.width_px; ++u) {
        const auto p = to_image({static_cast<double>(u), static_cast<double>(v)});
        lens_map_x_.at<float>(v, u) = p ? static_cast<float>(p->x) : -1e6f;
        lens_map_y_.at<float>(v, u) = p ? static_cast<float>(p->y) : -1e6f;
      }
    }
  }
}

std::optional<cv::Point2d> CanonicalView::ceiling_of_pixel(const cv::Point2d& p_px) const {
  const cv::Point2d n = camera::pixel_to_norm(camera_.intrinsics, p_px);
  const cv::Vec3d d_level = R_level_cam_ * cv::Vec3d(n.x, n.y, 1.0);
  const double rise = -d_level[1];
  if (!(rise > kMinRise)) return std::nullopt;
  const double t = camera_.ceiling_above_cam_m / rise;
  return cv::Point2d(t * d_level[2], -t * d_level[0]);
}

std::optional<cv::Point2d> CanonicalView::pixel_of_ceiling(
    const cv::Point2d& forward_left_m) const {
  const cv::Vec3d X_cam =
      R_level_cam_.t() *
      cv::Vec3d(-forward_left_m.y, -camera_.ceiling_above_cam_m, forward_left_m.x);
  if (!(X_cam[2] > kMinDepth)) return std::nullopt;
  return camera::norm_to_pixel(camera_.intrinsics, {X_cam[0] / X_cam[2], X_cam[1] / X_cam[2]});
}

cv::Point2d CanonicalView::canonical_of_ceiling(const cv::Point2d& forward_left_m) const {
  const cv::Vec3d p = A_canon_ceil_ * cv::Vec3d(forward_left_m.x, forward_left_m.y, 1.0);
  return {p[0], p[1]};
}

cv::Point2d CanonicalView::ceiling_of_canonical(const cv::Point2d& p_canon_px) const {
  const double s = frame_.px_per_m;
  const double u0 = (frame_.width_px - 1) / 2.0, v0 = (frame_.height_px - 1) / 2.0;
  return {frame_.center_forward_m - (p_canon_px.y - v0) / s,
          frame_.center_left_m + (p_canon_px.x - u0) / s};
}

std::optional<cv::Point2d> CanonicalView::to_canonical(const cv::Point2d& p_px) const {
  const auto fl = ceiling_of_pixel(p_px);
  if (!fl) return std::nullopt;
  return canonical_of_ceiling(*fl);
}

std::optional<cv::Point2d> CanonicalView::to_image(const cv::Point2d& p_canon_px) const {
  return pixel_of_ceiling(ceiling_of_canonical(p_canon_px));
}

cv::Mat CanonicalView::warp(const cv::Mat& image, cv::Mat* seen) const {
  const CameraIntrinsics& k = camera_.intrinsics;
  if (image.empty() || image.cols != k.width_px || image.rows != k.height_px)
    throw CeilingViewError("ceiling view: warp: image is " + std::to_string(image.cols) + "x" +
                           std::to_string(image.rows) + ", the intrinsics are for " +
                           std::to_string(k.width_px) + "x" + std::to_string(k.height_px));
  const cv::Size size(frame_.width_px, frame_.height_px);
  const auto resample = [&](const cv::Mat& src, cv::Mat& dst) {
    if (lens_map_x_.empty())
      cv::warpPerspective(src, dst, cv::Mat(H_canon_img_), size, cv::INTER_LINEAR,
                          cv::BORDER_CONSTANT, cv::Scalar::all(0));
    else
      cv::remap(src, dst, lens_map_x_, lens_map_y_, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                cv::Scalar::all(0));
  };
  cv::Mat out;
  resample(image, out);
  if (seen != nullptr) {
    // Bilinear sampling blends the zero border into pixels whose source is not fully inside the
    // image, so only pixels that stay at 255 are seen.
    cv::Mat ones(image.size(), CV_8UC1, cv::Scalar(255)), warped;
    resample(ones, warped);
    *seen = warped >= 255;
  }
  return out;
}

CanonicalFrame fit_frame(const CeilingCamera& camera, double px_per_m, double max_forward_m) {
  validate_camera(camera);
  if (!(std::isfinite(px_per_m) && px_per_m > 0.0))
    throw CeilingViewError("ceiling view: fit_frame: px_per_m = " + num(px_per_m) +
                           " must be finite and > 0");
  if (!(std::isfinite(max_forward_m) && max_forward_m > 0.0))
    throw CeilingViewError("ceiling view: fit_frame: max_forward_m = " + num(max_forward_m) +
                           " must be finite and > 0");
  // A provisional view for the point maps (its frame is irrelevant to ceiling_of_pixel).
  CanonicalFrame probe;
  probe.center_forward_m = 1e3;
  probe.width_px = probe.height_px = 1;
  const CanonicalView view(camera, probe);

  // Walk the image border; each edge maps to a straight line on the ceiling, so the clipped
  // footprint's bounding box comes from the samples within max_forward_m and the crossings of
  // the cut (found by bisection, the far part may lie beyond the horizon).
  const CameraIntrinsics& k = camera.intrinsics;
  const double w = k.width_px - 1.0, h = k.height_px - 1.0;
  const cv::Point2d corners[] = {{0, 0}, {w, 0}, {w, h}, {0, h}};
  const auto inside = [&](const cv::Point2d& p_px) -> std::optional<cv::Point2d> {
    const auto fl = view.ceiling_of_pixel(p_px);
    if (fl && fl->x <= max_forward_m) return fl;
    return std::nullopt;
  };
  double f_lo = 1e300, f_hi = -1e300, l_lo = 1e300, l_hi = -1e300;
  const auto add = [&](const cv::Point2d& fl) {
    f_lo = std::min(f_lo, fl.x);
    f_hi = std::max(f_hi, fl.x);
    l_lo = std::min(l_lo, fl.y);
    l_hi = std::max(l_hi, fl.y);
  };
  constexpr int kSamples = 256;
  for (int e = 0; e < 4; ++e) {
    const cv::Point2d a = corners[e], b = corners[(e + 1) % 4];
    std::optional<cv::Point2d> prev;
    double prev_t = 0.0;
    for (int i = 0; i <= kSamples; ++i) {
      const double t = static_cast<double>(i) / kSamples;
      const auto cur = inside(a + t * (b - a));
      if (cur) add(*cur);
      if (i > 0 && static_cast<bool>(cur) != static_cast<bool>(prev)) {
        double t_in = cur ? t : prev_t, t_out = cur ? prev_t : t;
        for (int it = 0; it < 50; ++it) {
          const double mid = 0.5 * (t_in + t_out);
          (inside(a + mid * (b - a)) ? t_in : t_out) = mid;
        }
        add(*inside(a + t_in * (b - a)));
      }
      prev = cur;
      prev_t = t;
    }
  }
  if (!(f_hi >= f_lo))
    throw CeilingViewError("ceiling view: fit_frame: no ceiling within max_forward_m = " +
                           num(max_forward_m) + " m is in the image");
  CanonicalFrame frame;
  frame.px_per_m = px_per_m;
  frame.center_forward_m = 0.5 * (f_lo + f_hi);
  frame.center_left_m = 0.5 * (l_lo + l_hi);
  frame.width_px = static_cast<int>(std::ceil((l_hi - l_lo) * px_per_m)) + 1;
  frame.height_px = static_cast<int>(std::ceil((f_hi - f_lo) * px_per_m)) + 1;
  const auto errors = frame.validate();
  if (!errors.empty()) throw CeilingViewError("ceiling view: fit_frame: " + errors.front());
  return frame;
}

}  // namespace pepper::core::ceiling
