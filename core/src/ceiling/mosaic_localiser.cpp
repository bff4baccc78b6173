// Localisation against the ceiling mosaic (see mosaic_localiser.hpp).
#include "core/ceiling/mosaic_localiser.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/core/hal/hal.hpp>
#include <opencv2/features2d.hpp>
#include <stdexcept>
#include <unordered_map>

namespace pepper::core::ceiling {

void LocaliserOptions::check() const {
  if (max_hamming < 1 || max_hamming > 256)
    throw std::invalid_argument("MosaicLocaliser: max_hamming must be in [1, 256]");
  if (!(std::isfinite(prior_radius_m) && prior_radius_m > 0.0))
    throw std::invalid_argument("MosaicLocaliser: prior_radius_m must be finite and > 0");
  if (!(std::isfinite(refine_radius_m) && refine_radius_m > 0.0))
    throw std::invalid_argument("MosaicLocaliser: refine_radius_m must be finite and > 0");
  if (!(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0))
    throw std::invalid_argument("MosaicLocaliser: min_inlier_ratio must be in [0, 1]");
  ransac.check();
}

MosaicLocaliser::MosaicLocaliser(Mosaic mosaic, LocaliserOptions options)
    : mosaic_(std::move(mosaic)), options_(std::move(options)) {
  options_.check();
  const auto errors = mosaic_.validate();
  if (!errors.empty()) throw std::invalid_argument("MosaicLocaliser: invalid mosaic: " + errors[0]);
  if (mosaic_.landmarks.empty())
    throw std::invalid_argument("MosaicLocaliser: the mosaic has no landmarks");
  descriptors_.create(static_cast<int>(mosaic_.landmarks.size()), kMosaicDescriptorBytes, CV_8U);
  for (size_t k = 0; k < mosaic_.landmarks.size(); ++k)
    mosaic_.landmarks[k].descriptor.copyTo(descriptors_.row(static_cast<int>(k)));
  by_x_.resize(mosaic_.landmarks.size());
  std::iota(by_x_.begin(), by_x_.end(), size_t{0});
  std::sort(by_x_.begin(), by_x_.end(), [&](size_t a, size_t b) {
    return mosaic_.landmarks[a].position_m.x < mosaic_.landmarks[b].position_m.x;
  });
  for (size_t k : by_x_) xs_.push_back(mosaic_.landmarks[k].position_m.x);
}

std::vector<size_t> MosaicLocaliser::within(const cv::Point2d& p_m, double radius_m) const {
  std::vector<size_t> out;
  const auto lo = std::lower_bound(xs_.begin(), xs_.end(), p_m.x - radius_m);
  const auto hi = std::upper_bound(xs_.begin(), xs_.end(), p_m.x + radius_m);
  const double r2 = radius_m * radius_m;
  for (auto it = lo; it != hi; ++it) {
    const size_t k = by_x_[static_cast<size_t>(it - xs_.begin())];
    const cv::Point2d d = mosaic_.landmarks[k].position_m - p_m;
    if (d.x * d.x + d.y * d.y <= r2) out.push_back(k);
  }
  return out;
}

template <typename Candidates>
void MosaicLocaliser::match(const CeilingObservation& obs, Candidates candidates,
                            std::vector<size_t>& obs_index,
                            std::vector<size_t>& mosaic_index) const {
  std::unordered_map<size_t, std::pair<size_t, int>> best_of_landmark;  // k -> (obs, distance)
  for (size_t i = 0; i < obs.size(); ++i) {
    const uchar* d_i = obs.descriptors.ptr<uchar>(static_cast<int>(i));
    int best = std::numeric_limits<int>::max();
    size_t best_k = 0;
    candidates(i, [&](size_t k) {
      const int dist = cv::hal::normHamming(d_i, descriptors_.ptr<uchar>(static_cast<int>(k)),
                                            kMosaicDescriptorBytes);
      if (dist < best) {
        best = dist;
        best_k = k;
      }
    });
    if (best > options_.max_hamming) continue;
    const auto it = best_of_landmark.find(best_k);
    if (it == best_of_landmark.end() || best < it->second.second)
      best_of_landmark[best_k] = {i, best};
  }
  obs_index.clear();
  mosaic_index.clear();
  for (const auto& [k, od] : best_of_landmark) {
    obs_index.push_back(od.first);
    mosaic_index.push_back(k);
  }
}

MosaicFix MosaicLocaliser::localise(const CeilingObservation& obs,
                                    const std::optional<PlanarPose>& prior) const {
  if (obs.descriptors.rows != static_cast<int>(obs.size()))
    throw std::invalid_argument("MosaicLocaliser::localise: one descriptor per landmark expected");
  if (!obs.descriptors.empty() &&
      (obs.descriptors.type() != CV_8U || obs.descriptors.cols != kMosaicDescriptorBytes))
    throw std::invalid_argument("MosaicLocaliser::localise: descriptors must be 32-byte ORB rows");
  MosaicFix fix;
  if (obs.size() < 2) return fix;
  std::vector<size_t> oi, mi;
  if (prior) {
    match(
        obs,
        [&](size_t i, auto&& visit) {
          for (size_t k : within(prior->apply(obs.p_base_m[i]), options_.prior_radius_m)) visit(k);
        },
        oi, mi);
  } else {
    // No prior: the nearest descriptor in the whole mosaic (OpenCV's vectorised brute force).
    cv::BFMatcher matcher(cv::NORM_HAMMING);
    std::vector<cv::DMatch> nearest;
    matcher.match(obs.descriptors, descriptors_, nearest);
    std::unordered_map<size_t, std::pair<size_t, float>> best_of_landmark;
    for (const cv::DMatch& m : nearest) {
      if (m.distance > options_.max_hamming) continue;
      const size_t k = static_cast<size_t>(m.trainIdx);
      const auto it = best_of_landmark.find(k);
      if (it == best_of_landmark.end() || m.distance < it->second.second)
        best_of_landmark[k] = {static_cast<size_t>(m.queryIdx), m.distance};
    }
    for (const auto& [k, od] : best_of_landmark) {
      oi.push_back(od.first);
      mi.push_back(k);
    }
  }
  fix.matches = static_cast<int>(oi.size());
  auto pairs = [&](std::vector<cv::Point2d>& src, std::vector<cv::Point2d>& dst) {
    src.clear();
    dst.clear();
    for (size_t p = 0; p < oi.size(); ++p) {
      src.push_back(obs.p_base_m[oi[p]]);
      dst.push_back(mosaic_.landmarks[mi[p]].position_m);
    }
  };
  std::vector<cv::Point2d> src, dst;
  pairs(src, dst);
  RigidFit fit = ransac_rigid(src, dst, options_.ransac);
  if (!fit.found) return fix;
  std::vector<size_t> fit_oi = oi;  // the pairs `fit` was made from
  // Guided re-matching around the robust pose: landmarks whose first nearest descriptor was
  // elsewhere (repeated texture) are found near their predicted place.
  for (int round = 0; round < 2; ++round) {
    const PlanarPose T = fit.T_dst_src;
    match(
        obs,
        [&](size_t i, auto&& visit) {
          for (size_t k : within(T.apply(obs.p_base_m[i]), options_.refine_radius_m)) visit(k);
        },
        oi, mi);
    pairs(src, dst);
    RigidRansacOptions refine = options_.ransac;
    refine.iterations = 100;  // the consensus is near T already
    const RigidFit refined = ransac_rigid(src, dst, refine);
    if (!refined.found || refined.inliers < fit.inliers) break;
    fit = refined;
    fit_oi = oi;
  }
  fix.inliers = fit.inliers;
  for (size_t p = 0; p < fit.inlier.size() && p < fit_oi.size(); ++p) {
    if (fit.inlier[p]) fix.inlier_observations.push_back(static_cast<int>(fit_oi[p]));
  }
  fix.rms_m = fit.rms_m;
  // Checked after the guided re-matching, which finds the landmarks the first nearest-descriptor
  // step missed: a view that overlaps the mosaic only in part has a low first-step ratio.
  if (fit.inliers < options_.min_inlier_ratio * fix.matches) return fix;
  fix.found = true;
  fix.T_mosaic_base = fit.T_dst_src;
  return fix;
}

}  // namespace pepper::core::ceiling
