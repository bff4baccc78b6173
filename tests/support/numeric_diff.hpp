#pragma once
// Central finite differences for Jacobian tests (STYLE.md 2.6).
//
// d f / d s at s0 ~ (f(s0 + h) - f(s0 - h)) / (2 h), truncation error O(h^2 f'''), rounding error
// O(eps |f| / h); h ~ cbrt(eps) * max(1, |s0|) balances the two (about 6e-6), giving ~1e-10
// relative accuracy on smooth functions. Tolerances in tests should be a few 1e-8.

#include <algorithm>
#include <cmath>
#include <limits>

namespace pepper::test {

/// Step that balances truncation and rounding for central differences at s0.
inline double central_diff_step(double s0) {
  return std::cbrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(s0));
}

/// Central difference of a scalar function of one scalar; step <= 0 picks central_diff_step.
template <typename F>
double central_diff(F&& f, double s0, double step = 0.0) {
  const double h = step > 0.0 ? step : central_diff_step(s0);
  return (f(s0 + h) - f(s0 - h)) / (2.0 * h);
}

/// |a - b| <= abs_tol + rel_tol * max(|a|, |b|): relative, and absolute near zero.
inline bool near_rel(double a, double b, double rel_tol, double abs_tol) {
  return std::abs(a - b) <= abs_tol + rel_tol * std::max(std::abs(a), std::abs(b));
}

}  // namespace pepper::test
