// EstimateErrors: one owner of the odometry estimate's sigmas and of the room-or-moved models of
// the sources that correct it. A source's update sets the sigmas of its axes from its model and
// every other begun model of those axes scales alike; odometry grows the sigmas and every begun
// model; a lines' model begins again for a new IN and after begin().
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "core/navigator/estimate_errors.hpp"

namespace pepper::core::navigator {
namespace {

const double kNaN = std::nan("");

FixErrorMixtureOptions vnhv() { return FixErrorMixtureOptions{}; }
FixErrorMixtureOptions line_yaw() {
  return {{kNaN, kNaN, 0.01}, {kNaN, kNaN, 0.1}, {kNaN, kNaN, 0.005}, 0.1};
}
FixErrorMixtureOptions floor_lines() {
  return {{kNaN, 0.04, kNaN}, {kNaN, 0.3, kNaN}, {kNaN, 0.01, kNaN}, 0.1};
}
FixErrorMixtureOptions switches() {
  return {{0.05, kNaN, kNaN}, {0.4, kNaN, kNaN}, {0.05, kNaN, kNaN}, 0.2};
}

TEST(EstimateErrors, AnUpdateSetsItsAxesSigmasAndScalesTheOtherModels) {
  EstimateErrors e(vnhv(), line_yaw(), floor_lines(), switches());
  e.place({0.2, 0.1, 0.05});
  EXPECT_TRUE(e.begun(FixSource::kVnhv));
  EXPECT_FALSE(e.begun(FixSource::kLineYaw));
  e.model_for(FixSource::kLineYaw, 4);
  e.model_for(FixSource::kFloorLines, 4);
  const double vnhv_heading_before = e.model(FixSource::kVnhv).variance()[2];
  const double vnhv_lateral_before = e.model(FixSource::kVnhv).variance()[1];

  // A line yaw: the heading alone moves, its sigma becomes the lines' model's, and the VNHV
  // model's heading variance shrinks in the same ratio; the floor lines' model is untouched.
  const Axes3 d = e.update(FixSource::kLineYaw, {kNaN, kNaN, 0.01}, 1.0);
  EXPECT_EQ(d[0], 0.0);
  EXPECT_EQ(d[1], 0.0);
  EXPECT_GT(d[2], 0.0);
  const double heading_var = e.model(FixSource::kLineYaw).variance()[2];
  EXPECT_LT(heading_var, 0.05 * 0.05);
  EXPECT_DOUBLE_EQ(e.sigma()[2], std::sqrt(heading_var));
  EXPECT_DOUBLE_EQ(e.sigma()[0], 0.2);
  EXPECT_DOUBLE_EQ(e.sigma()[1], 0.1);
  EXPECT_NEAR(e.model(FixSource::kVnhv).variance()[2],
              vnhv_heading_before * heading_var / (0.05 * 0.05), 1e-15);
  EXPECT_DOUBLE_EQ(e.model(FixSource::kVnhv).variance()[1], vnhv_lateral_before);
  EXPECT_DOUBLE_EQ(e.model(FixSource::kFloorLines).variance()[1], 0.1 * 0.1);

  // A VNHV fix: every axis's sigma becomes its model's; the lines' models' variances scale alike
  // (the floor lines' exactly: no evidence yet).
  const double line_before = e.model(FixSource::kLineYaw).variance()[2];
  const double sigma_heading_before = e.sigma()[2];
  e.update(FixSource::kVnhv, {0.01, -0.005, 0.002}, 1.0);
  const Axes3 v = e.model(FixSource::kVnhv).variance();
  for (int a = 0; a < 3; ++a) EXPECT_DOUBLE_EQ(e.sigma()[a], std::sqrt(v[a])) << a;
  // (The lines' model has evidence: its hypotheses' estimates differ, a spread that a rescale
  // of their variances leaves as it is.)
  ASSERT_LT(v[2], sigma_heading_before * sigma_heading_before);
  EXPECT_LT(e.model(FixSource::kLineYaw).variance()[2], line_before);
  EXPECT_GT(e.model(FixSource::kLineYaw).variance()[2],
            line_before * v[2] / (sigma_heading_before * sigma_heading_before));
  EXPECT_NEAR(e.model(FixSource::kFloorLines).variance()[1], 0.1 * 0.1 * v[1] / (0.1 * 0.1),
              1e-15);
}

TEST(EstimateErrors, OdometryGrowsTheSigmasAndEveryBegunModel) {
  EstimateErrors e(vnhv(), line_yaw(), floor_lines(), switches());
  e.place({0.1, 0.1, 0.02});
  e.model_for(FixSource::kLineYaw, 2);
  e.grow({0.01, 0.02, 0.003});
  EXPECT_DOUBLE_EQ(e.sigma()[0], 0.11);
  EXPECT_DOUBLE_EQ(e.sigma()[1], 0.12);
  EXPECT_DOUBLE_EQ(e.sigma()[2], 0.023);
  EXPECT_NEAR(e.model(FixSource::kVnhv).variance()[1], 0.12 * 0.12, 1e-15);
  EXPECT_NEAR(e.model(FixSource::kLineYaw).variance()[2], 0.023 * 0.023, 1e-15);
  // The floor lines' model was not begun: it begins from the grown sigma.
  EXPECT_NEAR(e.model_for(FixSource::kFloorLines, 2).variance()[1], 0.12 * 0.12, 1e-15);
  EXPECT_THROW(e.grow({-0.01, 0.0, 0.0}), std::invalid_argument);
}

// What driving added since each axis was last known (the dead-reckoning bound): the odometry's
// growth adds up; a measurement of an axis clears that axis only; a placement clears all.
TEST(EstimateErrors, GrownCountsTheOdometrysGrowthSinceEachAxisWasLastSet) {
  EstimateErrors e(vnhv(), line_yaw(), floor_lines(), switches());
  e.place({0.1, 0.1, 0.02});
  EXPECT_EQ(e.grown()[1], 0.0);
  e.grow({0.01, 0.02, 0.003});
  e.grow({0.01, 0.03, 0.001});
  EXPECT_DOUBLE_EQ(e.grown()[0], 0.02);
  EXPECT_DOUBLE_EQ(e.grown()[1], 0.05);
  EXPECT_DOUBLE_EQ(e.grown()[2], 0.004);
  // A heading from lines: the heading is known again, the lateral growth stays.
  e.model_for(FixSource::kLineYaw, 3);
  e.update(FixSource::kLineYaw, {kNaN, kNaN, 0.0}, 1.0);
  EXPECT_EQ(e.grown()[2], 0.0);
  EXPECT_DOUBLE_EQ(e.grown()[1], 0.05);
  // The floor lines measure across the path: that growth is cleared, whatever the sigma now.
  e.model_for(FixSource::kFloorLines, 3);
  e.update(FixSource::kFloorLines, {kNaN, 0.01, kNaN}, 1.0);
  EXPECT_EQ(e.grown()[1], 0.0);
  EXPECT_DOUBLE_EQ(e.grown()[0], 0.02);
  e.grow({0.01, 0.01, 0.01});
  e.place({0.5, 0.5, 0.1});
  for (int a = 0; a < 3; ++a) EXPECT_EQ(e.grown()[a], 0.0) << a;
}

TEST(EstimateErrors, ALinesModelBeginsAgainForANewInAndAfterBegin) {
  EstimateErrors e(vnhv(), line_yaw(), floor_lines(), switches());
  e.place({0.1, 0.1, 0.02});
  e.model_for(FixSource::kLineYaw, 3);
  for (int i = 0; i < 20; ++i) e.update(FixSource::kLineYaw, {kNaN, kNaN, 0.12}, 1.0);
  EXPECT_LT(e.model(FixSource::kLineYaw).usual_probability(), 0.5) << "a moved shelf";
  // Same IN: the same model, with its evidence.
  EXPECT_LT(e.model_for(FixSource::kLineYaw, 3).usual_probability(), 0.5);
  // Next IN: a new model at the prior's odds.
  EXPECT_NEAR(e.model_for(FixSource::kLineYaw, 4).usual_probability(), 0.9, 1e-12);
  for (int i = 0; i < 20; ++i) e.update(FixSource::kLineYaw, {kNaN, kNaN, 0.12}, 1.0);
  e.begin();
  EXPECT_FALSE(e.begun(FixSource::kLineYaw));
  EXPECT_THROW(e.update(FixSource::kLineYaw, {kNaN, kNaN, 0.0}, 1.0), std::invalid_argument);
  EXPECT_NEAR(e.model_for(FixSource::kLineYaw, 4).usual_probability(), 0.9, 1e-12);
}

TEST(EstimateErrors, BadSourcesAndSigmasAreRefused) {
  EXPECT_THROW(EstimateErrors(line_yaw(), line_yaw(), floor_lines(), switches()),
               std::invalid_argument);
  FixErrorMixtureOptions bad = floor_lines();
  bad.noise_sigma[1] = 0.0;
  EXPECT_THROW(EstimateErrors(vnhv(), line_yaw(), bad, switches()), std::invalid_argument);
  EstimateErrors e(vnhv(), line_yaw(), floor_lines(), switches());
  EXPECT_THROW(e.place({0.1, 0.0, 0.1}), std::invalid_argument);
  EXPECT_THROW(e.model_for(FixSource::kFloorLines, -1), std::invalid_argument);
}

// A switch the image decided measures the along axis once: a freshly placed estimate (sigma 0.5 m)
// takes most of it, a located one (sigma 3 cm) hardly moves for a look-alike's early switch.
TEST(EstimateErrors, ASwitchMeasuresAlongOnlyAndWeighsAgainstTheEstimatesSigma) {
  EstimateErrors e(vnhv(), line_yaw(), floor_lines(), switches());
  e.place({0.5, 0.5, 0.1});
  EXPECT_FALSE(e.begun(FixSource::kSwitch));
  e.model_for(FixSource::kSwitch, 7);
  const Axes3 d = e.update(FixSource::kSwitch, {-0.25, kNaN, kNaN}, 1.0);
  EXPECT_LT(d[0], -0.2);
  EXPECT_GT(d[0], -0.25);
  EXPECT_EQ(d[1], 0.0);
  EXPECT_EQ(d[2], 0.0);
  EXPECT_LT(e.sigma()[0], 0.2);
  EXPECT_DOUBLE_EQ(e.sigma()[1], 0.5);

  // The switches share one error: a run of switches 4 cm early pulls the estimate by less than
  // that error's sigma (5 cm) in all, not by 4 cm each time. begin() (a new VNHV model at every
  // switch) keeps the model; a placement ends it.
  e.place({0.03, 0.02, 0.01});
  double pulled_m = 0.0;
  for (int i = 0; i < 30; ++i) {
    e.begin();
    e.model_for(FixSource::kSwitch, 8 + i);
    EXPECT_TRUE(e.begun(FixSource::kSwitch));
    pulled_m += e.update(FixSource::kSwitch, {0.04 - pulled_m, kNaN, kNaN}, 1.0)[0];
  }
  EXPECT_GT(pulled_m, 0.0);
  EXPECT_LT(pulled_m, 0.03);
  e.place({0.03, 0.02, 0.01});
  EXPECT_FALSE(e.begun(FixSource::kSwitch));
  e.model_for(FixSource::kSwitch, 40);
  const Axes3 early = e.update(FixSource::kSwitch, {0.3, kNaN, kNaN}, 1.0);
  EXPECT_GT(early[0], 0.0);
  EXPECT_LT(early[0], 0.03);
  EXPECT_LT(e.model(FixSource::kSwitch).usual_probability(), 0.5) << "a look-alike's switch";
}

}  // namespace
}  // namespace pepper::core::navigator
