#pragma once
// ViSP's visual-servoing control law (vpServo) behind Eigen types; see visual_features.hpp for why
// an adapter and for the conventions.
//
// servo_velocity() runs vpServo as an eye-in-hand task with a robot Jacobian
// (vpServo::EYEINHAND_L_cVe_eJe, current interaction matrix, pseudo-inverse), on a task given by
// its stacked interaction matrix and error, so the caller chooses the features (ViSP's own or
// combinations of them, e.g. the mean of several lines' rows):
//   q_dot = -lambda * (L * J)^+ * e
// with L (n x 6) the interaction matrix, e = s - s* (n), J (6 x k) the camera twist produced by a
// unit velocity of each of the robot's k degrees of freedom (cVe * eJe in ViSP's terms, here
// given in the camera frame: cVe is the identity), and ^+ ViSP's pseudo-inverse (singular values
// below 1e-6 of the largest dropped). Returns q_dot (k).
//
// Errors: inconsistent sizes, no rows, no degree of freedom, lambda <= 0 or non-finite entries
// throw std::invalid_argument naming the field. Pure; thread-safe.

#include <Eigen/Core>

namespace pepper::visp_adapter {

struct ServoTask {
  Eigen::MatrixXd interaction;         ///< L, n x 6 (camera twist columns)
  Eigen::VectorXd error;               ///< e = s - s*, n
  Eigen::MatrixXd robot_jacobian_cam;  ///< J, 6 x k: camera twist per unit robot velocity
  double lambda = 1.0;                 ///< gain, 1/s, > 0
};

/// vpServo::computeControlLaw() for the task: the robot velocities q_dot (k).
Eigen::VectorXd servo_velocity(const ServoTask& task);

}  // namespace pepper::visp_adapter
