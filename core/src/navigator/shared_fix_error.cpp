#include "core/navigator/shared_fix_error.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace pepper::core::navigator {

namespace {
void require_positive(double v, const char* what) {
  if (!(v > 0.0) || !std::isfinite(v)) {
    throw std::invalid_argument(std::string("SharedFixError: ") + what + " must be > 0 and finite");
  }
}
}  // namespace

void SharedFixError::begin(double sigma_b) {
  require_positive(sigma_b, "sigma_b");
  bias_ = 0.0;
  bias_var_ = sigma_b * sigma_b;
  cross_cov_ = 0.0;
}

double SharedFixError::update(double& est_var, double innovation, double noise_var) {
  require_positive(est_var, "the estimate's variance");
  require_positive(noise_var, "the fix's noise variance");
  if (!std::isfinite(innovation)) {
    throw std::invalid_argument("SharedFixError: the innovation must be finite");
  }
  // Measurement y = e + b + n of the state (e, b): H = [1 1].
  const double pe = est_var + cross_cov_;  // cov(e, y)
  const double pb = cross_cov_ + bias_var_;  // cov(b, y)
  const double s = est_var + bias_var_ + 2.0 * cross_cov_ + noise_var;
  const double r = innovation - bias_;
  const double ke = pe / s, kb = pb / s;
  bias_ += kb * r;
  // Variances stay positive (a floor far below any axis's own noise guards rounding).
  constexpr double kMinVar = 1e-12;
  est_var = std::max(est_var - pe * pe / s, kMinVar);
  bias_var_ = std::max(bias_var_ - pb * pb / s, kMinVar);
  cross_cov_ -= pe * pb / s;
  // |C| <= sqrt(P B): rounding must not make the joint covariance indefinite.
  const double bound = std::sqrt(est_var * bias_var_);
  cross_cov_ = std::clamp(cross_cov_, -bound, bound);
  return ke * r;
}

double SharedFixError::expected_var(double est_var, double noise_var) const {
  return std::max(est_var + bias_var_ + 2.0 * cross_cov_, 0.0) + noise_var;
}

void SharedFixError::rescale(double before, double after) {
  if (!(before > 0.0) || !std::isfinite(before) || !(after >= 0.0) || !std::isfinite(after)) {
    throw std::invalid_argument("SharedFixError: variances must be finite, before > 0");
  }
  // A Kalman update scales the covariance with the variance; a variance that grew (an update
  // that turned along into across) leaves it as it was. Either way the joint covariance stays
  // positive semi-definite: |C| <= sqrt(P B).
  cross_cov_ *= std::min(1.0, after / before);
  const double bound = std::sqrt(after * bias_var_);
  cross_cov_ = std::clamp(cross_cov_, -bound, bound);
}

}  // namespace pepper::core::navigator
