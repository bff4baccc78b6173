#pragma once
// The rotational-velocity law of Bista et al. (IROS 2017) with feed-forward (METHOD.md,
// "Replay: control law"):
//
//   omega = -lambda * ( J_L (g1 eL_N + g2 eL_NN) + J_P (g1 eP_N + g2 eP_NN) ) / (J_L^2 + J_P^2)
//
// eL_N = Xa - XN (line feature of the current image minus that of the next key image, computed on
// the same matched lines), eL_NN = Xa - XNN, eP_* likewise for points; J_* from
// core/control/visual_features.hpp. A modality that is absent (or disabled by the mode) is
// dropped from numerator and denominator. When the next-next key image does not exist (last
// segment), its error is replaced by the next one, i.e. the whole weight g1 + g2 goes to IN.
// Units: errors in normalised image units, omega in rad/s, > 0 turns left (docs/conventions.md).
//
// Expected outcome as value: no usable modality -> std::nullopt (the navigator stops). Pure and
// thread-safe. Options are checked by validate(); compute_ibvs_omega throws
// std::invalid_argument when they are invalid.

#include <optional>
#include <string>
#include <vector>

namespace pepper::core::control {

enum class FeatureMode { kLinesAndPoints, kLinesOnly, kPointsOnly };

const char* to_string(FeatureMode mode);

struct IbvsOptions {
  FeatureMode mode = FeatureMode::kLinesAndPoints;
  double g1 = 0.7;      ///< weight of the next key image IN (METHOD.md, paper value), in [0, 1]
  double g2 = 0.3;      ///< weight of the next-next key image INN (feed-forward), in [0, 1]
  double lambda = 1.0;  ///< gain, 1/s, > 0 (paper value)

  /// Messages naming each invalid field and its allowed range; empty when valid.
  std::vector<std::string> validate() const;
};

/// Errors and Jacobian of one modality (lines or points).
struct ModalityError {
  double err_next = 0.0;                ///< feature(Ia) - feature(IN), normalised units
  std::optional<double> err_next_next;  ///< feature(Ia) - feature(INN); nullopt if no INN match
  double jacobian = 1.0;                ///< J_L or J_P (d feature / d omega), 1/(rad/s) units
};

struct IbvsInput {
  std::optional<ModalityError> lines;
  std::optional<ModalityError> points;
};

struct IbvsResult {
  std::optional<double> omega_rad_s;  ///< nullopt: no usable modality -> stop
  bool used_lines = false;
  bool used_points = false;
};

IbvsResult compute_ibvs_omega(const IbvsInput& input, const IbvsOptions& options);

}  // namespace pepper::core::control
