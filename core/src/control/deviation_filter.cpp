#include "core/control/deviation_filter.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>  // Matx inv
#include <sstream>
#include <stdexcept>

namespace pepper::core::control {

std::vector<std::string> DeviationFilterOptions::validate() const {
  std::vector<std::string> errors;
  auto check = [&](bool ok, const char* name, double value, const char* range) {
    if (!ok) {
      std::ostringstream os;
      os << "control.vnhv.filter." << name << " = " << value << " must be " << range;
      errors.push_back(os.str());
    }
  };
  auto positive = [&](double v, const char* name) {
    check(std::isfinite(v) && v > 0.0, name, v, "> 0");
  };
  positive(measurement_sigma_m, "measurement_sigma_m");
  positive(measurement_sigma_rad, "measurement_sigma_rad");
  positive(process_sigma_m, "process_sigma_m");
  positive(process_sigma_rad, "process_sigma_rad");
  positive(gate_chi2, "gate_chi2");
  check(max_rejections >= 1, "max_rejections", max_rejections, ">= 1");
  check(max_prediction_s >= 0, "max_prediction_s", max_prediction_s, ">= 0");
  return errors;
}

DeviationFilter::DeviationFilter(const DeviationFilterOptions& options) : options_(options) {
  if (const auto errors = options_.validate(); !errors.empty()) {
    throw std::invalid_argument("DeviationFilter: " + errors.front());
  }
}

void DeviationFilter::reset() {
  started_ = false;
  rejections_ = 0;
}

void DeviationFilter::start(const SegmentDeviation& measured, int64_t t_ns, double weight) {
  started_ = true;
  y_m_ = measured.lateral_m;
  theta_rad_ = wrap_angle_rad(measured.heading_rad);
  const double sy = options_.measurement_sigma_m, st = options_.measurement_sigma_rad;
  P_ = cv::Matx22d(sy * sy, 0.0, 0.0, st * st) * (1.0 / weight);
  t_ns_ = t_ns;
  last_accepted_t_ns_ = t_ns;
  rejections_ = 0;
}

void DeviationFilter::predict(double v_m_s, double omega_rad_s, int64_t t_ns,
                              double curvature_1_m) {
  if (!std::isfinite(v_m_s) || !std::isfinite(omega_rad_s) || !std::isfinite(curvature_1_m)) {
    throw std::invalid_argument("DeviationFilter::predict: non-finite command");
  }
  if (!started_) return;
  if (t_ns < t_ns_) {
    throw std::invalid_argument("DeviationFilter::predict: t_ns " + std::to_string(t_ns) +
                                " is before the state's " + std::to_string(t_ns_));
  }
  const double dt = static_cast<double>(t_ns - t_ns_) * 1e-9;
  const double path_rate =
      curvature_1_m == 0.0 ? 0.0
                           : curvature_1_m * v_m_s * std::cos(theta_rad_) /
                                 std::max(0.1, 1.0 - curvature_1_m * y_m_);
  const double turn_rate = omega_rad_s - path_rate;  // heading change relative to the path
  const double theta_mid = theta_rad_ + 0.5 * turn_rate * dt;
  y_m_ += v_m_s * std::sin(theta_mid) * dt;
  theta_rad_ = wrap_angle_rad(theta_rad_ + turn_rate * dt);
  const cv::Matx22d F(1.0, v_m_s * std::cos(theta_mid) * dt, 0.0, 1.0);
  const double qy = options_.process_sigma_m, qt = options_.process_sigma_rad;
  P_ = F * P_ * F.t() + cv::Matx22d(qy * qy * dt, 0.0, 0.0, qt * qt * dt);
  t_ns_ = t_ns;
}

DeviationFilter::Correction DeviationFilter::correct(const SegmentDeviation& measured,
                                                     int64_t t_ns, double weight) {
  if (!std::isfinite(measured.lateral_m) || !std::isfinite(measured.heading_rad)) {
    throw std::invalid_argument("DeviationFilter::correct: non-finite measurement");
  }
  if (!(weight > 0.0 && weight <= 1.0)) {
    throw std::invalid_argument("DeviationFilter::correct: weight " + std::to_string(weight) +
                                " is not in (0, 1]");
  }
  if (!started_) {
    start(measured, t_ns, weight);
    return Correction::kStarted;
  }
  if (t_ns != t_ns_) {
    throw std::invalid_argument("DeviationFilter::correct: measurement at t_ns " +
                                std::to_string(t_ns) + ", state at " + std::to_string(t_ns_) +
                                " (predict first)");
  }
  const double sy = options_.measurement_sigma_m, st = options_.measurement_sigma_rad;
  const cv::Vec2d innovation(measured.lateral_m - y_m_,
                             wrap_angle_rad(measured.heading_rad - theta_rad_));
  const cv::Matx22d S = P_ + cv::Matx22d(sy * sy, 0.0, 0.0, st * st) * (1.0 / weight);
  const cv::Matx22d S_inv = S.inv();
  const double d2 = (innovation.t() * S_inv * innovation)(0);
  if (!(d2 <= options_.gate_chi2)) {
    if (++rejections_ >= options_.max_rejections) {
      start(measured, t_ns, weight);
      return Correction::kRestarted;
    }
    return Correction::kRejected;
  }
  const cv::Matx22d K = P_ * S_inv;
  const cv::Vec2d dx = K * innovation;
  y_m_ += dx[0];
  theta_rad_ = wrap_angle_rad(theta_rad_ + dx[1]);
  P_ = (cv::Matx22d::eye() - K) * P_;
  last_accepted_t_ns_ = t_ns;
  rejections_ = 0;
  return Correction::kAccepted;
}

std::optional<SegmentDeviation> DeviationFilter::estimate(int64_t t_ns) const {
  if (!started_ || t_ns - last_accepted_t_ns_ > std::llround(options_.max_prediction_s * 1e9)) {
    return std::nullopt;
  }
  return SegmentDeviation{y_m_, theta_rad_};
}

}  // namespace pepper::core::control
