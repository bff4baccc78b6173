// The adapter's ViSP features against the closed forms of the interaction matrices (Chaumette &
// Hutchinson, "Visual servo control I", 2006): what ViSP is asked and what comes back, without ViSP
// types (this file compiles as C++20, which ViSP 3.5's headers do not: the adapter's headers are
// ViSP-free by construction).
#include "visp_adapter/servo.hpp"
#include "visp_adapter/visual_features.hpp"

#include <cmath>
#include <stdexcept>

#include <Eigen/QR>
#include <gtest/gtest.h>

namespace pepper::visp_adapter {
namespace {

TEST(VispAdapterFeatures, PointRowsAreTheClosedForm) {
  const double x = 0.3, y = -0.2, z_m = 2.5;
  const InteractionMatrix l = point_interaction(x, y, z_m);
  InteractionMatrix expected;
  expected << -1.0 / z_m, 0.0, x / z_m, x * y, -(1.0 + x * x), y,  //
      0.0, -1.0 / z_m, y / z_m, 1.0 + y * y, -x * y, -x;
  EXPECT_TRUE(l.isApprox(expected, 1e-12)) << l << "\n" << expected;
}

TEST(VispAdapterFeatures, LineRowsAreTheClosedForm) {
  const double rho = 0.15, theta = 0.7;
  const PlaneCam plane{0.2, -0.1, 1.0, -3.0};
  const InteractionMatrix l = line_interaction(rho, theta, plane);
  const double c = std::cos(theta), s = std::sin(theta);
  const double lr = (plane.a * rho * c + plane.b * rho * s + plane.c) / plane.d_m;
  const double lt = (plane.a * s - plane.b * c) / plane.d_m;
  InteractionMatrix expected;
  expected << lr * c, lr * s, -lr * rho, (1.0 + rho * rho) * s, -(1.0 + rho * rho) * c, 0.0,  //
      lt * c, lt * s, -lt * rho, -rho * c, -rho * s, -1.0;
  EXPECT_TRUE(l.isApprox(expected, 1e-12)) << l << "\n" << expected;
}

TEST(VispAdapterFeatures, RefusesWhatViSPCannotUse) {
  EXPECT_THROW(point_interaction(0.1, 0.1, 0.0), std::invalid_argument);
  EXPECT_THROW(point_interaction(0.1, 0.1, -1.0), std::invalid_argument);
  EXPECT_THROW(point_interaction(NAN, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(line_interaction(0.1, 0.2, PlaneCam{0.0, 0.0, 1.0, 0.0}), std::invalid_argument);
  try {
    point_interaction(0.1, 0.1, -1.0);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("depth_m"), std::string::npos) << e.what();
  }
}

TEST(VispAdapterServo, OneDofTaskIsTheLeastSquaresStep) {
  // Two rows, one degree of freedom (rotation about camera y): q_dot = -lambda (Lj . e)/(Lj . Lj)
  // with Lj = L * J, the least-squares solution that vpServo's pseudo-inverse gives.
  ServoTask task;
  task.interaction = Eigen::MatrixXd::Zero(2, 6);
  task.interaction(0, 4) = -1.2;
  task.interaction(1, 4) = -0.8;
  task.interaction(0, 0) = 0.5;  // a translation column the robot cannot produce: ignored
  task.error = Eigen::Vector2d(0.05, -0.02);
  task.robot_jacobian_cam = Eigen::MatrixXd::Zero(6, 1);
  task.robot_jacobian_cam(4, 0) = -1.0;
  task.lambda = 0.7;
  const Eigen::VectorXd q_dot = servo_velocity(task);
  ASSERT_EQ(q_dot.size(), 1);
  const double lj0 = 1.2, lj1 = 0.8;
  EXPECT_NEAR(q_dot(0), -0.7 * (lj0 * 0.05 + lj1 * -0.02) / (lj0 * lj0 + lj1 * lj1), 1e-12);
}

TEST(VispAdapterServo, SixDofTaskOnFourPointsMatchesEigenPseudoInverse) {
  ServoTask task;
  task.interaction.resize(8, 6);
  const double pts[4][3] = {{0.1, 0.1, 1.0}, {-0.1, 0.12, 1.2}, {-0.09, -0.1, 0.9}, {0.11, -0.1, 1.1}};
  for (int i = 0; i < 4; ++i) task.interaction.block<2, 6>(2 * i, 0) = point_interaction(pts[i][0], pts[i][1], pts[i][2]);
  task.error = Eigen::VectorXd::LinSpaced(8, -0.02, 0.03);
  task.robot_jacobian_cam = Eigen::MatrixXd::Identity(6, 6);
  task.lambda = 0.5;
  const Eigen::VectorXd v = servo_velocity(task);
  const Eigen::VectorXd expected =
      -0.5 * task.interaction.completeOrthogonalDecomposition().pseudoInverse() * task.error;
  EXPECT_TRUE(v.isApprox(expected, 1e-9)) << v.transpose() << "\n" << expected.transpose();
}

TEST(VispAdapterServo, RefusesInconsistentTasks) {
  ServoTask task;
  task.interaction = Eigen::MatrixXd::Zero(2, 6);
  task.error = Eigen::VectorXd::Zero(3);
  task.robot_jacobian_cam = Eigen::MatrixXd::Identity(6, 6);
  EXPECT_THROW(servo_velocity(task), std::invalid_argument);
  task.error = Eigen::VectorXd::Zero(2);
  task.lambda = 0.0;
  EXPECT_THROW(servo_velocity(task), std::invalid_argument);
  task.lambda = 1.0;
  task.robot_jacobian_cam = Eigen::MatrixXd::Zero(5, 1);
  EXPECT_THROW(servo_velocity(task), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::visp_adapter
