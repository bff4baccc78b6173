#include "core/navigator/fix_error_mixture.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace pepper::core::navigator {

namespace {
// Log of a Gaussian density of r with variance s (constant terms cancel between hypotheses).
double log_density(double r, double s) { return -0.5 * (r * r / s + std::log(s)); }
// The log odds saturate here: a segment's evidence can make "moved" near certain, not certain,
// so that later fixes of the segment can still turn it back.
constexpr double kMaxLogOdds = 20.0;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

void FixErrorMixture::begin(const FixErrorMixtureOptions& options, const Axes3& est_var) {
  if (!(options.moved_prior > 0.0 && options.moved_prior < 1.0)) {
    throw std::invalid_argument("FixErrorMixture: moved_prior must be in (0, 1)");
  }
  int modelled = 0;
  for (int a = 0; a < 3; ++a) {
    if (!options.models(a)) {  // not measured by this source: nothing of it is modelled
      if (!std::isnan(options.moved_sigma[a]) || !std::isnan(options.noise_sigma[a])) {
        throw std::invalid_argument(
            "FixErrorMixture: an axis not modelled needs all three sigmas NaN");
      }
      continue;
    }
    ++modelled;
    if (!(options.noise_sigma[a] > 0.0)) {
      throw std::invalid_argument("FixErrorMixture: noise sigmas must be > 0");
    }
    if (!(est_var[a] > 0.0) || !std::isfinite(est_var[a])) {
      throw std::invalid_argument("FixErrorMixture: the estimate's variances must be > 0");
    }
    usual_.error[a].begin(options.usual_sigma[a]);  // throws for sigma <= 0
    moved_.error[a].begin(options.moved_sigma[a]);
  }
  if (modelled == 0) throw std::invalid_argument("FixErrorMixture: no axis modelled");
  usual_.offset = moved_.offset = Axes3{};
  usual_.var = moved_.var = est_var;
  options_ = options;
  log_odds_moved_ = std::log(options.moved_prior / (1.0 - options.moved_prior));
}

Axes3 FixErrorMixture::update(const Axes3& innovation, double weight) {
  if (!(weight > 0.0 && weight <= 1.0)) {
    throw std::invalid_argument("FixErrorMixture: the fix's weight must be in (0, 1]");
  }
  double log_ratio = 0.0;  // log p(fix | moved) - log p(fix | usual)
  bool any = false;
  for (int a = 0; a < 3; ++a) {
    if (std::isnan(innovation[a])) continue;  // this fix does not measure the axis
    if (!std::isfinite(innovation[a])) {
      throw std::invalid_argument("FixErrorMixture: an innovation must be finite or NaN");
    }
    if (!options_.models(a)) {
      throw std::invalid_argument("FixErrorMixture: an innovation on an axis not modelled");
    }
    any = true;
    const double r_var = options_.noise_sigma[a] * options_.noise_sigma[a] / weight;
    double ll[2];
    Hypothesis* hs[2] = {&usual_, &moved_};
    for (int k = 0; k < 2; ++k) {
      Hypothesis& h = *hs[k];
      const double y = innovation[a] - h.offset[a];  // against this hypothesis's estimate
      ll[k] = log_density(y - h.error[a].expected(), h.error[a].expected_var(h.var[a], r_var));
      h.offset[a] += h.error[a].update(h.var[a], y, r_var);
    }
    log_ratio += ll[1] - ll[0];
  }
  if (!any) return Axes3{};
  log_odds_moved_ = std::clamp(log_odds_moved_ + log_ratio, -kMaxLogOdds, kMaxLogOdds);
  // The mixture's mean moves; both offsets are re-referenced to it.
  const double p = usual_probability();
  Axes3 move{};
  for (int a = 0; a < 3; ++a) {
    move[a] = p * usual_.offset[a] + (1.0 - p) * moved_.offset[a];
    usual_.offset[a] -= move[a];
    moved_.offset[a] -= move[a];
  }
  return move;
}

Axes3 FixErrorMixture::variance() const {
  const double p = usual_probability();
  Axes3 v{};
  for (int a = 0; a < 3; ++a) {
    v[a] = !models(a) ? kNaN
                      : p * (usual_.var[a] + usual_.offset[a] * usual_.offset[a]) +
                            (1.0 - p) * (moved_.var[a] + moved_.offset[a] * moved_.offset[a]);
  }
  return v;
}

namespace {
void check_modelled(const FixErrorMixtureOptions& o, int axis) {
  if (axis < 0 || axis > 2) throw std::invalid_argument("FixErrorMixture: axis must be 0, 1 or 2");
  if (!o.models(axis)) throw std::invalid_argument("FixErrorMixture: axis not modelled");
}
}  // namespace

void FixErrorMixture::grow(int axis, double d_sigma) {
  check_modelled(options_, axis);
  if (!(d_sigma >= 0.0) || !std::isfinite(d_sigma)) {
    throw std::invalid_argument("FixErrorMixture: a growth must be >= 0 and finite");
  }
  for (Hypothesis* h : {&usual_, &moved_}) {
    const double s = std::sqrt(h->var[axis]) + d_sigma;
    h->var[axis] = s * s;
  }
}

void FixErrorMixture::rescale(int axis, double before, double after) {
  check_modelled(options_, axis);
  if (!(before > 0.0) || !std::isfinite(before) || !(after > 0.0) || !std::isfinite(after)) {
    throw std::invalid_argument("FixErrorMixture: variances must be > 0 and finite");
  }
  for (Hypothesis* h : {&usual_, &moved_}) {
    h->var[axis] *= after / before;
    h->error[axis].rescale(before, after);
  }
}

double FixErrorMixture::usual_probability() const {
  return 1.0 / (1.0 + std::exp(log_odds_moved_));
}

Axes3 FixErrorMixture::expected() const {
  Axes3 e{};
  for (int a = 0; a < 3; ++a) {
    e[a] = models(a) ? usual_.offset[a] + usual_.error[a].expected() : kNaN;
  }
  return e;
}

Axes3 FixErrorMixture::expected_var() const {
  Axes3 v{};
  for (int a = 0; a < 3; ++a) {
    v[a] = !models(a) ? kNaN
                      : usual_.error[a].expected_var(
                            usual_.var[a], options_.noise_sigma[a] * options_.noise_sigma[a]);
  }
  return v;
}

}  // namespace pepper::core::navigator
