// Relay images by the paper's two conditions, on synthetic sightings: a tour along a line and
// through a turn over a grid of ceiling landmarks, a gap in the ceiling, angle wrap-around.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/ceiling/relay_images.hpp"

namespace pepper::core::ceiling {
namespace {

// Landmarks on a 0.2 m grid; a frame sees those within `radius_m` of the camera, each with the
// orientation (landmark angle - heading): in image axes the content turns by -heading.
std::vector<LandmarkSighting> view(double x_m, double y_m, double heading_rad, double radius_m) {
  std::vector<LandmarkSighting> out;
  int64_t id = 0;
  for (int i = -60; i <= 60; ++i)
    for (int j = -60; j <= 60; ++j, ++id) {
      const double lx = 0.2 * i, ly = 0.2 * j;
      if (std::hypot(lx - x_m, ly - y_m) > radius_m) continue;
      const double own_angle = 0.37 * static_cast<double>(id % 17);  // any fixed orientation
      out.push_back({id, {lx, ly}, wrap_angle_rad(own_angle - heading_rad)});
    }
  return out;
}

void expect_chain_satisfies_conditions(const std::vector<std::vector<LandmarkSighting>>& frames,
                                       const RelaySelection& sel, const RelayOptions& o) {
  ASSERT_FALSE(sel.relay_frames.empty());
  EXPECT_EQ(sel.relay_frames.front(), 0u);
  EXPECT_EQ(sel.relay_frames.back(), frames.size() - 1);
  for (size_t r = 0; r + 1 < sel.relay_frames.size(); ++r) {
    const size_t a = sel.relay_frames[r], b = sel.relay_frames[r + 1];
    EXPECT_LT(a, b);
    EXPECT_TRUE(check_relay_pair(frames[a], frames[b], o).ok) << a << " -> " << b;
    // Greedy: the frame after b does not satisfy the conditions with a (b is as far as it goes),
    // unless b is the last frame.
    if (b + 1 < frames.size() && r + 2 < sel.relay_frames.size()) {
      EXPECT_FALSE(check_relay_pair(frames[a], frames[b + 1], o).ok) << a << " -> " << b + 1;
    }
  }
}

TEST(RelayImages, AStraightTourIsCutWhereTooFewLandmarksAreShared) {
  // 4 m along x, a frame every 2 cm, seeing a 0.6 m disc: two views share landmarks only while
  // less than 1.2 m apart.
  std::vector<std::vector<LandmarkSighting>> frames;
  for (int k = 0; k <= 200; ++k) frames.push_back(view(0.02 * k, 0.0, 0.0, 0.6));
  RelayOptions o;
  o.min_shared_landmarks = 8;
  const RelaySelection sel = select_relay_images(frames, o);
  expect_chain_satisfies_conditions(frames, sel, o);
  EXPECT_TRUE(sel.breaks.empty());
  // Eight shared grid points (0.04 m^2 each) need a lens of ~0.32 m^2 between two 0.6 m discs,
  // i.e. views ~0.7 m apart: 6 to 8 relay images for 4 m, not one per frame.
  EXPECT_GE(sel.relay_frames.size(), 6u);
  EXPECT_LE(sel.relay_frames.size(), 8u);
  // More shared landmarks required: relay images closer together.
  o.min_shared_landmarks = 60;
  EXPECT_GT(select_relay_images(frames, o).relay_frames.size(), sel.relay_frames.size());
}

TEST(RelayImages, ATurnOnTheSpotIsCutByTheOrientationCondition) {
  // Turning 180 degrees on the spot: all landmarks stay in view (condition 1 always holds), so
  // only condition 2 cuts: at most 0.3 rad between relay images, so >= ceil(pi / 0.3) = 11 steps.
  std::vector<std::vector<LandmarkSighting>> frames;
  for (int k = 0; k <= 180; ++k) frames.push_back(view(1.0, 1.0, k * M_PI / 180.0, 0.8));
  RelayOptions o;
  o.max_orientation_change_rad = 0.3;
  const RelaySelection sel = select_relay_images(frames, o);
  expect_chain_satisfies_conditions(frames, sel, o);
  EXPECT_TRUE(sel.breaks.empty());
  EXPECT_EQ(sel.relay_frames.size(), 12u);  // 0, 17, 34, ... (17 deg < 0.3 rad < 18 deg), 180
  for (size_t r = 0; r + 1 < sel.relay_frames.size(); ++r) {
    const RelayPairCheck c =
        check_relay_pair(frames[sel.relay_frames[r]], frames[sel.relay_frames[r + 1]], o);
    EXPECT_LT(c.orientation_change_rad, 0.3);
  }
  // Across the +-pi wrap: 170 deg and -170 deg orientations are 20 deg apart, not 340.
  const std::vector<LandmarkSighting> a{{1, {0, 0}, 170 * M_PI / 180},
                                        {2, {1, 0}, 170 * M_PI / 180}};
  const std::vector<LandmarkSighting> b{{1, {0, 0}, -170 * M_PI / 180},
                                        {2, {1, 0}, -170 * M_PI / 180}};
  RelayOptions two;
  two.min_shared_landmarks = 2;
  two.max_orientation_change_rad = 0.4;  // 20 deg = 0.349 rad passes, 340 deg would not
  const RelayPairCheck wrapped = check_relay_pair(a, b, two);
  EXPECT_EQ(wrapped.shared_landmarks, 2);
  EXPECT_NEAR(wrapped.orientation_change_rad, 20 * M_PI / 180, 1e-9);
  EXPECT_TRUE(wrapped.ok);
}

TEST(RelayImages, TheMedianOrientationChangeIgnoresAFewWildLandmarkAngles) {
  std::vector<LandmarkSighting> a, b;
  for (int64_t id = 0; id < 20; ++id) {
    a.push_back({id, {0, 0}, 0.1});
    // 0.05 rad turn; three landmarks with a wild ORB angle.
    b.push_back({id, {0, 0}, id < 3 ? 2.5 : 0.15});
  }
  const RelayPairCheck c = check_relay_pair(a, b, {});
  EXPECT_EQ(c.shared_landmarks, 20);
  EXPECT_NEAR(c.orientation_change_rad, 0.05, 1e-9);
  EXPECT_TRUE(c.ok);
}

TEST(RelayImages, AGapInTheCeilingIsReportedAsABreak) {
  std::vector<std::vector<LandmarkSighting>> frames;
  for (int k = 0; k < 10; ++k) frames.push_back(view(0.02 * k, 0.0, 0.0, 0.6));
  frames.push_back({});  // a frame that saw nothing of the mosaic
  for (int k = 0; k < 10; ++k) frames.push_back(view(8.0 + 0.02 * k, 0.0, 0.0, 0.6));
  const RelaySelection sel = select_relay_images(frames, {});
  EXPECT_EQ(sel.relay_frames.front(), 0u);
  EXPECT_EQ(sel.relay_frames.back(), frames.size() - 1);
  // 0 -> 9 (last reachable), 9 -> 10 (break: empty frame), 10 -> 11 (break), 11 -> 20.
  ASSERT_EQ(sel.relay_frames, (std::vector<size_t>{0, 9, 10, 11, 20}));
  EXPECT_EQ(sel.breaks, (std::vector<size_t>{1, 2}));
}

TEST(RelayImages, EdgeCasesAndBadOptions) {
  EXPECT_TRUE(select_relay_images({}).relay_frames.empty());
  const auto one = select_relay_images({view(0, 0, 0, 0.5)});
  EXPECT_EQ(one.relay_frames, (std::vector<size_t>{0}));
  RelayOptions o;
  o.min_shared_landmarks = 0;
  EXPECT_THROW(select_relay_images({}, o), std::invalid_argument);
  o = {};
  o.max_orientation_change_rad = 0.0;
  EXPECT_THROW(select_relay_images({}, o), std::invalid_argument);
  o.max_orientation_change_rad = 4.0;
  EXPECT_THROW(check_relay_pair({}, {}, o), std::invalid_argument);
}

// A turn posed by the odometry alone: every frame a relay image (1 cm and 0.034 rad apart),
// each pair linked by the chain. Thinned to about 0.2 rad per relay segment, so the replay
// follows arcs it feeds forward; the relay images outside the run and the run's ends stay.
TEST(RelayImages, ARunOnlyTheChainLinksIsThinnedToArcs) {
  std::vector<PlanarPose> poses = {{0.0, 0.0, 0.0}, {0.5, 0.0, 0.0}};
  PlanarPose p = poses.back();
  for (int k = 0; k < 44; ++k) poses.push_back(p = p * PlanarPose{0.01, 0.0, -0.034});
  poses.push_back(p * PlanarPose{0.5, 0.0, 0.0});
  std::vector<uint8_t> linked(poses.size() - 1, 1);
  linked.front() = 0;  // relay 0 -> 1: the conditions hold
  linked.back() = 0;
  const std::vector<size_t> kept = thin_linked_relays(poses, linked, 0.3, 0.2);
  ASSERT_GE(kept.size(), 4u);
  EXPECT_EQ(kept.front(), 0u);
  EXPECT_EQ(kept[1], 1u);
  EXPECT_EQ(kept.back(), poses.size() - 1);
  EXPECT_EQ(kept[kept.size() - 2], poses.size() - 2);  // the run's last relay image
  // 1.5 rad in steps of at least 0.2 rad: at most 8 segments inside the run.
  EXPECT_LE(kept.size(), 2u + 8u + 1u);
  for (size_t j = 2; j + 2 < kept.size(); ++j) {
    const double turned = std::abs(wrap_angle_rad(poses[kept[j]].theta_rad -
                                                  poses[kept[j - 1]].theta_rad));
    EXPECT_GE(turned, 0.2 - 1e-9) << j;
    EXPECT_LT(turned, 0.2 + 0.034) << j;
  }
  // Nothing linked: every relay image stays.
  const std::vector<uint8_t> none(poses.size() - 1, 0);
  EXPECT_EQ(thin_linked_relays(poses, none, 0.3, 0.2).size(), poses.size());
  EXPECT_THROW(thin_linked_relays(poses, std::vector<uint8_t>(3, 1), 0.3, 0.2),
               std::invalid_argument);
  EXPECT_THROW(thin_linked_relays(poses, linked, -1.0, 0.2), std::invalid_argument);
  RelayOptions o;
  o.linked_step_rad = -0.1;
  EXPECT_THROW(o.check(), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::ceiling
