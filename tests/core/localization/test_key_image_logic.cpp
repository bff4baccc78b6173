#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/localization/key_image_logic.hpp"

namespace pepper::core::localization {
namespace {

TEST(InitialLocalization, ArgmaxThenBetterNeighbour) {
  // i = 3 (40); neighbours 2 (25) and 4 (31): j = 4 -> IP 3, IN 4, INN 5.
  const std::vector<int> counts = {2, 10, 25, 40, 31, 8, 0};
  const auto r = localize_from_counts(counts);
  ASSERT_TRUE(r.segment);
  EXPECT_EQ(r.best, 3);
  EXPECT_EQ(r.neighbour, 4);
  EXPECT_EQ(*r.segment, (Segment{3, 4, 5}));
  // Better neighbour before: IP = j, IN = i.
  const std::vector<int> before = {2, 10, 35, 40, 31, 8, 0};
  EXPECT_EQ(*localize_from_counts(before).segment, (Segment{2, 3, 4}));
}

TEST(InitialLocalization, EdgesTiesAndPrefilteredEntries) {
  // Best is the first key image: only neighbour 1.
  EXPECT_EQ(*localize_from_counts(std::vector<int>{50, 3, 1}).segment, (Segment{0, 1, 2}));
  // Best is the final image: IP = n-2, IN = final, no INN.
  EXPECT_EQ(*localize_from_counts(std::vector<int>{1, 3, 50}).segment,
            (Segment{1, 2, std::nullopt}));
  // Tie on the argmax: lowest index; tie between neighbours: forward (i + 1).
  const auto tie = localize_from_counts(std::vector<int>{20, 30, 30, 20, 5});
  EXPECT_EQ(tie.best, 1);
  EXPECT_EQ(*tie.segment, (Segment{1, 2, 3}));
  // -1 = not evaluated by the prefilter: never wins, and loses as a neighbour.
  const auto pruned = localize_from_counts(std::vector<int>{-1, -1, 30, -1, 12, -1});
  EXPECT_EQ(pruned.best, 2);
  EXPECT_EQ(*pruned.segment, (Segment{2, 3, 4}));  // neighbours -1 / -1: forward
  const auto pruned2 = localize_from_counts(std::vector<int>{-1, 4, 30, -1, 12, -1});
  EXPECT_EQ(*pruned2.segment, (Segment{1, 2, 3}));
}

TEST(InitialLocalization, TooFewMatchesIsNotLocalised) {
  const auto r = localize_from_counts(std::vector<int>{3, 14, 2});
  EXPECT_FALSE(r.segment);
  EXPECT_EQ(r.best, 1);
  EXPECT_FALSE(localize_from_counts(std::vector<int>{-1, -1}).segment);
  EXPECT_THROW(localize_from_counts(std::vector<int>{40}), std::invalid_argument);
}

SwitchCounts three_view(int next, int prev) {
  SwitchCounts c;
  c.three_view_next = next;
  c.three_view_prev = prev;
  return c;
}

SwitchCounts two_view(int nn, int n, int p) {
  SwitchCounts c;
  c.two_view_next_next = nn;
  c.two_view_next = n;
  c.two_view_prev = p;
  return c;
}

TEST(SwitchCriterion, ThreeAndTwoViewRules) {
  EXPECT_EQ(switch_criterion(three_view(10, 9)), SwitchCriterion::kThreeView);
  EXPECT_EQ(switch_criterion(three_view(9, 9)), SwitchCriterion::kNone);  // strict
  EXPECT_EQ(switch_criterion(two_view(30, 29, 12)), SwitchCriterion::kTwoView);
  EXPECT_EQ(switch_criterion(two_view(30, 31, 12)), SwitchCriterion::kNone);  // needs both
  EXPECT_EQ(switch_criterion(two_view(30, 12, 31)), SwitchCriterion::kNone);
  SwitchCounts both = two_view(30, 10, 10);
  both.three_view_next = 5;
  both.three_view_prev = 1;
  EXPECT_EQ(switch_criterion(both), SwitchCriterion::kBoth);
}

SwitcherOptions paper_rule() {
  SwitcherOptions o;
  o.min_next_scale_ratio = 0.0;
  return o;
}

TEST(KeyImageSwitcher, NeedsTwoConsecutiveFrames) {
  KeyImageSwitcher s(segment_ending_at(1, 5), 5, paper_rule());
  EXPECT_EQ(s.update(three_view(10, 5), false).event, SwitchEvent::kNone);  // 1st
  EXPECT_EQ(s.update(three_view(4, 5), false).event, SwitchEvent::kNone);   // broken streak
  EXPECT_EQ(s.update(two_view(30, 20, 10), false).event, SwitchEvent::kNone);
  // Second consecutive frame, by the other criterion: switch.
  const SwitchUpdate u = s.update(three_view(10, 5), false);
  EXPECT_EQ(u.event, SwitchEvent::kSwitched);
  EXPECT_EQ(u.streak, 2);
  EXPECT_EQ(s.segment(), (Segment{1, 2, 3}));
  // The streak restarts after a switch.
  EXPECT_EQ(s.update(three_view(10, 5), false).event, SwitchEvent::kNone);
  EXPECT_EQ(s.update(three_view(10, 5), false).event, SwitchEvent::kSwitched);
  EXPECT_EQ(s.segment(), (Segment{2, 3, 4}));
}

TEST(KeyImageSwitcher, ScriptedTourToTheEnd) {
  // 4 key images: (0,1,2) -> (1,2,3) -> (2,3,-) -> arrival at 3 -> complete.
  KeyImageSwitcher s(segment_ending_at(1, 4), 4, paper_rule());
  const SwitchCounts want = three_view(20, 10), no = three_view(10, 20);
  const std::vector<std::pair<SwitchCounts, bool>> script = {
      {no, false},   {want, false}, {want, false},                 // switch to IN = 2
      {want, false}, {no, false},   {want, false}, {want, false},  // switch to IN = 3 (final)
      {want, false}, {want, false}, {want, false},                 // counts ignored now: no INN
      {no, true},    {no, false},   {no, true},    {no, true}};    // arrival seen twice in a row
  std::vector<SwitchEvent> events;
  std::vector<int> next;
  for (const auto& [counts, reached] : script) {
    events.push_back(s.update(counts, reached).event);
    next.push_back(s.segment().next);
  }
  const std::vector<int> expected_next = {1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3};
  EXPECT_EQ(next, expected_next);  // indices only increase
  EXPECT_EQ(events[2], SwitchEvent::kSwitched);
  EXPECT_EQ(events[6], SwitchEvent::kSwitched);
  for (int k = 7; k < 13; ++k) EXPECT_EQ(events[k], SwitchEvent::kNone) << k;
  EXPECT_EQ(events[13], SwitchEvent::kTourComplete);
  EXPECT_TRUE(s.tour_complete());
  EXPECT_FALSE(s.segment().next_next);
  // Stays complete.
  EXPECT_EQ(s.update(want, false).event, SwitchEvent::kTourComplete);
}

TEST(KeyImageSwitcher, ConfigurableStreakAndValidation) {
  SwitcherOptions one = paper_rule();
  one.consecutive_frames = 1;
  KeyImageSwitcher s(segment_ending_at(1, 3), 3, one);
  EXPECT_EQ(s.update(three_view(2, 1), false).event, SwitchEvent::kSwitched);
  EXPECT_EQ(s.update({}, true).event, SwitchEvent::kTourComplete);
  SwitcherOptions bad;
  bad.consecutive_frames = 0;
  ASSERT_EQ(bad.validate().size(), 1u);
  EXPECT_NE(bad.validate()[0].find("consecutive_frames"), std::string::npos);
  EXPECT_THROW(KeyImageSwitcher(segment_ending_at(1, 3), 3, bad), std::invalid_argument);
  EXPECT_THROW(KeyImageSwitcher(Segment{0, 2, 3}, 4), std::invalid_argument);
  EXPECT_THROW(segment_ending_at(0, 3), std::invalid_argument);
}

TEST(KeyImageSwitcher, ScaleGuardAndAnUnknownRatio) {
  KeyImageSwitcher s(segment_ending_at(1, 6), 6);  // defaults: guard 0.9, passed 1.05
  SwitchCounts c = three_view(50, 20);             // three-view rule holds...
  c.next_scale_ratio = 0.8;                        // ...but IN still looks small: far from it
  SwitchUpdate u = s.update(c, false);
  EXPECT_EQ(u.streak, 0);
  EXPECT_EQ(u.criteria_bits, 1 | kCriterionGuardBlocked);
  c.next_scale_ratio = 0.95;
  EXPECT_EQ(s.update(c, false).event, SwitchEvent::kNone);
  EXPECT_EQ(s.update(c, false).event, SwitchEvent::kSwitched);
  EXPECT_EQ(s.segment().next, 2);
  // Unknown scale (too few points to measure it): the guard cannot judge and does not block,
  // the paper's rule decides (blocking stalled replay in front of plain walls).
  c.next_scale_ratio = std::nan("");
  u = s.update(c, false);
  EXPECT_EQ(u.streak, 1);
  EXPECT_EQ(u.criteria_bits, 1);
  EXPECT_EQ(s.update(c, false).event, SwitchEvent::kSwitched);
  EXPECT_EQ(s.segment().next, 3);
  SwitchCounts none = three_view(10, 20);  // ...and without a paper rule, nothing happens
  none.next_scale_ratio = std::nan("");
  EXPECT_EQ(s.update(none, false).streak, 0);
  // ...unless the caller says a blind switch is not allowed yet (the navigator: too little
  // time on the segment): then the guard blocks the unknown ratio too.
  SwitchCounts early = c;
  early.blind_switch_allowed = false;
  u = s.update(early, false);
  EXPECT_EQ(u.streak, 0);
  EXPECT_EQ(u.criteria_bits, 1 | kCriterionGuardBlocked);
  EXPECT_EQ(s.update(early, false).event, SwitchEvent::kNone);
  EXPECT_EQ(s.segment().next, 3);
  early.next_scale_ratio = 0.95;  // a measured ratio is judged on its own
  EXPECT_EQ(s.update(early, false).streak, 1);
  s.update(none, false);  // reset the streak
  // No paper rule and IN's points larger than taught: the scale alone wants no switch (the
  // "passed IN" addition by scale is gone; the caller's travel verdicts cover a passed IN).
  SwitchCounts passed = three_view(10, 20);
  passed.next_scale_ratio = 1.5;
  u = s.update(passed, false);
  EXPECT_EQ(u.criteria_bits, 0);
  EXPECT_EQ(s.update(passed, false).event, SwitchEvent::kNone);
  EXPECT_EQ(s.segment().next, 3);
  SwitcherOptions bad;
  bad.min_next_scale_ratio = 2.5;
  EXPECT_EQ(bad.validate().size(), 1u);
}

// "IN ahead by odometry": the caller says the estimate is still well before IN; a paper rule
// that holds with the scale guard satisfied is blocked, and switches once the verdict is gone.
TEST(KeyImageSwitcher, TheEstimateBeforeInBlocksThePaperRules) {
  KeyImageSwitcher s(segment_ending_at(1, 6), 6);
  SwitchCounts c = three_view(50, 20);  // the three-view rule holds...
  c.next_scale_ratio = 0.95;            // ...and the scale guard lets it through...
  c.before_by_odometry = true;          // ...but the odometry says IN is still ahead
  for (int i = 0; i < 4; ++i) {
    const SwitchUpdate u = s.update(c, false);
    EXPECT_EQ(u.event, SwitchEvent::kNone);
    EXPECT_EQ(u.streak, 0);
    EXPECT_EQ(u.criteria_bits, 1 | kCriterionGuardBlocked);
  }
  EXPECT_EQ(s.segment().next, 1);
  c.before_by_odometry = false;
  EXPECT_EQ(s.update(c, false).event, SwitchEvent::kNone);
  EXPECT_EQ(s.update(c, false).event, SwitchEvent::kSwitched);
  EXPECT_EQ(s.segment().next, 2);
}

// "Passed IN by distance": the caller says the robot drove well past IN with the scale unknown;
// with no paper rule and no ratio, that alone makes the switch wanted (two frames, as for any).
TEST(KeyImageSwitcher, PassedByDistanceSwitchesWithoutAnyCount) {
  KeyImageSwitcher s(segment_ending_at(1, 6), 6);
  SwitchCounts blind;  // nothing matched: no rule, unknown ratio
  EXPECT_EQ(s.update(blind, false).streak, 0);
  blind.passed_by_distance = true;
  SwitchUpdate u = s.update(blind, false);
  EXPECT_EQ(u.streak, 1);
  EXPECT_EQ(u.criteria_bits, kCriterionPassedByDistance);
  EXPECT_EQ(s.update(blind, false).event, SwitchEvent::kSwitched);
  EXPECT_EQ(s.segment().next, 2);
  // On the final segment the tour ends by arrival only: distance alone does not complete it.
  KeyImageSwitcher last(segment_ending_at(5, 6), 6);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(last.update(blind, false).event, SwitchEvent::kNone);
}

TEST(MedianScaleRatio, GrowsToOneAtTheKeyPose) {
  // Points at depth 4 m seen from 1 m behind the key pose: image coordinates scale by 4/5.
  std::vector<cv::Point2d> key = {{-0.3, 0.1}, {0.2, -0.2}, {0.4, 0.3}, {-0.1, -0.35}, {0.0, 0.2}};
  std::vector<cv::Point2d> behind, at;
  for (const auto& p : key) {
    behind.push_back(p * 0.8);
    at.push_back(p + cv::Point2d(0.05, 0.0));  // same scale, shifted (rotation)
  }
  EXPECT_NEAR(*median_scale_ratio(key, behind), 0.8, 1e-12);
  EXPECT_NEAR(*median_scale_ratio(key, at), 1.0, 1e-12);
  EXPECT_FALSE(median_scale_ratio(std::vector<cv::Point2d>(key.begin(), key.begin() + 2),
                                  std::vector<cv::Point2d>(at.begin(), at.begin() + 2)));
}


// Vertical wall lines (door frames, poster edges) at depth 4 m projected from depth z_m (camera
// on the axis, looking at the wall): x_norm = X / z, y_norm = Y / z.
LineCorrespondence wall_line(double x_m, double y0_m, double y1_m, double cut_a, double cut_b,
                             double z_key_m, double z_cur_m) {
  // cut_*: fraction of the segment a detector kept at each end (fragmentation differs per view)
  LineCorrespondence c;
  c.a0_norm = {x_m / z_key_m, (y0_m + cut_a) / z_key_m};
  c.a1_norm = {x_m / z_key_m, (y1_m - cut_a) / z_key_m};
  c.b0_norm = {x_m / z_cur_m, (y0_m + cut_b) / z_cur_m};
  c.b1_norm = {x_m / z_cur_m, (y1_m - 2 * cut_b) / z_cur_m};
  return c;
}

TEST(LineScaleRatio, ParallelSeparationsScaleLikePointsAndIgnoreFragmentation) {
  // Key pose 4 m from the wall, current 5 m: the scene appears at 4/5 of the key's size.
  std::vector<LineCorrespondence> lines;
  const double xs[] = {-1.2, -0.7, 0.3, 0.9, 1.4};
  for (int i = 0; i < 5; ++i) lines.push_back(wall_line(xs[i], -0.8, 0.6, 0.05 * i, 0.1, 4.0, 5.0));
  std::vector<double> ratios;
  append_line_scale_ratios(lines, 0.05, 0.05, ratios);
  ASSERT_EQ(ratios.size(), 10u);  // every pair of the five vertical lines
  for (double r : ratios) EXPECT_NEAR(r, 0.8, 1e-9);

  // At the key pose: 1.
  std::vector<LineCorrespondence> at;
  for (int i = 0; i < 5; ++i) at.push_back(wall_line(xs[i], -0.8, 0.6, 0.0, 0.2, 4.0, 4.0));
  ratios.clear();
  append_line_scale_ratios(at, 0.05, 0.05, ratios);
  ASSERT_FALSE(ratios.empty());
  EXPECT_NEAR(*median_ratio(ratios), 1.0, 1e-9);
}

TEST(LineScaleRatio, SkipsNonParallelAndTooClosePairs) {
  LineCorrespondence vertical = wall_line(0.0, -0.5, 0.5, 0.0, 0.0, 4.0, 4.0);
  LineCorrespondence horizontal;
  horizontal.a0_norm = horizontal.b0_norm = {-0.2, 0.1};
  horizontal.a1_norm = horizontal.b1_norm = {0.2, 0.1};
  LineCorrespondence near_twin = wall_line(0.1, -0.5, 0.5, 0.0, 0.0, 4.0, 4.0);  // 0.025 apart
  std::vector<double> ratios;
  const std::vector<LineCorrespondence> lines = {vertical, horizontal, near_twin};
  append_line_scale_ratios(lines, 0.05, 0.05, ratios);
  EXPECT_TRUE(ratios.empty());
  EXPECT_FALSE(median_ratio(ratios).has_value());
  // A degenerate (zero-length) segment is skipped, not divided by.
  LineCorrespondence dot;
  const std::vector<LineCorrespondence> with_dot = {vertical, dot};
  append_line_scale_ratios(with_dot, 0.05, 0.05, ratios);
  EXPECT_TRUE(ratios.empty());
}

}  // namespace
}  // namespace pepper::core::localization
