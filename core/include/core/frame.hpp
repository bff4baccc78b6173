#pragma once
// A camera frame as the core sees it: an 8-bit single-channel image and its capture stamp.
//
// Time base: `t_ns` is the capture time in nanoseconds on the robot's (or simulator's) monotonic
// clock, as carried by the bridge. The core never reads the wall clock (ARCHITECTURE.md).
// Conventions for frames, signs and units: docs/conventions.md.

#include <cstdint>
#include <optional>

#include <opencv2/core/mat.hpp>

#include "core/odometry.hpp"

namespace pepper::core {

struct Frame {
  cv::Mat gray;        ///< CV_8UC1, any size; shared buffer (cv::Mat semantics), treat as read-only.
  int64_t t_ns = 0;    ///< capture time, ns, monotonic clock of the image source.
  int64_t index = -1;  ///< sequence number assigned by the source (-1 when unknown).
  /// The robot's odometry read with this frame (core/odometry.hpp); nullopt when the source has
  /// none (plain image sequences, old recordings).
  std::optional<OdometryPose> odom;
};

}  // namespace pepper::core
