// Teach on synthetic rendered images (tests/core/navigator/test_world.hpp): online and offline
// give the same map; key images are denser in the turn than on straight runs.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "core/mapping/teacher.hpp"
#include "core/navigator/test_world.hpp"

namespace pepper::core::mapping {
namespace {

using test::shared_tour;

TEST(Teacher, OnlineAndOfflineGiveTheSameMap) {
  const auto& tour = shared_tour();
  Teacher online(tour.camera, tour.teach_options);
  for (size_t i = 0; i < tour.frames.size(); ++i) {
    const TeachStep s = online.add_frame(tour.frames[i]);
    ASSERT_EQ(s.count, tour.steps[i].count) << "frame " << i;
    ASSERT_EQ(s.new_key_frame, tour.steps[i].new_key_frame) << "frame " << i;
  }
  const memory::VisualMemory map = online.finish();
  const memory::VisualMemory& offline = tour.map;
  ASSERT_EQ(map.key_images.size(), offline.key_images.size());
  for (size_t i = 0; i < map.key_images.size(); ++i) {
    EXPECT_EQ(map.key_images[i].source_frame_index, offline.key_images[i].source_frame_index);
    EXPECT_EQ(map.key_images[i].t_ns, offline.key_images[i].t_ns);
    EXPECT_EQ(map.key_images[i].features.lines.size(), offline.key_images[i].features.lines.size());
    EXPECT_EQ(map.key_images[i].features.corners_px, offline.key_images[i].features.corners_px);
  }
  EXPECT_EQ(map.key_images.front().source_frame_index, 0);
  EXPECT_EQ(map.key_images.back().source_frame_index, static_cast<int64_t>(tour.frames.size()) - 1);
  EXPECT_EQ(map.camera, tour.camera);
}

// Each key image keeps the distance given with its own frame, also when the selector takes the
// previous frame; a tour gives it with every frame or none, and never backwards.
TEST(Teacher, KeyImagesKeepTheirFramesTravelledDistance) {
  const auto& tour = shared_tour();
  auto travelled_at = [](size_t i) { return 0.045 * static_cast<double>(i) + 0.001; };
  Teacher teacher(tour.camera, tour.teach_options);
  for (size_t i = 0; i < tour.frames.size(); ++i) teacher.add_frame(tour.frames[i], travelled_at(i));
  const memory::VisualMemory map = teacher.finish();
  ASSERT_GE(map.key_images.size(), 3u);
  bool previous_frame_taken = false;
  for (size_t k = 0; k < tour.steps.size(); ++k) {
    if (tour.steps[k].new_key_frame && *tour.steps[k].new_key_frame != tour.steps[k].frame_number)
      previous_frame_taken = true;
  }
  EXPECT_TRUE(previous_frame_taken) << "the tour should exercise the previous-frame choice";
  for (const auto& key : map.key_images) {
    EXPECT_EQ(key.travelled_m, travelled_at(static_cast<size_t>(key.source_frame_index)))
        << "key image of frame " << key.source_frame_index;
  }

  Teacher mixed(tour.camera, tour.teach_options);
  mixed.add_frame(tour.frames[0], 0.0);
  EXPECT_THROW(mixed.add_frame(tour.frames[1]), std::invalid_argument);  // then unknown
  Teacher backwards(tour.camera, tour.teach_options);
  backwards.add_frame(tour.frames[0], 0.5);
  EXPECT_THROW(backwards.add_frame(tour.frames[1], 0.4), std::invalid_argument);
  Teacher none(tour.camera, tour.teach_options);
  none.add_frame(tour.frames[0]);
  none.add_frame(tour.frames[1]);
  EXPECT_TRUE(std::isnan(none.finish().key_images[0].travelled_m));
}

TEST(Teacher, KeyImagesDenserInTheTurn) {
  const auto& tour = shared_tour();
  // Frames 0..55 straight (2.5 m / 4.5 cm), 56..74 turn (0.84 m of arc), then straight.
  constexpr int kTurnBegin = 56, kTurnEnd = 75;
  const int n = static_cast<int>(tour.frames.size());
  int in_turn = 0, straight = 0;
  for (const auto& k : tour.map.key_images) {
    if (k.source_frame_index == 0 || k.source_frame_index == n - 1) continue;  // forced ones
    (k.source_frame_index >= kTurnBegin && k.source_frame_index < kTurnEnd ? in_turn : straight)++;
  }
  const double turn_density = in_turn / double(kTurnEnd - kTurnBegin);
  const double straight_density = straight / double(n - (kTurnEnd - kTurnBegin));
  EXPECT_GE(in_turn, 2);  // 3 before KLT started at the lines' shift (tracks survive the turn)
  EXPECT_GT(turn_density, 3.0 * straight_density)
      << in_turn << " key images in the turn, " << straight << " on straight runs";
  // Count model check: every selection happened on a count below the threshold in force,
  // which is epsilon under the paper's rule that this tour uses.
  for (const TeachStep& s : tour.steps) {
    if (s.frame_number > 0) {
      EXPECT_EQ(s.threshold, tour.teach_options.selector.epsilon);
    }
    if (s.new_key_frame) {
      EXPECT_LT(s.count, s.threshold);
    }
  }
}

/// The shared tour's frames with odometry: the path's poses seen from an odometry frame that is
/// not the world (rotated and shifted, as a robot's is), plus a heading that reads 3 % long.
std::vector<Frame> frames_with_odometry(const test::SharedTour& tour) {
  std::vector<Frame> frames = tour.frames;
  const double c = std::cos(0.7), s = std::sin(0.7);
  for (size_t i = 0; i < frames.size(); ++i) {
    const sim::Pose2D& p = tour.path[i];
    frames[i].odom = OdometryPose{10.0 + c * p.x_m - s * p.y_m, -4.0 + s * p.x_m + c * p.y_m,
                                  0.7 + 1.03 * p.yaw_rad};
  }
  return frames;
}

// Issue 29: with the robot's odometry, the 60-degree turn of the shared tour gets key images
// inside it from the heading rule alone, no two successive key images more than the bound (plus
// one frame's turn) apart in heading; each key image keeps its own frame's odometry. The count
// rule is kept out with the smallest threshold (a count below 1) and a first leg short enough
// that the view ahead keeps verified points with the first key image into the turn: from the
// tour's first frame, 2.6 m back, the planar model verifies no point at the turn's third frame,
// and the five-point model's 9 there were a chance fit (a rotation about a nearly horizontal
// axis, a motion no robot makes). Holds with either essential model (the parameter).
class TeacherHeadingRule : public ::testing::TestWithParam<bool> {};

TEST_P(TeacherHeadingRule, TakesKeyImagesInsideATurn) {
  const auto& tour = shared_tour();
  constexpr size_t kFirstFrame = 40;  // 0.7 m before the turn
  const std::vector<Frame> all = frames_with_odometry(tour);
  const std::vector<Frame> frames(all.begin() + kFirstFrame, all.end());
  TeachOptions options = tour.teach_options;
  options.matcher.essential.planar = GetParam();
  options.selector.epsilon = 1;
  options.selector.max_heading_change_rad = 0.35;
  Teacher teacher(tour.camera, options);
  int heading_keys = 0;
  for (const Frame& f : frames) {
    const TeachStep step = teacher.add_frame(f);
    if (step.new_key_rule) {
      ASSERT_EQ(*step.new_key_rule, KeyImageRule::kHeading)
          << "frame " << kFirstFrame + static_cast<size_t>(step.frame_number) << ", count "
          << step.count;
      ++heading_keys;
    }
    if (step.frame_number > 0) {
      ASSERT_TRUE(step.heading_change_rad.has_value());
    }
  }
  const memory::VisualMemory map = teacher.finish();
  // 60 degrees x 1.03 = 1.08 rad read: above 0.35 three times.
  EXPECT_EQ(heading_keys, 3);
  ASSERT_EQ(map.key_images.size(), 5u);          // first, three in the turn, last
  EXPECT_EQ(map.key_images[0].source_frame_index, static_cast<int64_t>(kFirstFrame));
  constexpr int kTurnBegin = 56, kTurnEnd = 75;  // frames of the arc (see KeyImagesDenserInTheTurn)
  // One frame turns 4.5 cm / 0.8 m = 0.056 rad (x 1.03 as read).
  const double max_step_rad = 0.35 + 1.03 * 0.045 / 0.8 + 1e-9;
  for (size_t k = 0; k < map.key_images.size(); ++k) {
    const memory::KeyImage& key = map.key_images[k];
    const size_t tour_frame = static_cast<size_t>(key.source_frame_index);  // the frame's own index
    const Frame& own = all[tour_frame];
    ASSERT_TRUE(key.odom.has_value());
    EXPECT_EQ(key.odom->x_m, own.odom->x_m);
    EXPECT_EQ(key.odom->yaw_rad, own.odom->yaw_rad);
    if (k > 0 && k + 1 < map.key_images.size()) {
      EXPECT_GE(static_cast<int>(tour_frame), kTurnBegin);
      EXPECT_LT(static_cast<int>(tour_frame), kTurnEnd);
    }
    if (k > 0) {
      EXPECT_LE(key.odom->yaw_rad - map.key_images[k - 1].odom->yaw_rad, max_step_rad);
    }
  }
  // Without odometry the heading rule does nothing: fewer key images, none of them by heading.
  Teacher blind(tour.camera, options);
  for (size_t i = kFirstFrame; i < tour.frames.size(); ++i) {
    const TeachStep step = blind.add_frame(tour.frames[i]);
    EXPECT_FALSE(step.heading_change_rad.has_value());
    if (step.new_key_rule) {
      EXPECT_NE(*step.new_key_rule, KeyImageRule::kHeading);
    }
  }
  const memory::VisualMemory blind_map = blind.finish();
  EXPECT_LT(blind_map.key_images.size(), map.key_images.size());
  EXPECT_FALSE(blind_map.key_images[0].odom.has_value());
}

INSTANTIATE_TEST_SUITE_P(EssentialModel, TeacherHeadingRule, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "planar" : "five_point"; });

TEST(Teacher, BadInputs) {
  const auto& tour = shared_tour();
  Teacher t(tour.camera);
  EXPECT_THROW(t.add_frame(Frame{}), std::invalid_argument);
  t.add_frame(tour.frames[0]);
  Frame other = tour.frames[1];
  other.gray = cv::Mat(120, 160, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(t.add_frame(other), std::invalid_argument);
  EXPECT_THROW(t.finish(), std::invalid_argument);  // one frame only
  Frame nan_odometry = tour.frames[1];
  nan_odometry.odom = OdometryPose{0.0, std::nan(""), 0.0};
  EXPECT_THROW(t.add_frame(nan_odometry), std::invalid_argument);
  TeachOptions bad;
  bad.selector.epsilon = 0;
  EXPECT_THROW(Teacher(tour.camera, bad), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::mapping
