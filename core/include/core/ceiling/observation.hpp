#pragma once
// One frame's ceiling landmarks in the robot's base frame (issue 24): the canonical view's
// landmarks (landmarks.hpp) turned into metric points on the ceiling plane, relative to the base,
// so that the mosaic builder and the localiser fit base poses, not camera poses.
//
// Frames and units: base frame x forward, y left (docs/conventions.md), metres, the ceiling point
// projected vertically; orientation_base_rad is the landmark's (ORB) orientation as an angle in
// those axes, counter-clockwise seen from above. The canonical view is a proper rotation of the
// base axes (u = robot left, v = robot back), so angles keep their sign:
// orientation_base_rad = orientation_canon_rad + pi/2.
// cam_in_base_m: the optical centre's horizontal offset from the base's rotation axis (the
// canonical view is centred on the optical centre; for Pepper it is ~5-9 cm forward and depends
// on the head pitch, sim::CameraMount::T_base_cam). Pure.

#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <vector>

#include "core/ceiling/canonical_view.hpp"
#include "core/ceiling/landmarks.hpp"

namespace pepper::core::ceiling {

struct CeilingObservation {
  std::vector<cv::Point2d> p_base_m;          ///< ceiling point, base frame
  std::vector<double> orientation_base_rad;   ///< base frame, counter-clockwise from above
  std::vector<cv::Point2f> p_canon_px;        ///< where it was seen in the canonical view
  std::vector<double> orientation_canon_rad;  ///< its orientation there (image axes, y down)
  cv::Mat descriptors;                        ///< one ORB row per landmark (CV_8U)

  size_t size() const { return p_base_m.size(); }
};

/// The landmarks of one canonical view in the base frame.
CeilingObservation observe(const CanonicalView& view, const cv::Point2d& cam_in_base_m,
                           const CeilingLandmarks& landmarks);

}  // namespace pepper::core::ceiling
