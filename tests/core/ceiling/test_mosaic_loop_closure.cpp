// MosaicBuilder's loop closure on synthetic teaches (issue 24: "a synthetic teach along a loop
// closes with a landmark pose error below a stated bound"; docs/method/ceiling.md, "Closing a
// loop"). The ceiling is synthetic_ceiling.hpp's (points on a jittered 0.1 m grid, random
// descriptors); the observations get the errors that make a real chain drift:
// - 3 mm of Gaussian noise per axis on every landmark position (about 1/3 px at 120 px/m);
// - 10 % of the descriptor bits flipped per sighting (two sightings ~50 bits apart, max 64);
// - a forward stretch that grows across the view, x' = x (1 + k (x - 0.8 m)), k = 0.01 / m: a
//   canonical view slightly off in scale towards its far rows. The chain comes out ~1 % long, as
//   the renders' chained distances were 0.8-1.3 % longer than the truth (ceiling.md).
// The figures are printed: build/tests/core_tests --gtest_filter='MosaicLoopClosure*'
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/ceiling/mosaic_builder.hpp"
#include "synthetic_ceiling.hpp"

namespace pepper::core::ceiling {
namespace {

using test_support::SyntheticCeiling;

constexpr double kStepM = 0.02;  // between frames: 0.3 m/s at 15 Hz

using Path = test_support::SyntheticPath;
using Errors = test_support::ChainErrors;

Path rounded_rectangle(double overlap_m) {
  return test_support::rounded_rectangle(overlap_m, kStepM);
}

struct TeachRun {
  Path path;
  SyntheticCeiling ceiling;
  Mosaic mosaic;
  std::vector<MosaicFrameResult> frames;
  std::vector<LoopClosure> closures;
  int64_t implausible_closures = 0;
  std::map<int64_t, int> point_of_id;  // kept landmark -> true ceiling point
  std::map<int64_t, double> error_of_id;
  int duplicated_points = 0;  // true points with more than one kept landmark
};

TeachRun teach(const Path& path, const MosaicBuilderOptions& options, const Errors& e,
               uint32_t seed) {
  TeachRun run;
  run.path = path;
  // The loop spans x in [-1, 5], y in [0, 4]; the view reaches 1.3 m ahead and 0.6 m aside.
  run.ceiling = test_support::make_synthetic_ceiling(seed, -2.5, 90, -1.5, 70);
  std::mt19937 rng(seed + 100);
  test_support::ChainErrorInjector errors(e, rng);
  MosaicBuilder builder(options);
  for (const PlanarPose& T_world_base : path.truth) {
    CeilingObservation o = test_support::see_synthetic(run.ceiling, T_world_base, rng, 10);
    errors.apply(o);
    builder.add_frame(o);
  }
  run.mosaic = builder.mosaic();
  run.frames = builder.frames();
  run.closures = builder.loop_closures();
  run.implausible_closures = builder.implausible_closures();
  if (run.mosaic.landmarks.empty()) return run;
  // Each kept landmark's true point: the nearest true descriptor (a sighting is ~26 bits from
  // it, a junk descriptor ~128 from every one). The mosaic frame is the first true pose.
  cv::Mat descriptors;
  for (const MosaicLandmark& l : run.mosaic.landmarks) descriptors.push_back(l.descriptor);
  std::vector<cv::DMatch> truth_of;
  cv::BFMatcher(cv::NORM_HAMMING).match(descriptors, run.ceiling.descriptors, truth_of);
  std::map<int, int> landmarks_of_point;
  for (const cv::DMatch& m : truth_of) {
    if (m.distance > 80) continue;  // junk (never kept in practice)
    const MosaicLandmark& l = run.mosaic.landmarks[static_cast<size_t>(m.queryIdx)];
    run.point_of_id[l.id] = m.trainIdx;
    run.error_of_id[l.id] =
        cv::norm(path.truth[0].apply(l.position_m) - run.ceiling.points_world[m.trainIdx]);
    ++landmarks_of_point[m.trainIdx];
  }
  for (const auto& [point, n] : landmarks_of_point) run.duplicated_points += n > 1 ? 1 : 0;
  return run;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * static_cast<double>(v.size() - 1))];
}

// The landmarks at the closure: those whose true point lies within 1.5 m of the start, mapped at
// the loop's beginning and passed under again at its end.
std::vector<double> closure_errors(const TeachRun& run) {
  std::vector<double> out;
  const cv::Point2d start(run.path.truth[0].x_m, run.path.truth[0].y_m);
  for (const auto& [id, point] : run.point_of_id)
    if (cv::norm(run.ceiling.points_world[point] - start) < 1.5)
      out.push_back(run.error_of_id.at(id));
  return out;
}

// The largest error of one frame-to-frame motion of the recorded poses: a chain that snaps onto
// the old landmarks jumps by its drift there.
double max_jump_m(const TeachRun& run) {
  double out = 0.0;
  for (size_t k = 1; k < run.frames.size(); ++k) {
    const PlanarPose d_est =
        run.frames[k - 1].T_mosaic_base.inverse() * run.frames[k].T_mosaic_base;
    const PlanarPose d_true = run.path.truth[k - 1].inverse() * run.path.truth[k];
    out = std::max(out, std::hypot(d_est.x_m - d_true.x_m, d_est.y_m - d_true.y_m));
  }
  return out;
}

// The recorded pose's error in the mosaic frame (the first true pose).
double pose_error_m(const TeachRun& run, size_t k) {
  const PlanarPose truth = run.path.truth[0].inverse() * run.path.truth[k];
  const PlanarPose& est = run.frames[k].T_mosaic_base;
  return std::hypot(est.x_m - truth.x_m, est.y_m - truth.y_m);
}

MosaicBuilderOptions without_loops() {
  MosaicBuilderOptions o;
  o.loop.enabled = false;
  return o;
}

void expect_same_build(const TeachRun& a, const TeachRun& b) {
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (size_t k = 0; k < a.frames.size(); ++k) {
    EXPECT_EQ(a.frames[k].localised, b.frames[k].localised) << k;
    EXPECT_EQ(a.frames[k].T_mosaic_base.x_m, b.frames[k].T_mosaic_base.x_m) << k;
    EXPECT_EQ(a.frames[k].T_mosaic_base.y_m, b.frames[k].T_mosaic_base.y_m) << k;
    EXPECT_EQ(a.frames[k].T_mosaic_base.theta_rad, b.frames[k].T_mosaic_base.theta_rad) << k;
    EXPECT_EQ(a.frames[k].inliers, b.frames[k].inliers) << k;
    EXPECT_EQ(a.frames[k].added, b.frames[k].added) << k;
    ASSERT_EQ(a.frames[k].sightings.size(), b.frames[k].sightings.size()) << k;
    for (size_t i = 0; i < a.frames[k].sightings.size(); ++i)
      EXPECT_EQ(a.frames[k].sightings[i].id, b.frames[k].sightings[i].id) << k;
  }
  ASSERT_EQ(a.mosaic.landmarks.size(), b.mosaic.landmarks.size());
  for (size_t i = 0; i < a.mosaic.landmarks.size(); ++i) {
    const MosaicLandmark &la = a.mosaic.landmarks[i], &lb = b.mosaic.landmarks[i];
    EXPECT_EQ(la.id, lb.id);
    EXPECT_EQ(la.position_m, lb.position_m);
    EXPECT_EQ(la.orientation_rad, lb.orientation_rad);
    EXPECT_EQ(la.observations, lb.observations);
  }
}

// The loop of the issue. Bounds: at the closure, the landmarks of the loop's end are placed
// through the correction's interpolation, exact only at the closing frame; the first pass's
// landmarks there are off by the noise and the first metres of chain (up to ~13 mm). Measured
// over the three seeds: max 18-29 mm, median 5-7 mm with closure, against 91-134 mm max without.
// The bounds (max 40 mm, median 15 mm, and at most 0.4 of the open chain's max) leave ~40 % over
// the worst seed and are a third of the open chain's error at best.
TEST(MosaicLoopClosure, ALoopClosesWithTheLandmarksAtTheClosurePlacedWithinTheBound) {
  const Path path = rounded_rectangle(1.5);
  const double loop_m = kStepM * static_cast<double>(path.back_at_start);  // ~18.3 m
  for (uint32_t seed : {7u, 8u, 9u}) {
    const TeachRun open = teach(path, without_loops(), {}, seed);
    const TeachRun closed = teach(path, {}, {}, seed);
    const std::vector<double> e_open = closure_errors(open), e_closed = closure_errors(closed);
    std::printf(
        "[ loop ] seed %u, %.1f m: without closure: closure landmarks (%zu) median %.1f, p95 "
        "%.1f, max %.1f mm; pose 1.4 m before the start %.1f mm; largest frame-to-frame error "
        "%.1f mm; points mapped twice %d\n",
        seed, loop_m, e_open.size(), 1e3 * percentile(e_open, 0.5), 1e3 * percentile(e_open, 0.95),
        1e3 * percentile(e_open, 1.0), 1e3 * pose_error_m(open, path.back_at_start - 70),
        1e3 * max_jump_m(open), open.duplicated_points);
    std::printf(
        "[ loop ]          with closure: closure landmarks (%zu) median %.1f, p95 %.1f, max "
        "%.1f mm; pose 1.4 m before the start %.1f mm; largest frame-to-frame error %.1f mm; "
        "points mapped twice %d\n",
        e_closed.size(), 1e3 * percentile(e_closed, 0.5), 1e3 * percentile(e_closed, 0.95),
        1e3 * percentile(e_closed, 1.0), 1e3 * pose_error_m(closed, path.back_at_start - 70),
        1e3 * max_jump_m(closed), closed.duplicated_points);
    for (const LoopClosure& c : closed.closures)
      std::printf(
          "[ loop ]          closure at frame %lld (%.2f m; start at %.2f m): %d old landmarks "
          "misplaced by %.1f mm, correction (%.1f, %.1f) mm %.2f deg, %d landmarks and %d "
          "frames moved\n",
          static_cast<long long>(c.frame), c.to_travelled_m, c.from_travelled_m, c.old_inliers,
          1e3 * c.error_before_m, 1e3 * c.T_corrected_chained.x_m, 1e3 * c.T_corrected_chained.y_m,
          c.T_corrected_chained.theta_rad * 180 / M_PI, c.landmarks_moved, c.frames_moved);

    // The premise: without closure the chain arrives off by more than the builder's RANSAC
    // threshold (3 cm), so it snaps onto the old landmarks in one frame.
    ASSERT_GT(percentile(e_open, 1.0), 0.05) << seed;
    ASSERT_GT(max_jump_m(open), 0.03) << seed;
    EXPECT_TRUE(open.closures.empty());

    // One closure, as the start's landmarks come into view (the view reaches 1.3 m ahead).
    ASSERT_EQ(closed.closures.size(), 1u) << seed;
    const LoopClosure& c = closed.closures[0];
    EXPECT_GE(c.frame, static_cast<int64_t>(path.back_at_start) - 1.5 / kStepM) << seed;
    EXPECT_LE(c.frame, static_cast<int64_t>(path.back_at_start)) << seed;
    EXPECT_TRUE(closed.frames[static_cast<size_t>(c.frame)].closed_loop);
    EXPECT_LT(c.from_travelled_m, 1.5) << seed;  // the old landmarks are the start's
    EXPECT_GT(c.error_before_m, 0.03) << seed;
    EXPECT_GE(c.old_inliers, MosaicBuilderOptions{}.loop.min_inliers);

    EXPECT_LT(percentile(e_closed, 1.0), 0.040) << seed;
    EXPECT_LT(percentile(e_closed, 0.5), 0.015) << seed;
    EXPECT_LT(percentile(e_closed, 1.0), 0.4 * percentile(e_open, 1.0)) << seed;
    // No snap: the recorded poses move smoothly through the closure (noise: ~3 mm).
    EXPECT_LT(max_jump_m(closed), 0.010) << seed;
    EXPECT_EQ(closed.duplicated_points, 0) << seed;
    for (const MosaicFrameResult& f : closed.frames) EXPECT_TRUE(f.localised);
    EXPECT_TRUE(closed.mosaic.validate().empty());
  }
}

// The same loop with bounds on a correction tighter than its drift (the closure moves the frame
// by a few centimetres): refused as implausible, the chain stays as without closure. With the
// defaults (10 cm + 3 % of the loop, 0.05 rad + 5 % of its turns) it closed above; on a
// generated room's plain tiles a false closure would have moved the chain by 5 m and 3 rad.
TEST(MosaicLoopClosure, ACorrectionBeyondWhatAChainDriftsIsRefused) {
  const Path path = rounded_rectangle(1.5);
  MosaicBuilderOptions tight;
  tight.loop.max_correction_m = 0.01;
  tight.loop.max_correction_per_m = 0.0;
  const TeachRun run = teach(path, tight, {}, 7);
  const TeachRun open = teach(path, without_loops(), {}, 7);
  EXPECT_TRUE(run.closures.empty());
  EXPECT_GE(run.implausible_closures, 1);
  // Refused closures leave the chain as without the feature up to the start's landmarks.
  for (size_t k = 0; k + 100 < path.back_at_start; ++k) {
    ASSERT_EQ(run.frames[k].localised, open.frames[k].localised) << k;
    EXPECT_EQ(run.frames[k].T_mosaic_base.x_m, open.frames[k].T_mosaic_base.x_m) << k;
  }
  tight = {};
  tight.loop.max_correction_rad = 0.0;
  tight.loop.max_correction_per_rad = 0.0;
  EXPECT_TRUE(teach(path, tight, {}, 7).closures.empty());
  EXPECT_EQ(teach(path, {}, {}, 7).implausible_closures, 0);
}

// With a guided search narrower than the drift, the builder without closure does not find the
// start's landmarks and maps those ceiling points a second time; the closure matches them within
// its own (wider) radius and never creates a landmark for a frame landmark matched to an old one.
TEST(MosaicLoopClosure, TheStartIsNotMappedTwice) {
  const Path path = rounded_rectangle(1.5);
  MosaicBuilderOptions narrow = without_loops();
  narrow.search_radius_m = 0.08;
  const TeachRun open = teach(path, narrow, {}, 7);
  narrow.loop.enabled = true;
  const TeachRun closed = teach(path, narrow, {}, 7);
  std::printf("[ loop ] guided search 0.08 m: points mapped twice %d without closure, %d with\n",
              open.duplicated_points, closed.duplicated_points);
  ASSERT_GT(open.duplicated_points, 20);  // the premise
  EXPECT_EQ(closed.closures.size(), 1u);
  EXPECT_EQ(closed.duplicated_points, 0);
  EXPECT_LT(percentile(closure_errors(closed), 1.0), 0.040);
}

// Without noise the chain is exact: the old landmarks agree with it (misplaced by 0 <= the
// threshold) and join the fits; nothing is corrected and the poses stay exact.
TEST(MosaicLoopClosure, AnExactLoopAgreesAndIsNotCorrected) {
  const Path path = rounded_rectangle(1.5);
  const TeachRun run = teach(path, {}, {0.0, 0.0, 0.0}, 3);
  EXPECT_TRUE(run.closures.empty());
  for (size_t k = 0; k < run.frames.size(); ++k) {
    ASSERT_TRUE(run.frames[k].localised) << k;
    EXPECT_LT(pose_error_m(run, k), 1e-9) << k;
  }
  EXPECT_EQ(run.duplicated_points, 0);
  // Back at the start, the first frame's landmarks are seen again (they joined the fits).
  const auto& last = run.frames[path.back_at_start].sightings;
  const int64_t first_ids = static_cast<int64_t>(run.frames.front().sightings.size());
  EXPECT_GT(std::count_if(last.begin(), last.end(),
                          [&](const LandmarkSighting& s) { return s.id < first_ids; }),
            10);
}

// A tour that does not come back (the loop stopped 1.6 m before its start: the view reaches
// 1.3 m ahead) or turns on the spot (no distance travelled) is built exactly as without the
// feature, and so is the open tour of test_mosaic_builder.cpp.
TEST(MosaicLoopClosure, ToursThatDoNotComeBackAreBuiltExactlyAsWithoutIt) {
  Path almost = rounded_rectangle(0.0);
  almost.truth.resize(almost.back_at_start - static_cast<size_t>(1.6 / kStepM));
  Path spin;
  for (int k = 0; k <= 400; ++k) spin.truth.push_back({1.0, 2.0, 0.05 * k});  // 3.2 turns
  Path open;
  for (int k = 0; k < 200; ++k) {
    const double s = 0.02 * k;
    open.truth.push_back({0.2 + s, 0.15 * std::sin(s / 1.5), 0.1 * std::cos(s / 1.5) - 0.1});
  }
  for (const Path* path : {&almost, &spin, &open}) {
    const TeachRun with = teach(*path, {}, {}, 5);
    const TeachRun without = teach(*path, without_loops(), {}, 5);
    EXPECT_TRUE(with.closures.empty());
    expect_same_build(with, without);
  }
}

TEST(MosaicLoopClosure, DegenerateTeachesDoNotBreakIt) {
  const Path path = rounded_rectangle(1.5);
  const SyntheticCeiling c = test_support::make_synthetic_ceiling(1, -2.5, 90, -1.5, 70);
  std::mt19937 rng(4);
  // Blind from 3 m before the start on: every later frame has no pose, nothing is corrected.
  {
    MosaicBuilder builder;
    for (size_t k = 0; k < path.truth.size(); ++k) {
      const bool blind = k + 150 > path.back_at_start;
      builder.add_frame(test_support::see_synthetic(c, path.truth[k], rng, 0, blind));
    }
    EXPECT_TRUE(builder.loop_closures().empty());
    EXPECT_FALSE(builder.frames().back().localised);
    EXPECT_TRUE(builder.mosaic().validate().empty());
  }
  // At the closure the view is junk only (a person under the camera), then the ceiling again.
  {
    MosaicBuilder builder;
    for (size_t k = 0; k < path.truth.size(); ++k) {
      const bool hidden = k + 40 > path.back_at_start && k < path.back_at_start;
      builder.add_frame(test_support::see_synthetic(c, path.truth[k], rng, hidden ? 60 : 5,
                                                    /*blind=*/hidden));
    }
    EXPECT_TRUE(builder.mosaic().validate().empty());
    EXPECT_LE(builder.loop_closures().size(), 1u);
  }
  // Every closure setting at its limit.
  {
    MosaicBuilderOptions o;
    o.loop.min_gap_m = 1e-6;
    o.loop.min_inliers = 3;
    o.loop.min_error_m = 0.0;
    o.loop.search_radius_m = 1e-3;
    MosaicBuilder builder(o);
    for (size_t k = 0; k < path.truth.size(); k += 3)
      builder.add_frame(test_support::see_synthetic(c, path.truth[k], rng, 5));
    EXPECT_TRUE(builder.mosaic().validate().empty());
    for (const MosaicFrameResult& f : builder.frames()) EXPECT_TRUE(f.localised);
  }
  // Empty frames, and a single frame.
  {
    MosaicBuilder builder;
    EXPECT_TRUE(builder.add_frame(CeilingObservation{}).localised);
    EXPECT_FALSE(builder.add_frame(CeilingObservation{}).localised);
    EXPECT_TRUE(builder.loop_closures().empty());
  }
}

TEST(MosaicLoopClosure, RefusesBadOptionsNamingTheField) {
  const auto message = [](const MosaicBuilderOptions& o) { return test_support::builder_error(o); };
  MosaicBuilderOptions o;
  o.loop.min_gap_m = 0.0;
  EXPECT_NE(message(o).find("loop.min_gap_m"), std::string::npos);
  o = {};
  o.loop.search_radius_m = std::nan("");
  EXPECT_NE(message(o).find("loop.search_radius_m"), std::string::npos);
  o = {};
  o.loop.min_inliers = 2;
  EXPECT_NE(message(o).find("loop.min_inliers"), std::string::npos);
  o = {};
  o.loop.min_error_m = -0.01;
  EXPECT_NE(message(o).find("loop.min_error_m"), std::string::npos);
  o = {};
  o.loop.max_correction_per_rad = -1.0;
  EXPECT_NE(message(o).find("loop.max_correction_per_rad"), std::string::npos);
  o = {};
  o.loop.enabled = false;
  o.loop.min_error_m = -0.01;  // validated even when off: the options are what a map records
  EXPECT_NE(message(o).find("loop.min_error_m"), std::string::npos);
  EXPECT_EQ(message(MosaicBuilderOptions{}), "");
}

}  // namespace
}  // namespace pepper::core::ceiling
