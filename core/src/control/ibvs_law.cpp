#include "core/control/ibvs_law.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace pepper::core::control {

const char* to_string(FeatureMode mode) {
  switch (mode) {
    case FeatureMode::kLinesAndPoints:
      return "lines_and_points";
    case FeatureMode::kLinesOnly:
      return "lines_only";
    case FeatureMode::kPointsOnly:
      return "points_only";
  }
  return "unknown";
}

std::vector<std::string> IbvsOptions::validate() const {
  std::vector<std::string> errors;
  auto in_unit = [&](const char* name, double value) {
    if (!(std::isfinite(value) && value >= 0.0 && value <= 1.0)) {
      std::ostringstream os;
      os << "control.ibvs." << name << " = " << value << " must be in [0, 1]";
      errors.push_back(os.str());
    }
  };
  in_unit("g1", g1);
  in_unit("g2", g2);
  if (std::isfinite(g1) && std::isfinite(g2) && g1 + g2 <= 0.0) {
    errors.push_back("control.ibvs.g1 + g2 must be > 0");
  }
  if (!(std::isfinite(lambda) && lambda > 0.0)) {
    std::ostringstream os;
    os << "control.ibvs.lambda = " << lambda << " must be finite and > 0";
    errors.push_back(os.str());
  }
  return errors;
}

namespace {
bool usable(const std::optional<ModalityError>& m) {
  return m.has_value() && std::isfinite(m->err_next) && std::isfinite(m->jacobian) &&
         (!m->err_next_next || std::isfinite(*m->err_next_next));
}
}  // namespace

IbvsResult compute_ibvs_omega(const IbvsInput& input, const IbvsOptions& options) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument("compute_ibvs_omega: " + errors.front());
  }
  IbvsResult result;
  const bool lines_allowed = options.mode != FeatureMode::kPointsOnly;
  const bool points_allowed = options.mode != FeatureMode::kLinesOnly;
  double numerator = 0.0;
  double denominator = 0.0;
  auto add = [&](const ModalityError& m) {
    const double e_nn = m.err_next_next.value_or(m.err_next);
    numerator += m.jacobian * (options.g1 * m.err_next + options.g2 * e_nn);
    denominator += m.jacobian * m.jacobian;
  };
  if (lines_allowed && usable(input.lines)) {
    add(*input.lines);
    result.used_lines = true;
  }
  if (points_allowed && usable(input.points)) {
    add(*input.points);
    result.used_points = true;
  }
  // J_P >= 1 always; J_L can vanish for near-horizontal lines (theta ~ +-pi/2, small rho). A
  // vanishing denominator means the features carry no yaw information: no command.
  constexpr double kMinDenominator = 1e-9;
  if ((!result.used_lines && !result.used_points) || denominator < kMinDenominator) {
    result.used_lines = result.used_points = false;
    return result;
  }
  result.omega_rad_s = -options.lambda * numerator / denominator;
  return result;
}

}  // namespace pepper::core::control
