#pragma once
// Test support for the ceiling tests that run without rendering (mosaic builder, localiser,
// ceiling navigator): a ceiling of points on a jittered 0.1 m grid, each with a random ORB-like
// descriptor, what a base at a known pose sees of it, a loop to drive under it, and the
// observation errors that make a chained mosaic drift.

#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/ceiling/mosaic.hpp"
#include "core/ceiling/mosaic_builder.hpp"
#include "core/odometry.hpp"
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

// What a MosaicBuilder made with `o` throws (std::invalid_argument's message), or "".
inline std::string builder_error(const MosaicBuilderOptions& o) {
  try {
    MosaicBuilder b(o);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return {};
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

/// A tour of the synthetic ceiling: the true base pose T_world_base per frame.
struct SyntheticPath {
  std::vector<PlanarPose> truth;
  size_t back_at_start = 0;  ///< first frame back at the start (loops)
};

/// A rounded rectangle driven counter-clockwise from (0, 0) heading +x, `step_m` per frame:
/// straights of 4 m and 2 m, 90 degree left turns of radius 1 m (18.3 m), back at the start,
/// then `overlap_m` more along the first straight: the loop's end sees its beginning again.
inline SyntheticPath rounded_rectangle(double overlap_m, double step_m) {
  SyntheticPath path;
  PlanarPose p{0.0, 0.0, 0.0};
  path.truth.push_back(p);
  auto straight = [&](double length_m) {
    const int n = static_cast<int>(std::lround(length_m / step_m));
    for (int i = 0; i < n; ++i) path.truth.push_back(p = p * PlanarPose{length_m / n, 0.0, 0.0});
  };
  auto turn = [&]() {
    constexpr double kRadiusM = 1.0;
    const int n = static_cast<int>(std::lround(0.5 * M_PI * kRadiusM / step_m));
    const double dth = 0.5 * M_PI / n, chord = 2.0 * kRadiusM * std::sin(0.5 * dth);
    for (int i = 0; i < n; ++i)
      path.truth.push_back(
          p = p * PlanarPose{chord * std::cos(0.5 * dth), chord * std::sin(0.5 * dth), dth});
  };
  for (int side = 0; side < 2; ++side) {
    straight(4.0);
    turn();
    straight(2.0);
    turn();
  }
  path.back_at_start = path.truth.size() - 1;
  straight(overlap_m);
  return path;
}

/// The errors that make a chained mosaic drift (test_mosaic_loop_closure.cpp's header):
/// Gaussian noise per axis on every landmark position, a fraction of the descriptor bits flipped
/// per sighting, and a forward stretch growing across the view, x' = x (1 + k (x - 0.8 m)).
struct ChainErrors {
  double noise_m = 0.003;
  double flip = 0.1;
  double stretch_1_m = 0.01;
};

/// Applies ChainErrors to successive observations, drawing from `rng` (one noise distribution for
/// the whole teach, so that a teach is one deterministic sequence).
class ChainErrorInjector {
 public:
  ChainErrorInjector(const ChainErrors& e, std::mt19937& rng)
      : e_(e), rng_(rng), noise_(0.0, e.noise_m) {}

  void apply(CeilingObservation& o) {
    const uint32_t flip_below = static_cast<uint32_t>(e_.flip * 4294967295.0);
    for (cv::Point2d& p : o.p_base_m) {
      p.x *= 1.0 + e_.stretch_1_m * (p.x - 0.8);
      if (e_.noise_m > 0.0) p += cv::Point2d(noise_(rng_), noise_(rng_));
    }
    o.descriptors = o.descriptors.clone();
    for (int r = 0; e_.flip > 0.0 && r < o.descriptors.rows; ++r)
      for (int b = 0; b < kMosaicDescriptorBytes; ++b)
        for (int bit = 0; bit < 8; ++bit)
          if (rng_() < flip_below)
            o.descriptors.at<uint8_t>(r, b) ^= static_cast<uint8_t>(1u << bit);
  }

 private:
  ChainErrors e_;
  std::mt19937& rng_;
  std::normal_distribution<double> noise_;
};

/// A teach driven in legs of equal steps, some blind (the camera sees no ceiling point).
struct SyntheticLeg {
  PlanarPose step;  ///< T_prev_next per frame
  int frames = 0;
  bool blind = false;
};

/// The true base pose per frame, whether it is blind, and the wheel odometry: each true step
/// with `odometry_scale` times its translation and rotation (1.02: 2 % too long and too much).
struct SyntheticLegTour {
  std::vector<PlanarPose> truth;  ///< T_world_base per frame
  std::vector<uint8_t> blind;
  std::vector<OdometryPose> odom;
};

inline SyntheticLegTour drive_legs(const PlanarPose& start, const std::vector<SyntheticLeg>& legs,
                                   double odometry_scale = 1.02) {
  SyntheticLegTour t;
  PlanarPose p = start, o{0.0, 0.0, 0.0};
  t.truth.push_back(p);
  t.blind.push_back(0);
  t.odom.push_back({0.0, 0.0, 0.0});
  for (const SyntheticLeg& leg : legs)
    for (int i = 0; i < leg.frames; ++i) {
      t.truth.push_back(p = p * leg.step);
      t.blind.push_back(leg.blind ? 1 : 0);
      o = o * PlanarPose{odometry_scale * leg.step.x_m, odometry_scale * leg.step.y_m,
                         odometry_scale * leg.step.theta_rad};
      t.odom.push_back({o.x_m, o.y_m, o.theta_rad});
    }
  return t;
}

}  // namespace pepper::core::ceiling::test_support
