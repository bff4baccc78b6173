#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/mapping/key_image_selector.hpp"

namespace pepper::core::mapping {
namespace {

TEST(KeyImageSelector, ScriptedCounts) {
  KeyImageSelectorOptions o;
  o.epsilon = 10;
  o.min_frame_gap = 1;  // the paper's rule
  o.relative = 0.0;
  KeyImageSelector s(o);
  EXPECT_EQ(s.key(), 0);
  EXPECT_FALSE(s.on_frame(1, 50));
  EXPECT_FALSE(s.on_frame(2, 10));  // equal to epsilon: not below
  EXPECT_EQ(*s.on_frame(3, 9), 2);  // below: Ic-1 = 2 becomes key
  EXPECT_EQ(s.key(), 2);
  EXPECT_FALSE(s.on_frame(4, 30));
  EXPECT_EQ(*s.on_frame(5, 3), 4);
  EXPECT_EQ(*s.on_frame(6, 0), 5);
  EXPECT_FALSE(s.on_frame(7, 40));
  EXPECT_EQ(*s.finish(), 7);  // last frame stored
  EXPECT_EQ(s.key_images(), (std::vector<int64_t>{0, 2, 4, 5, 7}));
  EXPECT_THROW(s.on_frame(8, 50), std::invalid_argument);
}

// The heading rule (issue 29): a turn gets key images inside it even where the counts stay high
// (a corner facing a blank wall keeps the few features it has); the count rule is untouched.
TEST(KeyImageSelector, HeadingChangeTakesTheFrameBefore) {
  KeyImageSelectorOptions o;
  o.epsilon = 10;
  o.min_frame_gap = 2;
  o.relative = 0.0;
  o.max_heading_change_rad = 0.35;
  KeyImageSelector s(o);
  EXPECT_FALSE(s.on_frame(1, 50, 0.1));
  EXPECT_FALSE(s.on_frame(2, 50, 0.35));  // equal to the bound: not above
  EXPECT_EQ(*s.on_frame(3, 50, 0.4), 2);  // above: Ic-1 = 2, the last frame within the bound
  EXPECT_EQ(s.last_rule(), KeyImageRule::kHeading);
  EXPECT_FALSE(s.on_frame(4, 50, 0.5));  // candidate 3: gap 1 < 2, even though it turned
  EXPECT_EQ(*s.on_frame(5, 50, 0.6), 4);
  EXPECT_FALSE(s.on_frame(6, 50));  // no odometry: only the count rule
  EXPECT_EQ(*s.on_frame(7, 5), 6);
  EXPECT_EQ(s.last_rule(), KeyImageRule::kFeatures);
  EXPECT_EQ(*s.finish(), 7);
  EXPECT_EQ(s.last_rule(), KeyImageRule::kLast);

  o.max_heading_change_rad = 0.0;  // off
  KeyImageSelector off(o);
  EXPECT_FALSE(off.on_frame(1, 50, 3.0));
  EXPECT_FALSE(off.on_frame(2, 50, 3.0));
  EXPECT_FALSE(off.on_frame(3, 50, 3.0));
  o.max_heading_change_rad = -0.1;
  ASSERT_EQ(o.validate().size(), 1u);
  EXPECT_NE(o.validate()[0].find("max_heading_change_rad"), std::string::npos);
}

TEST(KeyImageSelector, MinFrameGap) {
  KeyImageSelectorOptions o;
  o.epsilon = 10;
  o.min_frame_gap = 3;
  o.relative = 0.0;
  KeyImageSelector s(o);
  EXPECT_FALSE(s.on_frame(1, 0));   // candidate 1: gap 1 < 3
  EXPECT_FALSE(s.on_frame(2, 0));   // candidate 1: gap 1
  EXPECT_FALSE(s.on_frame(3, 0));   // candidate 2: gap 2
  EXPECT_EQ(*s.on_frame(4, 0), 3);  // candidate 3: gap 3
  EXPECT_FALSE(s.on_frame(5, 0));
  EXPECT_FALSE(s.on_frame(6, 0));
  EXPECT_EQ(*s.on_frame(7, 5), 6);
  o.min_frame_gap = 0;
  EXPECT_EQ(o.validate().size(), 1u);
}

TEST(KeyImageSelector, RelativeThresholdFollowsEachKeyImagesReference) {
  KeyImageSelectorOptions o;
  o.epsilon = 20;
  o.min_frame_gap = 3;
  o.relative = 0.5;
  KeyImageSelector s(o);
  EXPECT_EQ(s.threshold(), 20.0);      // reference not known yet: epsilon
  EXPECT_FALSE(s.on_frame(1, 300));
  EXPECT_FALSE(s.on_frame(2, 200));    // frame key + 2: reference 200 -> threshold 100
  EXPECT_EQ(s.reference(), 200);
  EXPECT_EQ(s.threshold(), 100.0);
  EXPECT_FALSE(s.on_frame(3, 120));
  EXPECT_FALSE(s.on_frame(4, 100));    // equal: not below
  EXPECT_EQ(*s.on_frame(5, 99), 4);    // below half the reference: Ic-1 = 4
  EXPECT_EQ(s.last_threshold(), 100.0);
  EXPECT_EQ(s.reference(), -1);        // new key image: reference measured again
  EXPECT_EQ(s.threshold(), 20.0);
  EXPECT_FALSE(s.on_frame(6, 30));     // key 4 + 2: reference 30 -> threshold max(20, 15)
  EXPECT_EQ(s.threshold(), 20.0);      // the absolute floor wins on a poor image
  EXPECT_FALSE(s.on_frame(7, 20));
  EXPECT_EQ(*s.on_frame(8, 19), 7);
  // A reference near epsilon: the threshold is capped at max_fraction (0.7) of it, so a key
  // image needs 30 % of the reference gone instead of firing at once.
  EXPECT_FALSE(s.on_frame(9, 22));      // key 7 + 2: reference 22 -> min(max(20, 11), 15.4)
  EXPECT_NEAR(s.threshold(), 15.4, 1e-12);
  EXPECT_FALSE(s.on_frame(10, 19));     // below epsilon but not below the cap: no key image
  EXPECT_FALSE(s.on_frame(11, 16));
  EXPECT_EQ(*s.on_frame(12, 15), 11);
  // Nothing shared at the reference frame: the threshold stays at least 1.
  EXPECT_FALSE(s.on_frame(13, 0));      // key 11 + 2: reference 0 -> threshold 1 (gap 1)
  EXPECT_EQ(s.threshold(), 1.0);
  EXPECT_FALSE(s.on_frame(14, 0));      // gap 2
  EXPECT_EQ(*s.on_frame(15, 0), 14);
  o.max_fraction = 0.5;                 // not above relative
  EXPECT_EQ(o.validate().size(), 1u);
  o.max_fraction = 1.0;
  EXPECT_TRUE(o.validate().empty());
  o.relative = 1.0;
  EXPECT_EQ(o.validate().size(), 1u);
  o.relative = -0.1;
  EXPECT_EQ(o.validate().size(), 1u);
}

TEST(KeyImageSelector, LastFrameAlreadyKeyAndBadInput) {
  KeyImageSelectorOptions paper;
  paper.min_frame_gap = 1;
  KeyImageSelector s(paper);
  EXPECT_EQ(*s.on_frame(1, 0), 1);  // Ic-1 is the key itself: Ic becomes the key image
  EXPECT_FALSE(s.finish());         // the last frame already is the key image
  EXPECT_EQ(s.key_images(), (std::vector<int64_t>{0, 1}));
  KeyImageSelector t;
  EXPECT_THROW(t.on_frame(2, 100), std::invalid_argument);  // frames must be consecutive
  KeyImageSelectorOptions bad;
  bad.epsilon = 0;
  ASSERT_EQ(bad.validate().size(), 1u);
  EXPECT_NE(bad.validate()[0].find("epsilon"), std::string::npos);
  EXPECT_THROW(KeyImageSelector{bad}, std::invalid_argument);
}

// Synthetic count model: a tour of straight parts and one 90-degree turn, one frame per 3 cm of
// travel (0.15 m/s at 5 Hz) or per 0.05 rad while turning on the spot-ish. Shared features decay
// with the distance travelled and, much faster, with the yaw change since the key image:
//   count(k, c) = 200 exp(-|s_c - s_k| / 1.5 m - |yaw_c - yaw_k| / 0.35 rad).
TEST(KeyImageSelector, DenserKeyImagesInTurns) {
  std::vector<double> s_m, yaw;
  auto push = [&](double ds, double dyaw) {
    s_m.push_back(s_m.empty() ? 0.0 : s_m.back() + ds);
    yaw.push_back(yaw.empty() ? 0.0 : yaw.back() + dyaw);
  };
  for (int i = 0; i < 150; ++i) push(0.03, 0.0);    // frames 0..149 straight 4.5 m
  for (int i = 0; i < 32; ++i) push(0.016, 0.049);  // 150..181 turn ~90 deg
  for (int i = 0; i < 150; ++i) push(0.03, 0.0);    // straight again
  auto count = [&](int64_t k, int64_t c) {
    return static_cast<int>(
        200.0 * std::exp(-std::abs(s_m[c] - s_m[k]) / 1.5 - std::abs(yaw[c] - yaw[k]) / 0.35));
  };
  KeyImageSelectorOptions o;
  o.epsilon = 60;
  o.min_frame_gap = 1;
  KeyImageSelector sel(o);
  for (int64_t c = 1; c < static_cast<int64_t>(s_m.size()); ++c)
    sel.on_frame(c, count(sel.key(), c));
  sel.finish();
  const auto& keys = sel.key_images();
  int straight = 0, turning = 0;
  for (int64_t k : keys) (k > 150 && k <= 182 ? turning : straight) += 1;
  // Per frame: straight parts have 300 frames, the turn 32.
  const double straight_density = straight / 300.0, turn_density = turning / 32.0;
  EXPECT_GE(turning, 3);
  EXPECT_GT(turn_density, 3.0 * straight_density)
      << "turn " << turning << " keys / 32 frames, straight " << straight << " / 300";
  for (size_t i = 1; i < keys.size(); ++i) EXPECT_GT(keys[i], keys[i - 1]);
  EXPECT_EQ(keys.front(), 0);
  EXPECT_EQ(keys.back(), static_cast<int64_t>(s_m.size()) - 1);
}

}  // namespace
}  // namespace pepper::core::mapping
