#include "core/camera/distortion.hpp"

namespace pepper::core::camera {

cv::Point2d pixel_to_norm(const CameraIntrinsics& k, const cv::Point2d& p_px) {
  const cv::Point2d d = k.normalize(p_px);  // distorted normalised coordinates
  if (k.model == ProjectionModel::kWithoutDistortion) return d;
  const double scale = 1.0 + k.kdu * (d.x * d.x + d.y * d.y);
  return {d.x * scale, d.y * scale};
}

cv::Point2d norm_to_pixel(const CameraIntrinsics& k, const cv::Point2d& p_norm) {
  if (k.model == ProjectionModel::kWithoutDistortion) return k.denormalize(p_norm);
  const double scale = 1.0 + k.kud * (p_norm.x * p_norm.x + p_norm.y * p_norm.y);
  return k.denormalize({p_norm.x * scale, p_norm.y * scale});
}

}  // namespace pepper::core::camera
