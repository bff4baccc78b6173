// Canonical-view landmarks in the base frame (see observation.hpp).
#include "core/ceiling/observation.hpp"

#include <cmath>

namespace pepper::core::ceiling {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

CeilingObservation observe(const CanonicalView& view, const cv::Point2d& cam_in_base_m,
                           const CeilingLandmarks& landmarks) {
  CeilingObservation out;
  out.descriptors = landmarks.descriptors.clone();
  const size_t n = landmarks.keypoints.size();
  out.p_base_m.reserve(n);
  out.orientation_base_rad.reserve(n);
  out.p_canon_px.reserve(n);
  out.orientation_canon_rad.reserve(n);
  for (const cv::KeyPoint& k : landmarks.keypoints) {
    // ceiling_of_canonical gives (forward_m, left_m) from the optical centre, in base axes.
    const cv::Point2d fl = view.ceiling_of_canonical(cv::Point2d(k.pt));
    out.p_base_m.push_back(fl + cam_in_base_m);
    // ORB's angle is in degrees in image axes; an image direction (cos a, sin a) in (u, v) is the
    // base direction (-sin a, cos a), i.e. the angle a + pi/2.
    const double a = (k.angle >= 0.0f ? k.angle : 0.0f) * kPi / 180.0;
    out.p_canon_px.push_back(k.pt);
    out.orientation_canon_rad.push_back(a);
    out.orientation_base_rad.push_back(std::atan2(std::cos(a), -std::sin(a)));
  }
  return out;
}

}  // namespace pepper::core::ceiling
