#include "core/mapping/drive_odometer.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace pepper::core::mapping {

double DriveOdometer::on_frame(int64_t t_ns, double v_m_s) {
  if (!std::isfinite(v_m_s)) {
    throw std::invalid_argument("DriveOdometer::on_frame: commanded speed is not finite (" +
                                std::to_string(v_m_s) + ")");
  }
  if (last_t_ns_ && t_ns > *last_t_ns_) {
    travelled_m_ += std::abs(v_m_s) * static_cast<double>(t_ns - *last_t_ns_) * 1e-9;
  }
  if (!last_t_ns_ || t_ns > *last_t_ns_) last_t_ns_ = t_ns;
  return travelled_m_;
}

}  // namespace pepper::core::mapping
