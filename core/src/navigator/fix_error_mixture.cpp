#include "core/navigator/fix_error_mixture.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pepper::core::navigator {

namespace {
// Log of a Gaussian density of r with variance s (constant terms cancel between hypotheses).
double log_density(double r, double s) { return -0.5 * (r * r / s + std::log(s)); }
// The log odds saturate here: a segment's evidence can make "moved" near certain, not certain,
// so that later fixes of the segment can still turn it back.
constexpr double kMaxLogOdds = 20.0;
}  // namespace

void FixErrorMixture::begin(const FixErrorMixtureOptions& options) {
  if (!(options.moved_prior > 0.0 && options.moved_prior < 1.0)) {
    throw std::invalid_argument("FixErrorMixture: moved_prior must be in (0, 1)");
  }
  for (int a = 0; a < 3; ++a) {
    if (!(options.noise_sigma[a] > 0.0)) {
      throw std::invalid_argument("FixErrorMixture: noise sigmas must be > 0");
    }
    usual_[a].begin(options.usual_sigma[a]);  // throws for sigma <= 0
    moved_[a].begin(options.moved_sigma[a]);
  }
  options_ = options;
  log_odds_moved_ = std::log(options.moved_prior / (1.0 - options.moved_prior));
}

Axes3 FixErrorMixture::update(Axes3& est_var, const Axes3& innovation, double weight) {
  if (!(weight > 0.0 && weight <= 1.0)) {
    throw std::invalid_argument("FixErrorMixture: the fix's weight must be in (0, 1]");
  }
  Axes3 c_usual{}, c_moved{}, v_usual = est_var, v_moved = est_var;
  double log_ratio = 0.0;  // log p(fix | moved) - log p(fix | usual)
  for (int a = 0; a < 3; ++a) {
    const double r_var = options_.noise_sigma[a] * options_.noise_sigma[a] / weight;
    log_ratio += log_density(innovation[a] - moved_[a].expected(),
                             moved_[a].expected_var(est_var[a], r_var)) -
                 log_density(innovation[a] - usual_[a].expected(),
                             usual_[a].expected_var(est_var[a], r_var));
    c_usual[a] = usual_[a].update(v_usual[a], innovation[a], r_var);
    c_moved[a] = moved_[a].update(v_moved[a], innovation[a], r_var);
  }
  log_odds_moved_ = std::clamp(log_odds_moved_ + log_ratio, -kMaxLogOdds, kMaxLogOdds);
  const double p_usual = usual_probability();
  Axes3 correction{};
  for (int a = 0; a < 3; ++a) {
    correction[a] = p_usual * c_usual[a] + (1.0 - p_usual) * c_moved[a];
    const double du = c_usual[a] - correction[a], dm = c_moved[a] - correction[a];
    est_var[a] = p_usual * (v_usual[a] + du * du) + (1.0 - p_usual) * (v_moved[a] + dm * dm);
  }
  return correction;
}

void FixErrorMixture::rescale(int axis, double before, double after) {
  if (axis < 0 || axis > 2) throw std::invalid_argument("FixErrorMixture: axis must be 0, 1 or 2");
  usual_[axis].rescale(before, after);
  moved_[axis].rescale(before, after);
}

double FixErrorMixture::usual_probability() const {
  return 1.0 / (1.0 + std::exp(log_odds_moved_));
}

Axes3 FixErrorMixture::expected() const {
  Axes3 e{};
  for (int a = 0; a < 3; ++a) e[a] = usual_[a].expected();
  return e;
}

Axes3 FixErrorMixture::expected_var(const Axes3& est_var) const {
  Axes3 v{};
  for (int a = 0; a < 3; ++a) {
    v[a] = usual_[a].expected_var(est_var[a], options_.noise_sigma[a] * options_.noise_sigma[a]);
  }
  return v;
}

}  // namespace pepper::core::navigator
