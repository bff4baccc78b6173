#pragma once
// Distance driven during teach: the path length between key images (the map's
// `KeyImage::travelled_m`). The navigator turns a segment's image-space geometry into metres with
// it (VNHV's lateral scale, the taught turn's curvature, the blind-switch guard); without it, it
// falls back to the taught time times a nominal speed, which is wrong wherever the operator drove
// slower or faster (a turn, a pause).
//
// Two sources, chosen per interval between consecutive frames:
//   - the robot's odometry (Frame::odom, ALMotion.getRobotPosition(true)) when both frames carry
//     it: the length of the straight step between the two readings. It measures what the base
//     did (a blocked or slipping base, a slow start, a speed limit), not what it was told;
//   - else the forward speed commanded to the base, |v_m_s| over the interval (the fallback for
//     robots and recordings without odometry, and for a frame whose reading failed).
// An odometry step faster than kMaxPlausibleSpeed_m_s (Pepper cannot drive it: the odometry was
// reset or jumped) is not believed: that interval uses the commanded speed and is counted.
//
// Convention: `v_m_s` given with a frame is the command in force while the base moved from the
// previous frame to this one (as in a recording's frames.jsonl). Reversing counts as distance
// too: a path length, not a displacement. Stamps that do not increase add nothing.
// Pure and deterministic; not thread-safe.

#include <cstdint>
#include <optional>

#include "core/odometry.hpp"

namespace pepper::core::mapping {

class DriveOdometer {
 public:
  /// Above Pepper's top speed (0.55 m/s, ALMotion MaxVelXY 0.35 by default) with a margin.
  static constexpr double kMaxPlausibleSpeed_m_s = 1.0;

  /// Adds the interval since the previous frame (from the odometry when this frame and the
  /// previous one have it, else at |v_m_s|); returns the distance driven since the first frame
  /// (0 on the first). A non-finite v_m_s or odometry value throws std::invalid_argument.
  double on_frame(int64_t t_ns, double v_m_s,
                  const std::optional<OdometryPose>& odom = std::nullopt);
  double travelled_m() const { return travelled_m_; }
  /// The part of travelled_m() measured by the odometry (the rest is commanded speed).
  double from_odometry_m() const { return from_odometry_m_; }
  /// Intervals whose odometry step was implausibly fast (replaced by the commanded speed).
  int64_t odometry_jumps() const { return odometry_jumps_; }

 private:
  std::optional<int64_t> last_t_ns_;
  std::optional<OdometryPose> last_odom_;
  double travelled_m_ = 0.0;
  double from_odometry_m_ = 0.0;
  int64_t odometry_jumps_ = 0;
};

}  // namespace pepper::core::mapping
