// Verified matches under a light change (issue 26): real image pairs (Pepper's own key images,
// shared/data/pepper_qut_tmap, and visp-images-data's mbt/cube sequence) with the current image's
// brightness scaled by x0.6 and x1.4, globally and as a gradient across the image. The verified
// point and line counts must keep a stated fraction of the unchanged pair's, and the verified
// sets must stay clean: a point is an outlier when it lies off the unchanged pair's epipolar
// geometry (Sampson distance above 2 px at QVGA, 4 px at VGA), a line when the key line it joins was matched to a
// different current line in the unchanged pair.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/features/image_features.hpp"
#include "core/features/matching.hpp"
#include "core/features/real_image_data.hpp"

namespace pepper::core::features {
namespace {

const std::string kPepper = test_data::kPepper + "Edge_01/";
using test_data::cube_camera;
using test_data::kVispCube;
using test_data::pepper_qvga;

enum class Light { kSame, kDark, kBright, kGradient };
const char* name(Light l) {
  switch (l) {
    case Light::kSame: return "x1.0";
    case Light::kDark: return "x0.6";
    case Light::kBright: return "x1.4";
    case Light::kGradient: return "x0.6..1.4";
  }
  return "?";
}

// The light change of a scene seen by a camera with fixed exposure: every grey level scaled
// (saturating at 255); the gradient runs from x0.6 at the left edge to x1.4 at the right.
cv::Mat relight(const cv::Mat& gray, Light l) {
  cv::Mat out(gray.size(), CV_8UC1);
  for (int y = 0; y < gray.rows; ++y) {
    for (int x = 0; x < gray.cols; ++x) {
      double g = 1.0;
      if (l == Light::kDark) g = 0.6;
      if (l == Light::kBright) g = 1.4;
      if (l == Light::kGradient) g = 0.6 + 0.8 * x / std::max(1, gray.cols - 1);
      out.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(g * gray.at<uint8_t>(y, x));
    }
  }
  return out;
}

struct PairResult {
  int points = 0, lines = 0;
  int point_outliers = 0, line_outliers = 0;
};

double sampson_px(const cv::Matx33d& E, const cv::Point2d& a, const cv::Point2d& b, double f) {
  const cv::Vec3d xa(a.x, a.y, 1.0), xb(b.x, b.y, 1.0);
  const cv::Vec3d Ea = E * xa, Etb = E.t() * xb;
  const double num = xb.dot(Ea);
  const double den = Ea[0] * Ea[0] + Ea[1] * Ea[1] + Etb[0] * Etb[0] + Etb[1] * Etb[1];
  return den > 0 ? std::abs(num) / std::sqrt(den) * f : 0.0;
}

// The normalised grey levels under test: the defaults (features.klt.normalise_window_frac), with
// the camera's pitch for the planar essential model (the robot's head pitch in the app).
MatcherOptions matcher(double camera_pitch_rad) {
  MatcherOptions o;
  o.essential.camera_pitch_rad = camera_pitch_rad;
  return o;
}
FeatureExtractorOptions extractor() { return {}; }

// Matches key -> relit current, judged against key -> unchanged current.
PairResult measure(const FeatureExtractor& ex, const cv::Mat& key_gray, const cv::Mat& cur_gray,
                   Light l, double focal_px, double camera_pitch_rad) {
  // 2 px at QVGA (the unchanged pair's own E is an estimate too), as many pixels of a larger
  // image as there are of QVGA's.
  constexpr double kMaxSampsonQvgaPx = 2.0;
  const double px_scale = key_gray.cols / 320.0;
  const ImageFeatures key = ex.extract(key_gray);
  const ImageFeatures ref_cur = ex.extract(cur_gray);
  const TwoViewMatches ref = match_two_view(key, ref_cur, matcher(camera_pitch_rad));
  const ImageFeatures cur = ex.extract(relight(cur_gray, l));
  const TwoViewMatches m = match_two_view(key, cur, matcher(camera_pitch_rad));
  PairResult r;
  r.points = m.n_points();
  r.lines = m.n_lines();
  for (const PointMatch& p : m.points) {
    if (ref.essential_found &&
        sampson_px(ref.E_b_a, p.a_norm, p.b_norm, focal_px) > kMaxSampsonQvgaPx * px_scale) {
      ++r.point_outliers;
    }
  }
  for (const LineMatch& lm : m.lines) {
    const auto it = std::find_if(ref.lines.begin(), ref.lines.end(),
                                 [&](const LineMatch& q) { return q.idx_a == lm.idx_a; });
    if (it == ref.lines.end()) continue;  // not matched in the unchanged pair: unknown
    // The same image line as the unchanged pair's match (the relit image's segment may be
    // longer or shorter): both endpoints within 2 px of its supporting line, directions within
    // 2 degrees.
    const LineSegment& a = cur.lines[static_cast<size_t>(lm.idx_b)];
    const LineSegment& b = ref_cur.lines[static_cast<size_t>(it->idx_b)];
    const cv::Point2f db = b.p1_px - b.p0_px, da = a.p1_px - a.p0_px;
    const double nb = std::hypot(db.x, db.y), na = std::hypot(da.x, da.y);
    auto off_line = [&](const cv::Point2f& p) {
      const cv::Point2f q = p - b.p0_px;
      return std::abs(q.x * db.y - q.y * db.x) / nb;
    };
    const double cos_angle = std::abs(da.x * db.x + da.y * db.y) / (na * nb);
    if (off_line(a.p0_px) > 2.0 || off_line(a.p1_px) > 2.0 || cos_angle < std::cos(5.0 * M_PI / 180)) {
      ++r.line_outliers;
    }
  }
  return r;
}

struct Totals {
  PairResult sum[4];
};

Totals run_pairs(const FeatureExtractor& ex, const std::vector<std::pair<cv::Mat, cv::Mat>>& pairs,
                 double focal_px, double camera_pitch_rad, const char* what) {
  Totals t;
  for (const auto& [key, cur] : pairs) {
    for (const Light l : {Light::kSame, Light::kDark, Light::kBright, Light::kGradient}) {
      const PairResult r = measure(ex, key, cur, l, focal_px, camera_pitch_rad);
      PairResult& s = t.sum[static_cast<int>(l)];
      s.points += r.points;
      s.lines += r.lines;
      s.point_outliers += r.point_outliers;
      s.line_outliers += r.line_outliers;
    }
  }
  for (const Light l : {Light::kSame, Light::kDark, Light::kBright, Light::kGradient}) {
    const PairResult& s = t.sum[static_cast<int>(l)];
    std::printf("%s %-10s points %4d (outliers %3d)  lines %4d (outliers %3d)\n", what, name(l),
                s.points, s.point_outliers, s.lines, s.line_outliers);
  }
  return t;
}

cv::Mat read_gray(const std::string& path) {
  const cv::Mat img = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (img.empty()) throw std::runtime_error("cannot read " + path);
  return to_gray(img);
}

// Bounds: every light keeps >= 85 % of the unchanged pair's verified points and <= 2 % point
// outliers. Lines keep >= 85 % except at x1.4 (lines_bright): brightening saturates the light
// parts of the image and the edges there are gone (no method gets them back). A line "outlier"
// here is a line match that disagrees with the unchanged pair's; the comparison itself has a
// floor (re-detected segments differ a little): 2.0 % of the lines disagree at x0.97 on the
// Pepper pairs, hence a bound of 6 % rather than 2 %.
// Point outliers: 2 % everywhere. Where the light saturates (x1.4 and the gradient's bright
// side) the cube's white faces leave flat 255 patches that tracks slide along; the gain check
// (matching.cpp, plausible_gain) rejects them (measured 0 and 1.9 % with it, 2.9 % without).
void expect_robust(const Totals& t, double lines_bright) {
  const PairResult& same = t.sum[0];
  for (const Light l : {Light::kDark, Light::kBright, Light::kGradient}) {
    const PairResult& s = t.sum[static_cast<int>(l)];
    EXPECT_GE(s.points, 0.85 * same.points) << name(l);
    EXPECT_GE(s.lines, (l == Light::kBright ? lines_bright : 0.85) * same.lines) << name(l);
    EXPECT_LE(s.point_outliers, 0.02 * s.points + 1) << name(l);
    EXPECT_LE(s.line_outliers, 0.06 * s.lines + 1) << name(l);
  }
}

TEST(IlluminationData, PepperKeyImagesUnderLightChanges) {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(kPepper)) {
    if (e.path().extension() == ".png") files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 12u);
  std::vector<std::pair<cv::Mat, cv::Mat>> pairs;
  for (size_t i = 0; i + 1 < files.size() && pairs.size() < 10; i += 2) {
    pairs.emplace_back(read_gray(files[i]), read_gray(files[i + 1]));
  }
  const FeatureExtractor ex(pepper_qvga(), extractor());
  // Measured with the default window (31 px at QVGA) and the gain check (points, lines; of 1145,
  // 453 unchanged): x0.6 1138, 434; x1.4 1010, 252; gradient 1130, 426. With the planar
  // essential model at this pitch (features.matcher.essential.planar): 1133, 454; 1127, 433;
  // 984, 253; 1134, 425 (the bounds hold for both). On raw grey levels
  // (klt.normalise_window_frac = 0; 1073, 471 unchanged, before the gain check): x0.6 8 points,
  // x1.4 239.
  // The pitch of this data's camera: 0.18 rad down (bench_navigator_real's planar variant).
  expect_robust(run_pairs(ex, pairs, pepper_qvga().fx_px, 0.18, "pepper"), 0.5);
}

TEST(IlluminationData, VispCubeUnderLightChanges) {
  if (!std::filesystem::exists(kVispCube + "image0000.pgm")) {
    GTEST_SKIP() << "visp-images-data not installed";
  }
  std::vector<std::pair<cv::Mat, cv::Mat>> pairs;
  for (int i : {0, 20, 40, 60}) {
    char a[32], b[32];
    std::snprintf(a, sizeof(a), "image%04d.pgm", i);
    std::snprintf(b, sizeof(b), "image%04d.pgm", i + 5);
    pairs.emplace_back(read_gray(kVispCube + a), read_gray(kVispCube + b));
  }
  const FeatureExtractor ex(cube_camera(), extractor());
  // Measured with the default window (61 px at VGA) and the gain check (of 322 points, 201 lines
  // unchanged): x0.6 310, 196; x1.4 309, 193; gradient 313, 198. On raw grey levels (322 points
  // unchanged, before the gain check): x0.6 0 points, x1.4 47.
  // A hand-held camera: no pitch to state (the planar model's general refit takes its motion).
  expect_robust(run_pairs(ex, pairs, cube_camera().fx_px, 0.0, "cube"), 0.85);
}

}  // namespace
}  // namespace pepper::core::features
