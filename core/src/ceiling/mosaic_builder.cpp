// Building the ceiling mosaic (see mosaic_builder.hpp).
#include "core/ceiling/mosaic_builder.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/core/hal/hal.hpp>
#include <stdexcept>
#include <unordered_set>

namespace pepper::core::ceiling {

namespace {

// Grid cells as large as the search radius: a query looks at the 3 x 3 cells around its point.
int64_t pack(int64_t cx, int64_t cy) { return (cx << 32) ^ (cy & 0xffffffffLL); }

}  // namespace

void MosaicBuilderOptions::check() const {
  if (!(std::isfinite(px_per_m) && px_per_m > 0.0))
    throw std::invalid_argument("MosaicBuilder: px_per_m must be finite and > 0");
  if (!(std::isfinite(search_radius_m) && search_radius_m > 0.0))
    throw std::invalid_argument("MosaicBuilder: search_radius_m must be finite and > 0");
  if (max_hamming < 1 || max_hamming > 256)
    throw std::invalid_argument("MosaicBuilder: max_hamming must be in [1, 256]");
  if (min_observations < 1)
    throw std::invalid_argument("MosaicBuilder: min_observations must be >= 1");
  if (candidate_timeout_frames < 1)
    throw std::invalid_argument("MosaicBuilder: candidate_timeout_frames must be >= 1");
  if (!(std::isfinite(min_separation_m) && min_separation_m >= 0.0))
    throw std::invalid_argument("MosaicBuilder: min_separation_m must be finite and >= 0");
  if (!(std::isfinite(landmark_step_m) && landmark_step_m >= 0.0))
    throw std::invalid_argument("MosaicBuilder: landmark_step_m must be finite and >= 0");
  if (!(std::isfinite(landmark_step_rad) && landmark_step_rad >= 0.0))
    throw std::invalid_argument("MosaicBuilder: landmark_step_rad must be finite and >= 0");
  ransac.check();
}

MosaicBuilder::MosaicBuilder(MosaicBuilderOptions options) : options_(std::move(options)) {
  options_.check();
}

int64_t MosaicBuilder::cell_key(const cv::Point2d& p_m) const {
  const double cell = options_.search_radius_m;
  return pack(static_cast<int64_t>(std::floor(p_m.x / cell)),
              static_cast<int64_t>(std::floor(p_m.y / cell)));
}

void MosaicBuilder::insert_in_grid(size_t index) {
  grid_[cell_key(landmarks_[index].position_m)].push_back(index);
}

std::vector<size_t> MosaicBuilder::near(const cv::Point2d& p_m, double radius_m) const {
  const double cell = options_.search_radius_m;
  const int64_t cx = static_cast<int64_t>(std::floor(p_m.x / cell));
  const int64_t cy = static_cast<int64_t>(std::floor(p_m.y / cell));
  const int64_t reach = static_cast<int64_t>(std::ceil(radius_m / cell));
  std::vector<size_t> out;
  const double r2 = radius_m * radius_m;
  for (int64_t dx = -reach; dx <= reach; ++dx)
    for (int64_t dy = -reach; dy <= reach; ++dy) {
      const auto it = grid_.find(pack(cx + dx, cy + dy));
      if (it == grid_.end()) continue;
      for (size_t k : it->second) {
        const Landmark& l = landmarks_[k];
        if (!l.alive()) continue;
        const cv::Point2d d = l.position_m - p_m;
        if (d.x * d.x + d.y * d.y <= r2) out.push_back(k);
      }
    }
  return out;
}

void MosaicBuilder::add_landmark(const cv::Point2d& p_m, double orientation_rad,
                                 const cv::Mat& descriptor, int64_t frame) {
  Landmark l;
  l.id = next_id_++;
  l.position_m = p_m;
  l.orientation_rad = wrap_angle_rad(orientation_rad);
  l.descriptor = descriptor.clone();
  l.observations = 1;
  l.last_seen_frame = frame;
  landmarks_.push_back(std::move(l));
  insert_in_grid(landmarks_.size() - 1);
}

void MosaicBuilder::prune(int64_t frame) {
  for (auto& [key, slots] : grid_) {
    slots.erase(std::remove_if(slots.begin(), slots.end(),
                               [&](size_t k) {
                                 Landmark& l = landmarks_[k];
                                 const bool stale =
                                     l.alive() && l.observations < options_.min_observations &&
                                     frame - l.last_seen_frame > options_.candidate_timeout_frames;
                                 if (stale) l.observations = 0;
                                 return !l.alive();
                               }),
                slots.end());
  }
}

MosaicFrameResult MosaicBuilder::add_frame(const CeilingObservation& obs) {
  if (obs.descriptors.rows != static_cast<int>(obs.size()) ||
      obs.orientation_base_rad.size() != obs.size() || obs.p_canon_px.size() != obs.size() ||
      obs.orientation_canon_rad.size() != obs.size())
    throw std::invalid_argument("MosaicBuilder::add_frame: observation fields of different sizes");
  if (!obs.descriptors.empty() &&
      (obs.descriptors.type() != CV_8U || obs.descriptors.cols != kMosaicDescriptorBytes))
    throw std::invalid_argument("MosaicBuilder::add_frame: descriptors must be 32-byte ORB rows");
  const int64_t frame = static_cast<int64_t>(frames_.size());
  MosaicFrameResult result;
  const size_t n = obs.size();
  auto sighting = [&](int64_t id, size_t i) {
    result.sightings.push_back({id, cv::Point2d(obs.p_canon_px[i]), obs.orientation_canon_rad[i]});
  };

  if (frame == 0) {
    // The first frame fixes the mosaic frame: its landmarks are placed directly.
    result.localised = true;
    for (size_t i = 0; i < n; ++i) {
      add_landmark(obs.p_base_m[i], obs.orientation_base_rad[i],
                   obs.descriptors.row(static_cast<int>(i)), frame);
      sighting(landmarks_.back().id, i);
    }
    result.added = static_cast<int>(n);
    frames_.push_back(result);
    return result;
  }

  // Guided matching from the last good pose; each mosaic landmark keeps its closest observation.
  std::vector<int> match_of_obs(n, -1);
  std::unordered_map<size_t, std::pair<size_t, int>> best_obs_of_landmark;  // slot -> (obs, dist)
  for (size_t i = 0; i < n; ++i) {
    const cv::Point2d q = last_pose_.apply(obs.p_base_m[i]);
    const uchar* d_i = obs.descriptors.ptr<uchar>(static_cast<int>(i));
    int best = std::numeric_limits<int>::max();
    size_t best_k = 0;
    for (size_t k : near(q, options_.search_radius_m)) {
      const int dist =
          cv::hal::normHamming(d_i, landmarks_[k].descriptor.ptr<uchar>(), kMosaicDescriptorBytes);
      if (dist < best) {
        best = dist;
        best_k = k;
      }
    }
    if (best > options_.max_hamming) continue;
    auto it = best_obs_of_landmark.find(best_k);
    if (it == best_obs_of_landmark.end() || best < it->second.second)
      best_obs_of_landmark[best_k] = {i, best};
  }
  std::vector<size_t> pair_obs, pair_slot;
  std::vector<cv::Point2d> src, dst;
  for (const auto& [k, od] : best_obs_of_landmark) {
    pair_obs.push_back(od.first);
    pair_slot.push_back(k);
    src.push_back(obs.p_base_m[od.first]);
    dst.push_back(landmarks_[k].position_m);
    match_of_obs[od.first] = static_cast<int>(pair_obs.size()) - 1;
  }
  result.matches = static_cast<int>(src.size());
  const RigidFit fit = ransac_rigid(src, dst, options_.ransac);
  if (!fit.found) {
    frames_.push_back(result);
    prune(frame);
    return result;
  }
  result.localised = true;
  result.T_mosaic_base = fit.T_dst_src;
  result.inliers = fit.inliers;
  result.rms_m = fit.rms_m;
  last_pose_ = fit.T_dst_src;

  // Inlier sightings: one more consistent observation of an existing landmark (its pose stays).
  for (size_t p = 0; p < pair_obs.size(); ++p) {
    if (!fit.inlier[p]) continue;
    const size_t i = pair_obs[p];
    Landmark& l = landmarks_[pair_slot[p]];
    ++l.observations;
    l.last_seen_frame = frame;
    sighting(l.id, i);
  }
  // Unmatched observations become candidates, chained through this frame's pose; those matched
  // but rejected by RANSAC do not (their match may be wrong, the point may be off the plane).
  const bool create = std::hypot(last_pose_.x_m - creation_pose_.x_m,
                                 last_pose_.y_m - creation_pose_.y_m) >= options_.landmark_step_m ||
                      std::abs(wrap_angle_rad(last_pose_.theta_rad - creation_pose_.theta_rad)) >=
                          options_.landmark_step_rad;
  if (create) creation_pose_ = last_pose_;
  for (size_t i = 0; i < n && create; ++i) {
    if (match_of_obs[i] >= 0) continue;
    const cv::Point2d p_m = last_pose_.apply(obs.p_base_m[i]);
    if (options_.min_separation_m > 0.0 && !near(p_m, options_.min_separation_m).empty()) continue;
    add_landmark(p_m, last_pose_.theta_rad + obs.orientation_base_rad[i],
                 obs.descriptors.row(static_cast<int>(i)), frame);
    sighting(landmarks_.back().id, i);
    ++result.added;
  }
  frames_.push_back(result);
  prune(frame);
  return result;
}

Mosaic MosaicBuilder::mosaic() const {
  Mosaic m;
  m.px_per_m = options_.px_per_m;
  for (const Landmark& l : landmarks_) {
    if (l.observations < options_.min_observations) continue;
    MosaicLandmark out;
    out.id = l.id;
    out.position_m = l.position_m;
    out.orientation_rad = l.orientation_rad;
    out.descriptor = l.descriptor.clone();
    out.observations = l.observations;
    m.landmarks.push_back(std::move(out));
  }
  return m;
}

std::vector<std::vector<LandmarkSighting>> MosaicBuilder::kept_sightings() const {
  std::unordered_set<int64_t> kept;
  for (const Landmark& l : landmarks_)
    if (l.observations >= options_.min_observations) kept.insert(l.id);
  std::vector<std::vector<LandmarkSighting>> out;
  out.reserve(frames_.size());
  for (const MosaicFrameResult& f : frames_) {
    std::vector<LandmarkSighting> s;
    for (const LandmarkSighting& x : f.sightings)
      if (kept.count(x.id)) s.push_back(x);
    out.push_back(std::move(s));
  }
  return out;
}

size_t MosaicBuilder::candidates() const {
  size_t n = 0;
  for (const Landmark& l : landmarks_)
    if (l.alive() && l.observations < options_.min_observations) ++n;
  return n;
}

}  // namespace pepper::core::ceiling
