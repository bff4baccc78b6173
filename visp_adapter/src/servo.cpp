// vpServo behind Eigen types (see servo.hpp).
#include "visp_adapter/servo.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include <visp3/core/vpVelocityTwistMatrix.h>
#include <visp3/visual_features/vpGenericFeature.h>
#include <visp3/vs/vpServo.h>

#include "visp_matrix.hpp"

namespace pepper::visp_adapter {

Eigen::VectorXd servo_velocity(const ServoTask& task) {
  const Eigen::Index n = task.interaction.rows();
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("servo_velocity: " + what);
  };
  if (n == 0) fail("interaction has no rows");
  if (task.interaction.cols() != 6) fail("interaction must have 6 columns (camera twist)");
  if (task.error.size() != n) fail("error must have as many entries as interaction has rows");
  if (task.robot_jacobian_cam.rows() != 6) fail("robot_jacobian_cam must have 6 rows");
  if (task.robot_jacobian_cam.cols() == 0) fail("robot_jacobian_cam has no column (no dof)");
  if (!task.interaction.allFinite()) fail("interaction has a non-finite entry");
  if (!task.error.allFinite()) fail("error has a non-finite entry");
  if (!task.robot_jacobian_cam.allFinite()) fail("robot_jacobian_cam has a non-finite entry");
  if (!(std::isfinite(task.lambda) && task.lambda > 0.0)) fail("lambda must be finite and > 0");

  // The task as one generic feature: s = e with its interaction matrix, against s* = 0, so that
  // vpServo forms e = s - s* itself.
  const unsigned dim = static_cast<unsigned>(n);
  vpGenericFeature s(dim);
  s.set_s(to_visp(Eigen::VectorXd(task.error)));
  s.setInteractionMatrix(to_visp(Eigen::MatrixXd(task.interaction)));
  vpGenericFeature s_star(dim);
  s_star.set_s(vpColVector(dim, 0.0));

  vpServo servo;
  servo.setServo(vpServo::EYEINHAND_L_cVe_eJe);
  servo.setInteractionMatrixType(vpServo::CURRENT, vpServo::PSEUDO_INVERSE);
  servo.setLambda(task.lambda);
  servo.set_cVe(vpVelocityTwistMatrix());  // identity: the Jacobian is already in the camera frame
  servo.set_eJe(to_visp(Eigen::MatrixXd(task.robot_jacobian_cam)));
  servo.addFeature(s, s_star);
  return to_eigen(servo.computeControlLaw());
}

}  // namespace pepper::visp_adapter
