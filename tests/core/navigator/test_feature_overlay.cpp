// Feature overlays (display data for the teach UI): the caps, the mapping of matches to the
// current image's pixels, the navigator's overlay against IN agreeing with its counts, and the
// teacher exposing the last frame's features.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/features/feature_overlay.hpp"
#include "core/mapping/teacher.hpp"
#include "core/navigator/navigator.hpp"
#include "core/navigator/test_world.hpp"

namespace pepper::core {
namespace {

using features::FeatureOverlay;

features::ImageFeatures many_features(int n_lines, int n_corners) {
  features::ImageFeatures f;
  for (int i = 0; i < n_lines; ++i) {
    features::LineSegment s;
    s.p0_px = {static_cast<float>(i), 1.0f};
    s.p1_px = {static_cast<float>(i), 50.0f};
    f.lines.push_back(s);
  }
  for (int i = 0; i < n_corners; ++i) f.corners_px.emplace_back(static_cast<float>(i), 2.0f);
  return f;
}

TEST(FeatureOverlay, DetectedKeepsTheFirstUpToTheCaps) {
  const FeatureOverlay few = features::detected_overlay(many_features(3, 5));
  EXPECT_EQ(few.lines.size(), 3u);
  EXPECT_EQ(few.points_px.size(), 5u);
  EXPECT_EQ(few.lines[2].p1_px, cv::Point2f(2.0f, 50.0f));
  EXPECT_EQ(few.key_index, -1);
  const FeatureOverlay capped = features::detected_overlay(many_features(400, 700));
  EXPECT_EQ(capped.lines.size(), FeatureOverlay::kMaxLines);
  EXPECT_EQ(capped.points_px.size(), FeatureOverlay::kMaxPoints);
  EXPECT_EQ(capped.points_px.back(), cv::Point2f(FeatureOverlay::kMaxPoints - 1.0f, 2.0f));
}

TEST(FeatureOverlay, MatchedUsesTheCurrentImagePositions) {
  const features::ImageFeatures current = many_features(10, 0);
  features::TwoViewMatches m;
  m.lines.push_back({0, 7, 0.1f});  // key line 0 <-> current line 7
  features::PointMatch p;
  p.a_px = {1.0f, 1.0f};
  p.b_px = {30.5f, 40.25f};
  m.points.push_back(p);
  const FeatureOverlay o = features::matched_overlay(m, current, 4);
  EXPECT_EQ(o.key_index, 4);
  ASSERT_EQ(o.lines.size(), 1u);
  EXPECT_EQ(o.lines[0].p0_px, cv::Point2f(7.0f, 1.0f));
  ASSERT_EQ(o.points_px.size(), 1u);
  EXPECT_EQ(o.points_px[0], p.b_px);  // where it is now, not where it was in the key image
}

TEST(FeatureOverlay, NavigatorOverlayIsTheMatchesWithIn) {
  const auto& tour = test::shared_tour();
  navigator::Navigator nav(tour.map);
  int checked = 0;
  for (int i = 10; i < 40; ++i) {
    const navigator::StepResult r = nav.step(tour.frames[i]);
    const navigator::Telemetry& t = r.telemetry;
    if (t.state == navigator::NavState::kNotLocalized) {
      EXPECT_TRUE(t.overlay.lines.empty() && t.overlay.points_px.empty());
      continue;
    }
    EXPECT_EQ(t.overlay.key_index, t.in) << "frame " << i;
    if (t.switched) continue;  // the counts are of the IN before the switch
    EXPECT_EQ(t.overlay.lines.size(),
              std::min<std::size_t>(t.n_lines_next, FeatureOverlay::kMaxLines));
    EXPECT_EQ(t.overlay.points_px.size(),
              std::min<std::size_t>(t.n_points_next, FeatureOverlay::kMaxPoints));
    for (const auto& p : t.overlay.points_px) {
      EXPECT_TRUE(p.x >= -0.5f && p.y >= -0.5f && p.x < tour.camera.width_px &&
                  p.y < tour.camera.height_px)
          << p.x << ", " << p.y;
    }
    checked += t.overlay.points_px.empty() ? 0 : 1;
  }
  EXPECT_GT(checked, 10);  // the tour's own frames: localised and matching almost every frame
}

TEST(FeatureOverlay, TeacherExposesTheLastFramesFeatures) {
  const auto& tour = test::shared_tour();
  mapping::Teacher teacher(tour.camera, tour.teach_options);
  EXPECT_THROW(teacher.last_frame_features(), std::logic_error);
  teacher.add_frame(tour.frames[0]);
  teacher.add_frame(tour.frames[1]);
  const features::ImageFeatures& f = teacher.last_frame_features();
  EXPECT_EQ(f.gray.data, tour.frames[1].gray.data);  // this frame's, not the key image's
  EXPECT_FALSE(f.lines.empty());
  EXPECT_FALSE(f.corners_px.empty());
  teacher.finish();
  EXPECT_THROW(teacher.last_frame_features(), std::logic_error);
}

}  // namespace
}  // namespace pepper::core
