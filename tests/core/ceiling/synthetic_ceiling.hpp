#pragma once
// Test support for the ceiling tests that run without rendering (mosaic builder, localiser,
// ceiling navigator): a ceiling of points on a jittered 0.1 m grid, each with a random ORB-like
// descriptor, and what a base at a known pose sees of it.

#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "core/ceiling/mosaic.hpp"
#include "core/ceiling/observation.hpp"
#include "core/ceiling/planar_rigid.hpp"

namespace pepper::core::ceiling::test_support {

struct SyntheticCeiling {
  std::vector<cv::Point2d> points_world;  ///< ceiling points, world = mosaic frame (m)
  cv::Mat descriptors;                    ///< one random row per point
};

/// Points every 0.1 m (jittered by +-1.5 cm) over nx x ny cells from (x0_m, y0_m).
inline SyntheticCeiling make_synthetic_ceiling(uint32_t seed, double x0_m, int nx, double y0_m,
                                               int ny) {
  SyntheticCeiling c;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      c.points_world.emplace_back(x0_m + 0.1 * i + 0.03 * u(rng), y0_m + 0.1 * j + 0.03 * u(rng));
  c.descriptors.create(static_cast<int>(c.points_world.size()), kMosaicDescriptorBytes, CV_8U);
  cv::randu(c.descriptors, 0, 256);
  return c;
}

inline cv::Mat random_descriptor(std::mt19937& rng) {
  cv::Mat d(1, kMosaicDescriptorBytes, CV_8U);
  for (int b = 0; b < kMosaicDescriptorBytes; ++b)
    d.at<uint8_t>(0, b) = static_cast<uint8_t>(rng());
  return d;
}

/// What a base at T_world_base sees: the ceiling points 0.3..1.3 m ahead and within +-0.6 m
/// left (none when `blind`), plus `junk` points with random descriptors (a person, a moved lamp,
/// a view the mosaic does not know).
inline CeilingObservation see_synthetic(const SyntheticCeiling& c, const PlanarPose& T_world_base,
                                        std::mt19937& rng, int junk = 0, bool blind = false) {
  CeilingObservation o;
  const PlanarPose T_base_world = T_world_base.inverse();
  std::vector<cv::Mat> rows;
  for (size_t k = 0; !blind && k < c.points_world.size(); ++k) {
    const cv::Point2d p = T_base_world.apply(c.points_world[k]);
    if (p.x < 0.3 || p.x > 1.3 || std::abs(p.y) > 0.6) continue;
    o.p_base_m.push_back(p);
    rows.push_back(c.descriptors.row(static_cast<int>(k)));
  }
  std::uniform_real_distribution<double> fwd(0.3, 1.3), left(-0.6, 0.6);
  for (int j = 0; j < junk; ++j) {
    o.p_base_m.emplace_back(fwd(rng), left(rng));
    rows.push_back(random_descriptor(rng));
  }
  for (size_t i = 0; i < o.p_base_m.size(); ++i) {
    o.orientation_base_rad.push_back(0.0);
    o.p_canon_px.emplace_back(static_cast<float>(i), 0.0f);
    o.orientation_canon_rad.push_back(0.0);
  }
  if (!rows.empty()) cv::vconcat(rows, o.descriptors);
  return o;
}

}  // namespace pepper::core::ceiling::test_support
