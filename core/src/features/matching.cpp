// Two-view, three-view and wide-baseline verified matching (see matching.hpp).
#include "core/features/matching.hpp"

#include "core/features/concurrent_tasks.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

// The core runs single-threaded (ARCHITECTURE.md): no OpenMP inside Eigen products.
#ifndef EIGEN_DONT_PARALLELIZE
#define EIGEN_DONT_PARALLELIZE
#endif
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/core/hal/hal.hpp>
#include <opencv2/video/tracking.hpp>

#include "core/camera/distortion.hpp"

namespace pepper::core::features {
namespace {

// Adds the wall-clock time of its scope to *ms (telemetry; nothing when ms is null).
class ScopedMs {
 public:
  explicit ScopedMs(double* ms) : ms_(ms), t0_(std::chrono::steady_clock::now()) {}
  ~ScopedMs() {
    if (ms_ != nullptr)
      *ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_)
                  .count();
  }
  ScopedMs(const ScopedMs&) = delete;
  ScopedMs& operator=(const ScopedMs&) = delete;

 private:
  double* ms_;
  std::chrono::steady_clock::time_point t0_;
};

double* field(MatchTimings* t, double MatchTimings::*member) {
  return t != nullptr ? &(t->*member) : nullptr;
}

std::string join(const std::vector<std::string>& errors) {
  std::string s;
  for (const auto& e : errors) s += (s.empty() ? "" : "; ") + e;
  return s;
}

double focal_of(const ImageFeatures& f) { return 0.5 * (f.intrinsics.fx_px + f.intrinsics.fy_px); }

// |theta_a - theta_b| modulo pi, in [0, pi/2].
double angle_change(double ta, double tb) {
  double d = std::fmod(std::abs(ta - tb), M_PI);
  return d > M_PI_2 ? M_PI - d : d;
}

bool orientation_ok(const LineSegment& a, const LineSegment& b, const LineMatchOptions& o) {
  if (angle_change(a.line.theta_rad, b.line.theta_rad) > o.max_angle_change_rad) return false;
  // Planar motion with a horizontal optical axis keeps vertical lines vertical (theta = 0).
  const double va = std::abs(a.line.theta_rad), vb = std::abs(b.line.theta_rad);
  if (va < o.vertical_tolerance_rad && vb > o.vertical_mismatch_rad) return false;
  if (vb < o.vertical_tolerance_rad && va > o.vertical_mismatch_rad) return false;
  return true;
}

// Segments of a and b must overlap along b's line between the epipolar lines of a's endpoints.
bool epipolar_overlap_ok(const LineSegment& a, const LineSegment& b, const cv::Matx33d& E_b_a,
                         double focal_px) {
  const cv::Vec3d lb = cv::Vec3d(b.p0_norm.x, b.p0_norm.y, 1.0).cross(cv::Vec3d(b.p1_norm.x, b.p1_norm.y, 1.0));
  const cv::Point2d db = b.p1_norm - b.p0_norm;
  const double len_b = std::hypot(db.x, db.y);
  if (len_b <= 0) return true;
  const cv::Point2d u = db * (1.0 / len_b);
  double s[2];
  const cv::Point2d ends[2] = {a.p0_norm, a.p1_norm};
  for (int k = 0; k < 2; ++k) {
    const cv::Vec3d ep = E_b_a * cv::Vec3d(ends[k].x, ends[k].y, 1.0);
    // Near-parallel epipolar and segment lines (segment through the epipole): no constraint.
    const double n_ep = std::hypot(ep[0], ep[1]);
    if (n_ep <= 0) return true;
    const double sin_angle = std::abs(ep[0] * u.y - ep[1] * u.x) / n_ep;  // |cos(normal, u)|
    if (sin_angle < std::sin(5.0 * M_PI / 180.0)) return true;
    const cv::Vec3d q = lb.cross(ep);
    if (std::abs(q[2]) < 1e-12) return true;
    const cv::Point2d qp(q[0] / q[2], q[1] / q[2]);
    s[k] = (qp - b.p0_norm).dot(u);
  }
  const double lo = std::min(s[0], s[1]), hi = std::max(s[0], s[1]);
  const double margin = 0.1 * len_b + 5.0 / focal_px;
  return hi >= -margin && lo <= len_b + margin;
}

// Mutual best + ratio on unit-norm float descriptors via one similarity matrix. The product is
// Eigen's (vectorised): cv::gemm goes through the reference BLAS here (5x the instructions of
// this function on the navigator benchmark, callgrind).
std::vector<LineMatch> descriptor_matches(const cv::Mat& da, const cv::Mat& db,
                                          const LineMatchOptions& o) {
  std::vector<LineMatch> out;
  if (da.empty() || db.empty()) return out;
  using RowMajorF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const cv::Mat ca = da.isContinuous() ? da : da.clone(), cb = db.isContinuous() ? db : db.clone();
  const Eigen::Map<const RowMajorF> ea(ca.ptr<float>(), ca.rows, ca.cols);
  const Eigen::Map<const RowMajorF> eb(cb.ptr<float>(), cb.rows, cb.cols);
  RowMajorF sim = ea * eb.transpose();  // na x nb, cos similarity
  const cv::Mat dot(static_cast<int>(sim.rows()), static_cast<int>(sim.cols()), CV_32F,
                    sim.data());
  const int na = dot.rows, nb = dot.cols;
  std::vector<int> best_a_for_b(static_cast<size_t>(nb), -1);
  std::vector<float> best_dot_b(static_cast<size_t>(nb), -std::numeric_limits<float>::infinity());
  for (int i = 0; i < na; ++i) {
    const float* r = dot.ptr<float>(i);
    for (int j = 0; j < nb; ++j) {
      if (r[j] > best_dot_b[static_cast<size_t>(j)]) {
        best_dot_b[static_cast<size_t>(j)] = r[j];
        best_a_for_b[static_cast<size_t>(j)] = i;
      }
    }
  }
  auto dist = [](float d) { return std::sqrt(std::max(0.0f, 2.0f - 2.0f * d)); };
  for (int i = 0; i < na; ++i) {
    const float* r = dot.ptr<float>(i);
    int j1 = -1;
    float d1 = -std::numeric_limits<float>::infinity(), d2 = d1;
    for (int j = 0; j < nb; ++j) {
      if (r[j] > d1) {
        d2 = d1;
        d1 = r[j];
        j1 = j;
      } else if (r[j] > d2) {
        d2 = r[j];
      }
    }
    if (j1 < 0) continue;
    const float dist1 = dist(d1);
    if (dist1 > o.max_descriptor_distance) continue;
    if (nb >= 2 && dist1 > o.ratio * dist(d2)) continue;
    if (o.mutual && best_a_for_b[static_cast<size_t>(j1)] != i) continue;
    out.push_back({i, j1, dist1});
  }
  return out;
}

// Tracks of a's corners into b (one entry per corner).
struct Tracks {
  std::vector<cv::Point2f> b_px;
  std::vector<uchar> ok;     ///< tracked, patch error within max_error, inside b
  std::vector<float> error;  ///< KLT mean patch error (grey levels) of the tracks that are ok
};

// Standard deviation of the grey levels in the (2 r + 1)^2 patch around p, clipped to the image.
double patch_sigma(const cv::Mat& gray, const cv::Point2f& p, int r) {
  const int x = static_cast<int>(std::lround(p.x)), y = static_cast<int>(std::lround(p.y));
  const cv::Rect roi = cv::Rect(x - r, y - r, 2 * r + 1, 2 * r + 1) & cv::Rect(0, 0, gray.cols, gray.rows);
  if (roi.area() < 4) return 0.0;
  // Integer sums over the few pixels, then cv::meanStdDev's own formula: a call of that function
  // per track end cost more than the sums themselves (two per track, hundreds of tracks a frame).
  int64_t sum = 0, sum_sq = 0;
  for (int yy = roi.y; yy < roi.y + roi.height; ++yy) {
    const uint8_t* row = gray.ptr<uint8_t>(yy);
    for (int xx = roi.x; xx < roi.x + roi.width; ++xx) {
      sum += row[xx];
      sum_sq += row[xx] * row[xx];
    }
  }
  const double inv_n = 1.0 / roi.area();
  const double mean = static_cast<double>(sum) * inv_n;
  return std::sqrt(std::max(static_cast<double>(sum_sq) * inv_n - mean * mean, 0.0));
}

// A track's two patches under the light model of the normalised images (a grey level gain that
// varies slowly across the view): the target patch's contrast is the source's times a gain.
// Normalisation makes the patch error blind to that gain, so a corner tracked onto a flat wall
// (a contrast of sensor noise only, normalised to the same flat grey as any plain patch) would
// pass it; its gain, target over source contrast, is far below any light change the replay
// meets (x0.6 and sensor noise: > 0.5). Raw grey levels: their patch error already rejects it.
bool plausible_gain(const cv::Mat& a_gray, const cv::Point2f& a_px, const cv::Mat& b_gray,
                    const cv::Point2f& b_px) {
  constexpr int kRadiusPx = 3;
  constexpr double kMinGain = 0.3, kMaxGain = 1.0 / kMinGain;
  const double sa = patch_sigma(a_gray, a_px, kRadiusPx), sb = patch_sigma(b_gray, b_px, kRadiusPx);
  return sb >= kMinGain * sa && sb <= kMaxGain * sa;
}

// One pyramidal LK call from a's image into b's with a window of window_px (<= k.window_px), using
// their pyramids when they were built for k. With `use_initial`, b_pts holds the starting
// positions (OPTFLOW_USE_INITIAL_FLOW). Rejects tracks with a large patch error or ending
// outside b.
void run_lk(const ImageFeatures& a, const ImageFeatures& b, const KltOptions& k, int window_px,
            int max_level, bool use_initial, const std::vector<cv::Point2f>& a_pts,
            std::vector<cv::Point2f>& b_pts, std::vector<uchar>& status, std::vector<float>& err) {
  auto usable = [&](const ImageFeatures& f) {
    return !f.klt_pyramid.empty() && f.klt_pyramid_options.window_px == k.window_px &&
           f.klt_pyramid_options.normalise_window_frac == k.normalise_window_frac &&
           f.klt_pyramid_options.max_level >= k.max_level;
  };
  const bool a_pyr = usable(a), b_pyr = usable(b);
  const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, k.max_iterations,
                              k.epsilon);
  const int flags = use_initial ? cv::OPTFLOW_USE_INITIAL_FLOW : 0;
  const cv::Size win(window_px, window_px);
  if (a_pyr && b_pyr) {
    cv::calcOpticalFlowPyrLK(a.klt_pyramid, b.klt_pyramid, a_pts, b_pts, status, err, win,
                             max_level, crit, flags, k.min_eig_threshold);
  } else if (b_pyr) {
    cv::calcOpticalFlowPyrLK(klt_image(a.gray, k), b.klt_pyramid, a_pts, b_pts, status, err, win,
                             max_level, crit, flags, k.min_eig_threshold);
  } else {
    cv::calcOpticalFlowPyrLK(klt_image(a.gray, k), klt_image(b.gray, k), a_pts, b_pts, status, err,
                             win, max_level, crit, flags, k.min_eig_threshold);
  }
  const float w = static_cast<float>(b.image_size.width), h = static_cast<float>(b.image_size.height);
  const bool check_contrast = !a.gray.empty() && !b.gray.empty();
  for (size_t i = 0; i < status.size(); ++i) {
    if (!status[i]) continue;
    const cv::Point2f& p = b_pts[i];
    if (!(err[i] <= k.max_error) || !(p.x >= 0 && p.y >= 0 && p.x <= w - 1 && p.y <= h - 1)) {
      status[i] = 0;
    } else if (check_contrast && !plausible_gain(a.gray, a_pts[i], b.gray, p)) {
      status[i] = 0;
    }
  }
}

// Tracks all of a's corners into b. Corners with a prior position start there, shifted by the
// image motion since the prior's frame, with k.prior_max_level levels and the k.prior_window_px
// window: that motion is the median displacement of k.prior_probes of them first tracked with
// all levels (a turn moves the whole image by tens of pixels per frame; what is left after the
// shift is a few pixels). The corners without prior, and prior tracks that fail, are tracked
// with k.max_level from their position in a moved by `shift_px` (a guess of the image motion
// a -> b, or zero), except the corners in `skip` (klt_corners_to_skip), left untracked.
Tracks klt_track(const ImageFeatures& a, const ImageFeatures& b, const KltOptions& k,
                 const cv::Point2f& shift_px, std::span<const PointMatch> prior,
                 std::span<const int> skip) {
  const size_t n = a.corners_px.size();
  Tracks t;
  t.b_px.assign(n, cv::Point2f());
  t.ok.assign(n, 0);
  t.error.assign(n, 0.0f);
  std::vector<int> idx;
  std::vector<cv::Point2f> a_sub, b_sub;
  std::vector<uchar> st_sub;
  std::vector<float> err_sub;
  auto take = [&] {
    for (size_t j = 0; j < idx.size(); ++j) {
      if (!st_sub[j]) continue;
      const auto i = static_cast<size_t>(idx[j]);
      t.ok[i] = 1;
      t.b_px[i] = b_sub[j];
      t.error[i] = err_sub[j];
    }
  };
  if (k.prior_max_level >= 0 && !prior.empty()) {
    std::vector<uchar> has_prior(n, 0);
    std::vector<int> p_idx;
    std::vector<cv::Point2f> p_b;
    for (const PointMatch& m : prior) {
      const auto i = static_cast<size_t>(m.idx_a);
      if (m.idx_a < 0 || i >= n || has_prior[i]) continue;
      has_prior[i] = 1;
      p_idx.push_back(m.idx_a);
      p_b.push_back(m.b_px);
    }
    const int levels = std::min(k.prior_max_level, k.max_level);
    cv::Point2f shift(0.0f, 0.0f);
    const size_t probes =
        levels < k.max_level ? std::min(static_cast<size_t>(k.prior_probes), p_idx.size()) : 0;
    std::vector<uchar> is_probe(p_idx.size(), 0);
    if (probes > 0) {
      for (size_t s = 0; s < probes; ++s) {  // spread over the prior list
        const size_t j = s * p_idx.size() / probes;
        is_probe[j] = 1;
        idx.push_back(p_idx[j]);
        a_sub.push_back(a.corners_px[static_cast<size_t>(p_idx[j])]);
        b_sub.push_back(p_b[j]);
      }
      const std::vector<cv::Point2f> start = b_sub;
      run_lk(a, b, k, k.window_px, k.max_level, true, a_sub, b_sub, st_sub, err_sub);
      take();
      std::vector<float> dx, dy;
      for (size_t j = 0; j < idx.size(); ++j) {
        if (!st_sub[j]) continue;
        dx.push_back(b_sub[j].x - start[j].x);
        dy.push_back(b_sub[j].y - start[j].y);
      }
      if (!dx.empty()) {
        const auto mid = static_cast<std::ptrdiff_t>(dx.size() / 2);
        std::nth_element(dx.begin(), dx.begin() + mid, dx.end());
        std::nth_element(dy.begin(), dy.begin() + mid, dy.end());
        shift = cv::Point2f(dx[static_cast<size_t>(mid)], dy[static_cast<size_t>(mid)]);
      }
    }
    idx.clear();
    a_sub.clear();
    b_sub.clear();
    for (size_t j = 0; j < p_idx.size(); ++j) {
      if (is_probe[j]) continue;
      idx.push_back(p_idx[j]);
      a_sub.push_back(a.corners_px[static_cast<size_t>(p_idx[j])]);
      b_sub.push_back(p_b[j] + shift);
    }
    if (!idx.empty()) {
      run_lk(a, b, k, std::min(k.prior_window_px, k.window_px), levels, true, a_sub, b_sub, st_sub,
             err_sub);
      take();
    }
  }
  idx.clear();
  a_sub.clear();
  b_sub.clear();
  const bool shifted = shift_px != cv::Point2f(0.0f, 0.0f);
  std::vector<uchar> skipped(n, 0);
  for (const int i : skip) {
    if (i >= 0 && static_cast<size_t>(i) < n) skipped[static_cast<size_t>(i)] = 1;
  }
  for (size_t i = 0; i < n; ++i) {
    if (t.ok[i] || skipped[i]) continue;
    idx.push_back(static_cast<int>(i));
    a_sub.push_back(a.corners_px[i]);
    if (shifted) b_sub.push_back(a.corners_px[i] + shift_px);
  }
  if (!idx.empty()) {
    run_lk(a, b, k, k.window_px, k.max_level, shifted, a_sub, b_sub, st_sub, err_sub);
    take();
  }
  return t;
}

void check_image(const ImageFeatures& f, const char* who) {
  if (f.gray.empty() || f.image_size.width <= 0) {
    throw std::invalid_argument(std::string(who) + ": features without image (gray is empty)");
  }
}

// `cost[i]`: how doubtful candidate i is (KLT patch error, ORB distance): the essential RANSAC
// (PROSAC) draws its samples from the best candidates first. The verified points keep the
// candidates' order.
void verify_points(const ImageFeatures& b, std::vector<PointMatch> cands,
                   const std::vector<float>& cost, const MatcherOptions& o, TwoViewMatches& r) {
  r.point_candidates = static_cast<int>(cands.size());
  std::vector<int> order(cands.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) {
    return cost[static_cast<size_t>(x)] < cost[static_cast<size_t>(y)];
  });
  std::vector<cv::Point2d> an, bn;
  an.reserve(cands.size());
  bn.reserve(cands.size());
  for (const int i : order) {
    an.push_back(cands[static_cast<size_t>(i)].a_norm);
    bn.push_back(cands[static_cast<size_t>(i)].b_norm);
  }
  const auto ess = geometry::verify_essential(an, bn, focal_of(b), o.essential, true);
  r.essential_found = ess.found;
  r.E_b_a = ess.E_b_a;
  std::vector<int> kept;
  kept.reserve(ess.inliers.size());
  for (const int i : ess.inliers) kept.push_back(order[static_cast<size_t>(i)]);
  std::sort(kept.begin(), kept.end());
  r.points.reserve(kept.size());
  for (const int i : kept) r.points.push_back(cands[static_cast<size_t>(i)]);
}

// Descriptor matches (mutual + ratio) that pass the orientation checks; sets line_candidates.
std::vector<LineMatch> line_candidates(const ImageFeatures& a, const ImageFeatures& b,
                                       const MatcherOptions& o, TwoViewMatches& r) {
  std::vector<LineMatch> cands = descriptor_matches(a.line_descriptors, b.line_descriptors, o.lines);
  r.line_candidates = static_cast<int>(cands.size());
  std::vector<LineMatch> kept;
  kept.reserve(cands.size());
  for (const auto& m : cands) {
    if (orientation_ok(a.lines[static_cast<size_t>(m.idx_a)], b.lines[static_cast<size_t>(m.idx_b)],
                       o.lines))
      kept.push_back(m);
  }
  return kept;
}

// The epipolar overlap check (when E is known) on the candidates: the verified line set.
void verify_lines(const ImageFeatures& a, const ImageFeatures& b, const MatcherOptions& o,
                  const std::vector<LineMatch>& cands, TwoViewMatches& r) {
  for (const auto& m : cands) {
    const LineSegment& la = a.lines[static_cast<size_t>(m.idx_a)];
    const LineSegment& lb = b.lines[static_cast<size_t>(m.idx_b)];
    if (o.lines.epipolar_overlap && r.essential_found &&
        !epipolar_overlap_ok(la, lb, r.E_b_a, focal_of(b)))
      continue;
    r.lines.push_back(m);
  }
}

void verify_lines(const ImageFeatures& a, const ImageFeatures& b, const MatcherOptions& o,
                  TwoViewMatches& r) {
  verify_lines(a, b, o, line_candidates(a, b, o, r), r);
}

// Image motion a -> b common to the scene, from the line candidates: the median displacement of
// segment midpoints. Under a base rotation (turns) the whole image shifts sideways by up to
// ~100 px between key images at QVGA, beyond KLT's pyramid reach (~60 px with 3 levels); line
// descriptors match regardless, so their shift is KLT's starting guess. Zero with fewer than
// `kMinLines` candidates or when the shift is within KLT's own reach anyway.
cv::Point2f shift_from_lines(const ImageFeatures& a, const ImageFeatures& b,
                             const std::vector<LineMatch>& cands, const KltOptions& klt) {
  constexpr size_t kMinLines = 5;
  if (cands.size() < kMinLines) return {0.0f, 0.0f};
  std::vector<float> dx, dy;
  dx.reserve(cands.size());
  dy.reserve(cands.size());
  for (const auto& m : cands) {
    const LineSegment& la = a.lines[static_cast<size_t>(m.idx_a)];
    const LineSegment& lb = b.lines[static_cast<size_t>(m.idx_b)];
    const cv::Point2f d = 0.5f * (lb.p0_px + lb.p1_px) - 0.5f * (la.p0_px + la.p1_px);
    dx.push_back(d.x);
    dy.push_back(d.y);
  }
  const auto median = [](std::vector<float>& v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const cv::Point2f shift(median(dx), median(dy));
  // Within a window of the origin KLT converges by itself; a guess there only adds line noise.
  if (std::hypot(shift.x, shift.y) < static_cast<float>(klt.window_px)) return {0.0f, 0.0f};
  return shift;
}

// Planar prior of the key image's motion w.r.t. the hub from the point branch's essential matrix
// (three-view lines); none without a usable E.
std::optional<geometry::PlanarViewPrior> prior_of(const TwoViewMatches& key_to_hub, double focal_px,
                                                  const geometry::PlanarTrifocalOptions& o) {
  if (!key_to_hub.essential_found) return std::nullopt;
  std::vector<cv::Point2d> key, hub;
  key.reserve(key_to_hub.points.size());
  hub.reserve(key_to_hub.points.size());
  for (const auto& m : key_to_hub.points) {
    key.push_back(m.a_norm);
    hub.push_back(m.b_norm);
  }
  return geometry::planar_view_prior(key_to_hub.E_b_a, key, hub, focal_px, o);
}

}  // namespace

std::vector<std::string> LineMatchOptions::validate() const {
  std::vector<std::string> e;
  auto bad = [&](const char* name, double v, const char* range) {
    std::ostringstream os;
    os << "lines." << name << " = " << v << " must be in " << range;
    e.push_back(os.str());
  };
  if (!(ratio > 0.0 && ratio <= 1.0)) bad("ratio", ratio, "(0, 1]");
  if (!(max_descriptor_distance > 0.0 && max_descriptor_distance <= 2.0))
    bad("max_descriptor_distance", max_descriptor_distance, "(0, 2]");
  if (!(max_angle_change_rad > 0.0 && max_angle_change_rad <= M_PI_2))
    bad("max_angle_change_rad", max_angle_change_rad, "(0, pi/2]");
  if (!(vertical_tolerance_rad >= 0.0 && vertical_tolerance_rad < M_PI_2))
    bad("vertical_tolerance_rad", vertical_tolerance_rad, "[0, pi/2)");
  if (!(vertical_mismatch_rad >= vertical_tolerance_rad && vertical_mismatch_rad <= M_PI_2))
    bad("vertical_mismatch_rad", vertical_mismatch_rad, "[vertical_tolerance_rad, pi/2]");
  return e;
}

std::vector<std::string> MatcherOptions::validate() const {
  std::vector<std::string> e = lines.validate();
  for (auto& s : klt.validate()) e.push_back(s);
  for (auto& s : essential.validate()) e.push_back(s);
  for (auto& s : trifocal.validate()) e.push_back(s);
  if (!(three_view_point_radius_px > 0.0 && three_view_point_radius_px <= 50.0))
    e.push_back("three_view_point_radius_px = " + std::to_string(three_view_point_radius_px) +
                " must be in (0, 50]");
  if (!(orb_ratio > 0.0 && orb_ratio <= 1.0))
    e.push_back("orb_ratio = " + std::to_string(orb_ratio) + " must be in (0, 1]");
  if (!(orb_max_hamming >= 0 && orb_max_hamming <= 256))
    e.push_back("orb_max_hamming = " + std::to_string(orb_max_hamming) + " must be in [0, 256]");
  if (orb_fallback_below_points < 0)
    e.push_back("orb_fallback_below_points = " + std::to_string(orb_fallback_below_points) +
                " must be >= 0");
  if (!match_lines && !match_points) e.push_back("match_lines and match_points are both off");
  return e;
}

std::vector<LineMatch> match_lines(const ImageFeatures& a, const ImageFeatures& b,
                                   const LineMatchOptions& options) {
  const auto errors = options.validate();
  if (!errors.empty()) throw std::invalid_argument("match_lines: " + join(errors));
  std::vector<LineMatch> out;
  for (const auto& m : descriptor_matches(a.line_descriptors, b.line_descriptors, options)) {
    if (orientation_ok(a.lines[static_cast<size_t>(m.idx_a)], b.lines[static_cast<size_t>(m.idx_b)], options))
      out.push_back(m);
  }
  return out;
}

namespace {

// KLT of a's corners into b (klt_track) and essential RANSAC, into r.
void track_and_verify_points(const ImageFeatures& a, const ImageFeatures& b,
                             const MatcherOptions& options, const cv::Point2f& shift_px,
                             std::span<const PointMatch> prior, std::span<const int> skip,
                             TwoViewMatches& r, MatchTimings* timings) {
  const Tracks t = [&] {
    const ScopedMs ms(field(timings, &MatchTimings::klt_ms));
    return klt_track(a, b, options.klt, shift_px, prior, skip);
  }();
  std::vector<PointMatch> cands;
  std::vector<float> cost;  // KLT patch error
  cands.reserve(t.ok.size());
  cost.reserve(t.ok.size());
  for (size_t i = 0; i < t.ok.size(); ++i) {
    if (!t.ok[i]) continue;
    PointMatch m;
    m.idx_a = static_cast<int>(i);
    m.a_px = a.corners_px[i];
    m.b_px = t.b_px[i];
    m.a_norm = camera::pixel_to_norm(a.intrinsics, cv::Point2d(m.a_px));
    m.b_norm = camera::pixel_to_norm(b.intrinsics, cv::Point2d(m.b_px));
    cands.push_back(m);
    cost.push_back(t.error[i]);
  }
  for (size_t i = 0; i < t.ok.size(); ++i) {
    if (!t.ok[i]) r.klt_untracked.push_back(static_cast<int>(i));
  }
  const ScopedMs ms(field(timings, &MatchTimings::essential_ms));
  verify_points(b, std::move(cands), cost, options, r);
}

}  // namespace

std::vector<int> klt_corners_to_skip(std::span<const int> untracked, int64_t frame,
                                     int retry_frames) {
  std::vector<int> skip;
  if (retry_frames <= 1) return skip;
  skip.reserve(untracked.size());
  for (const int c : untracked) {
    if ((static_cast<int64_t>(c) + frame) % retry_frames != 0) skip.push_back(c);
  }
  return skip;
}

TwoViewMatches match_two_view(const ImageFeatures& a, const ImageFeatures& b,
                              const MatcherOptions& options, std::span<const PointMatch> prior,
                              MatchTimings* timings, std::span<const int> skip) {
  const auto errors = options.validate();
  if (!errors.empty()) throw std::invalid_argument("match_two_view: " + join(errors));
  check_image(a, "match_two_view (a)");
  check_image(b, "match_two_view (b)");
  TwoViewMatches r;
  std::vector<LineMatch> line_cands;
  if (options.match_lines) {
    const ScopedMs ms(field(timings, &MatchTimings::lines_ms));
    line_cands = line_candidates(a, b, options, r);
  }
  if (options.match_points && !a.corners_px.empty()) {
    // KLT starts at the lines' common shift when the image moved further than a KLT window
    // (turns); measured in closed loop on the mock robot against starting from rest, and
    // against using the shift only when tracking from rest verifies under half of the corners
    // (docs/perception.md "KLT starting guess").
    const cv::Point2f shift = options.klt_shift_from_lines
                                  ? shift_from_lines(a, b, line_cands, options.klt)
                                  : cv::Point2f(0.0f, 0.0f);
    track_and_verify_points(a, b, options, shift, prior, skip, r, timings);
  }
  const ScopedMs ms(field(timings, &MatchTimings::lines_ms));
  verify_lines(a, b, options, line_cands, r);
  return r;
}

TwoViewMatches match_wide_baseline(const ImageFeatures& a, const ImageFeatures& b,
                                   const MatcherOptions& options, MatchTimings* timings) {
  const auto errors = options.validate();
  if (!errors.empty()) throw std::invalid_argument("match_wide_baseline: " + join(errors));
  TwoViewMatches r;
  std::vector<PointMatch> cands;
  std::vector<float> cost;  // Hamming distance of the match
  if (options.match_points && !a.keypoint_descriptors.empty() &&
      !b.keypoint_descriptors.empty()) {
    const ScopedMs ms(field(timings, &MatchTimings::wide_baseline_ms));
    const cv::Mat& da = a.keypoint_descriptors;
    const cv::Mat& db = b.keypoint_descriptors;
    const int na = da.rows, nb = db.rows;
    // All pairwise Hamming distances on the raw descriptor bytes (cv::norm on row headers cost
    // 27 ms CPU for ~460 x 460 keypoints, this 2.5 ms: the same distance without a Mat per pair;
    // bench_features BM_WideBaselineKeyToCurrent).
    CV_Assert(da.type() == CV_8UC1 && db.type() == CV_8UC1 && da.cols == db.cols);
    std::vector<int> dist(static_cast<size_t>(na) * nb);
    for (int i = 0; i < na; ++i) {
      const uchar* ra = da.ptr<uchar>(i);
      for (int j = 0; j < nb; ++j)
        dist[static_cast<size_t>(i) * nb + j] = cv::hal::normHamming(ra, db.ptr<uchar>(j), da.cols);
    }
    std::vector<int> best_a_for_b(static_cast<size_t>(nb), -1), best_d_b(static_cast<size_t>(nb), 1 << 20);
    for (int i = 0; i < na; ++i)
      for (int j = 0; j < nb; ++j) {
        const int d = dist[static_cast<size_t>(i) * nb + j];
        if (d < best_d_b[static_cast<size_t>(j)]) {
          best_d_b[static_cast<size_t>(j)] = d;
          best_a_for_b[static_cast<size_t>(j)] = i;
        }
      }
    for (int i = 0; i < na; ++i) {
      int j1 = -1, d1 = 1 << 20, d2 = 1 << 20;
      for (int j = 0; j < nb; ++j) {
        const int d = dist[static_cast<size_t>(i) * nb + j];
        if (d < d1) {
          d2 = d1;
          d1 = d;
          j1 = j;
        } else if (d < d2) {
          d2 = d;
        }
      }
      if (j1 < 0 || d1 > options.orb_max_hamming) continue;
      if (nb >= 2 && d1 > options.orb_ratio * d2) continue;
      if (best_a_for_b[static_cast<size_t>(j1)] != i) continue;
      PointMatch m;
      m.idx_a = i;
      m.idx_b = j1;
      m.a_px = a.keypoints[static_cast<size_t>(i)].pt;
      m.b_px = b.keypoints[static_cast<size_t>(j1)].pt;
      m.a_norm = camera::pixel_to_norm(a.intrinsics, cv::Point2d(m.a_px));
      m.b_norm = camera::pixel_to_norm(b.intrinsics, cv::Point2d(m.b_px));
      cands.push_back(m);
      cost.push_back(static_cast<float>(d1));
    }
  }
  {
    const ScopedMs ms(field(timings, &MatchTimings::essential_ms));
    verify_points(b, std::move(cands), cost, options, r);
  }
  const ScopedMs ms(field(timings, &MatchTimings::lines_ms));
  if (options.match_lines) verify_lines(a, b, options, r);
  return r;
}

ThreeViewMatches verify_three_view(const ImageFeatures& x, const TwoViewMatches& x_to_hub,
                                   const ImageFeatures& hub, const ImageFeatures& y,
                                   const TwoViewMatches& y_to_hub, const MatcherOptions& options) {
  ThreeViewMatches r;
  // Lines: chain through the hub's line index.
  std::vector<int> x_of_hub(hub.lines.size(), -1);
  for (const auto& m : x_to_hub.lines) x_of_hub[static_cast<size_t>(m.idx_b)] = m.idx_a;
  std::vector<geometry::LineTriplet> triplets;
  std::vector<LineTripletMatch> cand;
  for (const auto& m : y_to_hub.lines) {
    const int xi = x_of_hub[static_cast<size_t>(m.idx_b)];
    if (xi < 0) continue;
    const LineSegment& lh = hub.lines[static_cast<size_t>(m.idx_b)];
    const LineSegment& lx = x.lines[static_cast<size_t>(xi)];
    const LineSegment& ly = y.lines[static_cast<size_t>(m.idx_a)];
    geometry::LineTriplet t;
    t.view[0] = {lh.p0_norm, lh.p1_norm};
    t.view[1] = {lx.p0_norm, lx.p1_norm};
    t.view[2] = {ly.p0_norm, ly.p1_norm};
    triplets.push_back(t);
    cand.push_back({xi, m.idx_b, m.idx_a});
  }
  r.line_candidates = static_cast<int>(cand.size());
  // Seeded by the two essential matrices when both are usable (planar_trifocal.hpp).
  const double f = focal_of(hub);
  std::optional<geometry::PlanarViewPrior> prior_x, prior_y;
  if (options.trifocal.prior_from_points) {
    prior_x = prior_of(x_to_hub, f, options.trifocal);
    if (prior_x) prior_y = prior_of(y_to_hub, f, options.trifocal);
  }
  r.trifocal = prior_x && prior_y ? geometry::verify_line_triplets(triplets, f, options.trifocal,
                                                                   {*prior_x, *prior_y})
                                  : geometry::verify_line_triplets(triplets, f, options.trifocal);
  for (int i : r.trifocal.inliers) r.lines.push_back(cand[static_cast<size_t>(i)]);

  // Points: verified tracks X -> hub and Y -> hub meeting in the hub (mutual nearest).
  const auto& px = x_to_hub.points;
  const auto& py = y_to_hub.points;
  const double r2 = options.three_view_point_radius_px * options.three_view_point_radius_px;
  std::vector<int> nn_x(px.size(), -1), nn_y(py.size(), -1);
  std::vector<double> d_x(px.size(), r2), d_y(py.size(), r2);
  for (size_t i = 0; i < px.size(); ++i) {
    for (size_t j = 0; j < py.size(); ++j) {
      const double dx = px[i].b_px.x - py[j].b_px.x, dy = px[i].b_px.y - py[j].b_px.y;
      const double d = dx * dx + dy * dy;
      if (d <= d_x[i]) {
        d_x[i] = d;
        nn_x[i] = static_cast<int>(j);
      }
      if (d <= d_y[j]) {
        d_y[j] = d;
        nn_y[j] = static_cast<int>(i);
      }
    }
  }
  for (size_t i = 0; i < px.size(); ++i) {
    const int j = nn_x[i];
    if (j < 0 || nn_y[static_cast<size_t>(j)] != static_cast<int>(i)) continue;
    PointTripletMatch m;
    m.idx_x = px[i].idx_a;
    m.idx_y = py[static_cast<size_t>(j)].idx_a;
    m.hub_px = 0.5f * (px[i].b_px + py[static_cast<size_t>(j)].b_px);
    m.hub_norm = camera::pixel_to_norm(hub.intrinsics, cv::Point2d(m.hub_px));
    r.points.push_back(m);
  }
  return r;
}

size_t FrameMatcher::PairHash::operator()(const std::pair<int64_t, int64_t>& p) const noexcept {
  return std::hash<int64_t>()(p.first) * 1000003u ^ std::hash<int64_t>()(p.second);
}

FrameMatcher::FrameMatcher(ImageFeatures current, const MatcherOptions& options)
    : current_(std::move(current)), options_(options) {
  const auto errors = options_.validate();
  if (!errors.empty()) throw std::invalid_argument("FrameMatcher: " + join(errors));
  check_image(current_, "FrameMatcher (current)");
  const bool ok = !current_.klt_pyramid.empty() &&
                  current_.klt_pyramid_options.window_px == options_.klt.window_px &&
                  current_.klt_pyramid_options.normalise_window_frac ==
                      options_.klt.normalise_window_frac &&
                  current_.klt_pyramid_options.max_level >= options_.klt.max_level;
  if (!ok) build_klt_pyramid(current_, options_.klt, false);  // only tracked into: no derivatives
}

FrameMatcher::FrameMatcher(ImageFeatures current, const MatcherOptions& options,
                           const FeatureExtractor* wide_baseline_extractor)
    : FrameMatcher(std::move(current), options) {
  if (current_.keypoints.empty()) wide_baseline_extractor_ = wide_baseline_extractor;
}

bool FrameMatcher::current_keypoints() {
  if (wide_baseline_extractor_ != nullptr) {
    const ScopedMs ms(&timings_.wide_baseline_ms);
    wide_baseline_extractor_->add_wide_baseline(current_);
    wide_baseline_extractor_ = nullptr;
  }
  return !current_.keypoints.empty();
}

void FrameMatcher::set_klt_prior(int64_t key_id, std::vector<PointMatch> prior,
                                 std::vector<int> skip) {
  klt_starts_[key_id] = KltStart{std::move(prior), std::move(skip)};
}

const KltStart& FrameMatcher::klt_start(int64_t key_id) const {
  static const KltStart kNone;
  const auto it = klt_starts_.find(key_id);
  return it == klt_starts_.end() ? kNone : it->second;
}

const TwoViewMatches* FrameMatcher::adopt_speculative(int64_t key_id) {
  const auto held = speculative_.find(key_id);
  if (held == speculative_.end()) return nullptr;
  const auto it = two_view_.emplace(key_id, std::move(held->second)).first;
  speculative_.erase(held);
  return &it->second;
}

const TwoViewMatches& FrameMatcher::two_view(int64_t key_id, const ImageFeatures& key) {
  if (const auto it = two_view_.find(key_id); it != two_view_.end()) return it->second;
  if (const TwoViewMatches* held = adopt_speculative(key_id)) return *held;
  const KltStart& start = klt_start(key_id);
  return two_view_
      .emplace(key_id,
               match_two_view(key, current_, options_, start.prior, &timings_, start.skip))
      .first->second;
}

bool FrameMatcher::concurrent() { return cv::getNumThreads() > 1; }

void FrameMatcher::compute_two_views(std::span<const KeyRef> keys) {
  struct Task {
    KeyRef key;
    std::span<const PointMatch> prior;
    std::span<const int> skip;
    TwoViewMatches result;
    MatchTimings timings;
    std::exception_ptr error;
  };
  std::vector<Task> tasks;
  tasks.reserve(keys.size());
  for (const KeyRef& k : keys) {
    if (k.features == nullptr)
      throw std::invalid_argument("FrameMatcher::compute_two_views: key " + std::to_string(k.id) +
                                  " has no features");
    if (two_view_.count(k.id) != 0) continue;
    if (k.speculative && !concurrent()) continue;  // on one thread: work for nothing
    if (speculative_.count(k.id) != 0) {
      if (!k.speculative) adopt_speculative(k.id);  // asked for now: as two_view() would
      continue;
    }
    // An id given twice is computed once, held back only if every mention is speculative.
    if (const auto same = std::find_if(tasks.begin(), tasks.end(),
                                       [&](const Task& t) { return t.key.id == k.id; });
        same != tasks.end()) {
      same->key.speculative = same->key.speculative && k.speculative;
      continue;
    }
    Task t;
    t.key = k;
    const KltStart& start = klt_start(k.id);
    t.prior = start.prior;
    t.skip = start.skip;
    tasks.push_back(std::move(t));
  }
  if (tasks.empty()) return;
  // Each task reads the current frame, its key image and its prior and writes only its own
  // Task: no shared state (OpenCV's KLT and RANSAC are reentrant and deterministic).
  auto run = [&](Task& t) noexcept {
    try {
      t.result =
          match_two_view(*t.key.features, current_, options_, t.prior, &t.timings, t.skip);
    } catch (...) {
      t.error = std::current_exception();
    }
  };
  // concurrent_tasks.hpp says why plain threads. cv::getNumThreads() <= 1 (the one-core
  // benchmarks) keeps everything on the calling thread.
  if (concurrent()) {
    run_concurrently(tasks.size(), [&](size_t i) { run(tasks[i]); });
  } else {
    for (Task& t : tasks) run(t);
  }
  std::exception_ptr first_error;
  for (Task& t : tasks) {  // in the callers' order, whichever task finished first
    timings_.lines_ms += t.timings.lines_ms;
    timings_.klt_ms += t.timings.klt_ms;
    timings_.essential_ms += t.timings.essential_ms;
    timings_.three_view_ms += t.timings.three_view_ms;
    timings_.wide_baseline_ms += t.timings.wide_baseline_ms;
    if (t.error) {
      // A speculative task's error is dropped with it: two_view() recomputes that key when it
      // is asked for, and throws then, as it would have without the speculation.
      if (!first_error && !t.key.speculative) first_error = t.error;
      continue;
    }
    (t.key.speculative ? speculative_ : two_view_).emplace(t.key.id, std::move(t.result));
  }
  if (first_error) std::rethrow_exception(first_error);
}

const TwoViewMatches& FrameMatcher::two_view_for_control(int64_t key_id, const ImageFeatures& key) {
  const TwoViewMatches& klt = two_view(key_id, key);
  if (klt.n_points() >= options_.orb_fallback_below_points || key.keypoints.empty() ||
      !current_keypoints()) {
    return klt;
  }
  auto it = control_.find(key_id);
  if (it != control_.end()) return it->second;
  TwoViewMatches r = klt;
  const TwoViewMatches& w = wide_baseline(key_id, key);
  if (w.n_points() >= options_.orb_fallback_below_points && w.n_points() > r.n_points()) {
    r.points = w.points;
    r.point_candidates = w.point_candidates;
    r.essential_found = w.essential_found;
    r.E_b_a = w.E_b_a;
    r.points_from_orb = true;
  }
  return control_.emplace(key_id, std::move(r)).first->second;
}

const TwoViewMatches* FrameMatcher::computed_two_view(int64_t key_id) const {
  const auto it = two_view_.find(key_id);
  return it == two_view_.end() ? nullptr : &it->second;
}

const ThreeViewMatches& FrameMatcher::three_view(int64_t x_id, const ImageFeatures& x, int64_t y_id,
                                                 const ImageFeatures& y) {
  const auto key = std::make_pair(x_id, y_id);
  auto it = three_view_.find(key);
  if (it != three_view_.end()) return it->second;
  const TwoViewMatches& xm = two_view(x_id, x);
  const TwoViewMatches& ym = two_view(y_id, y);
  ThreeViewMatches r;
  {
    const ScopedMs ms(&timings_.three_view_ms);
    r = verify_three_view(x, xm, current_, y, ym, options_);
  }
  return three_view_.emplace(key, std::move(r)).first->second;
}

const TwoViewMatches& FrameMatcher::wide_baseline(int64_t key_id, const ImageFeatures& key) {
  auto it = wide_.find(key_id);
  if (it != wide_.end()) return it->second;
  current_keypoints();
  return wide_.emplace(key_id, match_wide_baseline(key, current_, options_, &timings_))
      .first->second;
}

}  // namespace pepper::core::features
