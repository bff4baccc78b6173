// The teach's live warnings (session/teach_feedback.hpp, issue 25): features and rotation in,
// warnings out, on either side of each bound, with the hold and the hysteresis that keep a
// warning from blinking on noisy counts.
#include <gtest/gtest.h>

#include <string>

#include "session/teach_feedback.hpp"

namespace pepper::app {
namespace {

using K = TeachWarningKind;

TeachFeedbackLimits limits() {
  TeachFeedbackLimits l;  // the defaults the app derives from its defaults
  l.min_view_features = 40;
  l.min_verified_matches = 15;
  l.max_heading_change_rad = 0.35;
  l.min_frame_gap = 3;
  l.half_view_rad = 0.49;
  l.hold_frames = 3;
  l.clear_ratio = 1.25;
  return l;
}

/// A textured view, standing still, sharing plenty with its key image.
TeachView rich_view() {
  TeachView v;
  v.n_lines = 30;
  v.n_points = 90;
  v.verified_with_key = 80;
  v.turned_over_gap_rad = 0.0;
  v.heading_since_key_rad = 0.0;
  return v;
}

TEST(TeachFeedback, RichStillViewHasNoWarning) {
  EXPECT_TRUE(teach_feedback(rich_view(), limits()).warnings.empty());
}

TEST(TeachFeedback, BlankWallWarnsAndSaysWhatToDo) {
  TeachView v = rich_view();
  v.n_lines = 5;
  v.n_points = 34;  // 39 < 40
  v.verified_with_key = 3;  // few features also means few matches: one warning, not two
  const TeachFeedback f = teach_feedback(v, limits());
  ASSERT_EQ(f.warnings.size(), 1u);
  EXPECT_EQ(f.warnings[0].kind, K::kFewFeatures);
  EXPECT_NE(f.warnings[0].text.find("39 lines + points"), std::string::npos) << f.warnings[0].text;
  EXPECT_NE(f.warnings[0].text.find("needs 40"), std::string::npos);
  EXPECT_NE(f.warnings[0].text.find("poster"), std::string::npos);
  v.n_points = 35;  // exactly the bound: a key image here is not weak
  v.verified_with_key = 80;
  EXPECT_TRUE(teach_feedback(v, limits()).warnings.empty());
}

TEST(TeachFeedback, FewFeaturesClearsOnlyWellAboveTheBoundAndAfterTheHold) {
  TeachView blank = rich_view();
  blank.n_lines = 0;
  blank.n_points = 10;
  TeachFeedback f = teach_feedback(blank, limits());
  ASSERT_TRUE(f.has(K::kFewFeatures));
  // 45 is above 40 but below 1.25 x 40 = 50: the shown warning stays (and its hold restarts).
  TeachView hovering = rich_view();
  hovering.n_lines = 10;
  hovering.n_points = 35;
  for (int i = 0; i < 10; ++i) {
    f = teach_feedback(hovering, limits(), f);
    ASSERT_TRUE(f.has(K::kFewFeatures)) << "frame " << i;
  }
  // Rich again: held for hold_frames (3) frames in all, then gone.
  f = teach_feedback(rich_view(), limits(), f);
  EXPECT_TRUE(f.has(K::kFewFeatures));
  f = teach_feedback(rich_view(), limits(), f);
  EXPECT_TRUE(f.has(K::kFewFeatures));
  f = teach_feedback(rich_view(), limits(), f);
  EXPECT_FALSE(f.has(K::kFewFeatures));
  EXPECT_TRUE(f.warnings.empty());
  // Not shown before: 45 is no warning at all.
  EXPECT_TRUE(teach_feedback(hovering, limits()).warnings.empty());
}

TEST(TeachFeedback, TurnFasterThanTheKeyImageGapWarns) {
  TeachView v = rich_view();
  v.turned_over_gap_rad = 0.34;  // under 0.35 in 3 frames: key images can follow
  EXPECT_TRUE(teach_feedback(v, limits()).warnings.empty());
  v.turned_over_gap_rad = 0.45;  // 26 deg in 3 frames > 20 deg
  const TeachFeedback f = teach_feedback(v, limits());
  ASSERT_EQ(f.warnings.size(), 1u);
  EXPECT_EQ(f.warnings[0].kind, K::kTurningFast);
  EXPECT_NE(f.warnings[0].text.find("26 deg in 3 frames"), std::string::npos) << f.warnings[0].text;
  EXPECT_NE(f.warnings[0].text.find("20 deg"), std::string::npos);
  EXPECT_NE(f.warnings[0].text.find("Slow down"), std::string::npos);
}

TEST(TeachFeedback, KeyImagesMoreThanHalfAViewApartWarn) {
  TeachView v = rich_view();
  v.heading_since_key_rad = 0.48;  // 27.5 deg: just under half the 56-degree view
  EXPECT_TRUE(teach_feedback(v, limits()).warnings.empty());
  v.heading_since_key_rad = 0.60;
  const TeachFeedback f = teach_feedback(v, limits());
  ASSERT_TRUE(f.has(K::kTurningFast));
  EXPECT_NE(f.warnings[0].text.find("34 deg since the last key image"), std::string::npos)
      << f.warnings[0].text;
  // Without odometry (no heading known) there is nothing to judge.
  v.heading_since_key_rad.reset();
  v.turned_over_gap_rad.reset();
  EXPECT_TRUE(teach_feedback(v, limits()).warnings.empty());
}

TEST(TeachFeedback, OverlapWithTheKeyImageCollapsingWarnsOnlyWhenTheViewHasFeatures) {
  TeachView v = rich_view();
  v.verified_with_key = 15;  // what the replay needs: fine
  EXPECT_TRUE(teach_feedback(v, limits()).warnings.empty());
  v.verified_with_key = 9;
  TeachFeedback f = teach_feedback(v, limits());
  ASSERT_EQ(f.warnings.size(), 1u);
  EXPECT_EQ(f.warnings[0].kind, K::kOverlapLost);
  EXPECT_NE(f.warnings[0].text.find("only 9 features"), std::string::npos) << f.warnings[0].text;
  EXPECT_NE(f.warnings[0].text.find("needs 15"), std::string::npos);
  // Nor against a poor key image (a blank wall): turning from it to a rich view matches nothing
  // at any speed; few_features said so when it was taken.
  v.key_features = 20;
  EXPECT_TRUE(teach_feedback(v, limits()).warnings.empty());
  v.key_features = 40;
  EXPECT_TRUE(teach_feedback(v, limits()).has(K::kOverlapLost));
  // The first frame has no key image to compare with.
  v.verified_with_key.reset();
  EXPECT_TRUE(teach_feedback(v, limits()).warnings.empty());
}

TEST(TeachFeedback, SeveralWarningsAtOnceInKindOrderAndJson) {
  TeachView v = rich_view();
  v.verified_with_key = 4;
  v.turned_over_gap_rad = 0.5;
  const TeachFeedback f = teach_feedback(v, limits());
  ASSERT_EQ(f.warnings.size(), 2u);
  EXPECT_EQ(f.warnings[0].kind, K::kTurningFast);
  EXPECT_EQ(f.warnings[1].kind, K::kOverlapLost);
  const nlohmann::json j = to_json(f);
  ASSERT_EQ(j.at("warnings").size(), 2u);
  EXPECT_EQ(j["warnings"][0]["kind"], "turning_fast");
  EXPECT_EQ(j["warnings"][1]["kind"], "overlap_lost");
  EXPECT_EQ(to_json(TeachFeedback{}).at("warnings").size(), 0u);
}

TEST(TeachFeedback, BadLimitsAreNamed) {
  TeachFeedbackLimits l = limits();
  l.min_view_features = 0;
  l.hold_frames = 0;
  const auto e = l.validate();
  ASSERT_EQ(e.size(), 2u);
  EXPECT_NE(e[0].find("min_view_features"), std::string::npos);
  EXPECT_NE(e[1].find("hold_frames"), std::string::npos);
  EXPECT_TRUE(limits().validate().empty());
}

}  // namespace
}  // namespace pepper::app
