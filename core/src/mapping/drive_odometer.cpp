#include "core/mapping/drive_odometer.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace pepper::core::mapping {

double DriveOdometer::on_frame(int64_t t_ns, double v_m_s,
                               const std::optional<OdometryPose>& odom) {
  if (!std::isfinite(v_m_s)) {
    throw std::invalid_argument("DriveOdometer::on_frame: commanded speed is not finite (" +
                                std::to_string(v_m_s) + ")");
  }
  if (odom &&
      !(std::isfinite(odom->x_m) && std::isfinite(odom->y_m) && std::isfinite(odom->yaw_rad))) {
    throw std::invalid_argument("DriveOdometer::on_frame: odometry is not finite");
  }
  if (last_t_ns_ && t_ns > *last_t_ns_) {
    const double dt_s = static_cast<double>(t_ns - *last_t_ns_) * 1e-9;
    double step_m = std::abs(v_m_s) * dt_s;
    if (odom && last_odom_) {
      const double odom_m = std::hypot(odom->x_m - last_odom_->x_m, odom->y_m - last_odom_->y_m);
      if (odom_m <= kMaxPlausibleSpeed_m_s * dt_s) {
        step_m = odom_m;
        from_odometry_m_ += odom_m;
      } else {
        ++odometry_jumps_;
      }
    }
    travelled_m_ += step_m;
  }
  if (!last_t_ns_ || t_ns > *last_t_ns_) {
    last_t_ns_ = t_ns;
    last_odom_ = odom;
  }
  return travelled_m_;
}

}  // namespace pepper::core::mapping
