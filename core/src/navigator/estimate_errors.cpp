#include "core/navigator/estimate_errors.hpp"

#include <cmath>
#include <stdexcept>

namespace pepper::core::navigator {

EstimateErrors::EstimateErrors(const FixErrorMixtureOptions& vnhv,
                               const FixErrorMixtureOptions& line_yaw,
                               const FixErrorMixtureOptions& floor_lines,
                               const FixErrorMixtureOptions& switches) {
  sources_[0].options = vnhv;
  sources_[1].options = line_yaw;
  sources_[2].options = floor_lines;
  sources_[3].options = switches;
  for (int a = 0; a < 3; ++a) {
    if (!vnhv.models(a)) {
      throw std::invalid_argument("EstimateErrors: the VNHV fixes measure all three axes");
    }
  }
  // Each model's options are checked by a begin from unit variances (FixErrorMixture::begin).
  for (Source& s : sources_) s.mixture.begin(s.options, Axes3{1.0, 1.0, 1.0});
  place(sigma_);
}

Axes3 EstimateErrors::variances() const {
  return {sigma_[0] * sigma_[0], sigma_[1] * sigma_[1], sigma_[2] * sigma_[2]};
}

void EstimateErrors::place(const Axes3& sigma) {
  for (const double s : sigma) {
    if (!(s > 0.0) || !std::isfinite(s)) {
      throw std::invalid_argument("EstimateErrors: sigmas must be > 0 and finite");
    }
  }
  sigma_ = sigma;
  grown_ = {0.0, 0.0, 0.0};
  begin();
  source(FixSource::kSwitch).in = kNotBegun;
}

void EstimateErrors::begin() {
  Source& vnhv = source(FixSource::kVnhv);
  vnhv.mixture.begin(vnhv.options, variances());
  vnhv.in = kAnyIn;
  source(FixSource::kLineYaw).in = kNotBegun;
  source(FixSource::kFloorLines).in = kNotBegun;
}

void EstimateErrors::grow(const Axes3& d_sigma) {
  for (int a = 0; a < 3; ++a) {
    if (!(d_sigma[a] >= 0.0) || !std::isfinite(d_sigma[a])) {
      throw std::invalid_argument("EstimateErrors: a growth must be >= 0 and finite");
    }
  }
  for (int a = 0; a < 3; ++a) {
    sigma_[a] += d_sigma[a];
    grown_[a] += d_sigma[a];
  }
  for (Source& s : sources_) {
    if (s.in == kNotBegun) continue;
    for (int a = 0; a < 3; ++a) {
      if (s.options.models(a)) s.mixture.grow(a, d_sigma[a]);
    }
  }
}

const FixErrorMixture& EstimateErrors::model_for(FixSource which, int in) {
  Source& s = source(which);
  if (which == FixSource::kVnhv) return s.mixture;
  if (in < 0) throw std::invalid_argument("EstimateErrors: IN must be >= 0");
  if (which == FixSource::kSwitch) {  // one model from a placement on: the switches' shared error
    if (s.in == kNotBegun) {
      s.mixture.begin(s.options, variances());
      s.in = kAnyIn;
    }
    return s.mixture;
  }
  if (s.in != in) {
    s.mixture.begin(s.options, variances());
    s.in = in;
  }
  return s.mixture;
}

Axes3 EstimateErrors::update(FixSource which, const Axes3& innovation, double weight) {
  Source& s = source(which);
  if (s.in == kNotBegun) {
    throw std::invalid_argument("EstimateErrors: update of a model not begun (model_for first)");
  }
  const Axes3 move = s.mixture.update(innovation, weight);
  const Axes3 after = s.mixture.variance();
  for (int a = 0; a < 3; ++a) {
    if (!s.options.models(a)) continue;
    const double before = sigma_[a] * sigma_[a];
    for (Source& other : sources_) {
      if (&other == &s || other.in == kNotBegun || !other.options.models(a)) continue;
      other.mixture.rescale(a, before, after[a]);
    }
    sigma_[a] = std::sqrt(after[a]);
    grown_[a] = 0.0;
  }
  return move;
}

}  // namespace pepper::core::navigator
