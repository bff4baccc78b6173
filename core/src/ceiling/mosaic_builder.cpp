// Building the ceiling mosaic (see mosaic_builder.hpp).
#include "core/ceiling/mosaic_builder.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/core/hal/hal.hpp>
#include <stdexcept>
#include <string>
#include <unordered_set>

namespace pepper::core::ceiling {

namespace {

// Grid cells as large as the search radius: a query looks at the 3 x 3 cells around its point.
int64_t pack(int64_t cx, int64_t cy) { return (cx << 32) ^ (cy & 0xffffffffLL); }

int64_t cell_of(const cv::Point2d& p_m, double cell_m) {
  return pack(static_cast<int64_t>(std::floor(p_m.x / cell_m)),
              static_cast<int64_t>(std::floor(p_m.y / cell_m)));
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// SE(2) interpolation from the identity (alpha = 0) to C (alpha = 1) along the one-parameter
// subgroup through C: C^alpha = exp(alpha log C), a screw motion about C's fixed point. With
// V(theta) = [[s, -c], [c, s]] (s = sin(theta)/theta, c = (1 - cos(theta))/theta), the translation
// of exp(theta, v) is V(theta) v.
PlanarPose se2_power(const PlanarPose& C, double alpha) {
  auto V = [](double theta_rad, double* s, double* c) {
    if (std::abs(theta_rad) < 1e-9) {
      *s = 1.0;
      *c = 0.5 * theta_rad;
    } else {
      *s = std::sin(theta_rad) / theta_rad;
      *c = (1.0 - std::cos(theta_rad)) / theta_rad;
    }
  };
  const double theta = wrap_angle_rad(C.theta_rad);
  double s = 1.0, c = 0.0;
  V(theta, &s, &c);
  const double det = s * s + c * c;  // > 0 for |theta| <= pi
  const double vx = (s * C.x_m + c * C.y_m) / det, vy = (-c * C.x_m + s * C.y_m) / det;
  V(alpha * theta, &s, &c);
  return {alpha * (s * vx - c * vy), alpha * (c * vx + s * vy), alpha * theta};
}

}  // namespace

void LoopClosureOptions::check() const {
  if (!(std::isfinite(min_gap_m) && min_gap_m > 0.0))
    throw std::invalid_argument("MosaicBuilder: loop.min_gap_m must be finite and > 0");
  if (!(std::isfinite(search_radius_m) && search_radius_m > 0.0))
    throw std::invalid_argument("MosaicBuilder: loop.search_radius_m must be finite and > 0");
  if (min_inliers < 3) throw std::invalid_argument("MosaicBuilder: loop.min_inliers must be >= 3");
  if (!(std::isfinite(min_error_m) && min_error_m >= 0.0))
    throw std::invalid_argument("MosaicBuilder: loop.min_error_m must be finite and >= 0");
  const std::pair<const char*, double> bounds[] = {
      {"max_correction_m", max_correction_m}, {"max_correction_per_m", max_correction_per_m},
      {"max_correction_rad", max_correction_rad},
      {"max_correction_per_rad", max_correction_per_rad}};
  for (const auto& [name, value] : bounds) {
    if (!(std::isfinite(value) && value >= 0.0))
      throw std::invalid_argument(std::string("MosaicBuilder: loop.") + name +
                                  " must be finite and >= 0");
  }
}

void RelocalisationOptions::check() const {
  if (every_frames < 1)
    throw std::invalid_argument("MosaicBuilder: relocalisation.every_frames must be >= 1");
  try {
    localiser.check();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("MosaicBuilder: relocalisation.localiser: ") +
                                e.what());
  }
}

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
  loop.check();
  relocalisation.check();
}

MosaicBuilder::MosaicBuilder(MosaicBuilderOptions options) : options_(std::move(options)) {
  options_.check();
}

int64_t MosaicBuilder::cell_key(const cv::Point2d& p_m) const {
  return cell_of(p_m, options_.search_radius_m);
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
  l.created_travelled_m = travelled_m_;
  l.created_turned_rad = turned_rad_;
  l.last_seen_travelled_m = travelled_m_;
  landmarks_.push_back(std::move(l));
  insert_in_grid(landmarks_.size() - 1);
}

void MosaicBuilder::rebuild_grid() {
  grid_.clear();
  for (size_t k = 0; k < landmarks_.size(); ++k)
    if (landmarks_[k].alive()) insert_in_grid(k);
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

MosaicFrameResult MosaicBuilder::add_frame(const CeilingObservation& obs,
                                           const std::optional<OdometryPose>& odom) {
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
    odom_at_good_ = odom;
    return result;
  }

  // The odometry's prediction of this frame's pose: the last fitted frame's pose moved by the
  // odometry since that frame.
  std::optional<PlanarPose> predicted;
  if (options_.odometry_prior && odom && odom_at_good_) {
    predicted = last_pose_ * odometry_motion(*odom_at_good_, *odom);
  }

  // With loop closure, the landmarks not seen for loop.min_gap_m of travel ("old") are matched
  // by close_loop only, which decides whether they agree with the recent chain.
  const bool loop = options_.loop.enabled;
  auto fit_pairs = [&](const std::vector<Pair>& ps) {
    std::vector<cv::Point2d> src, dst;
    for (const Pair& p : ps) {
      src.push_back(obs.p_base_m[p.obs]);
      dst.push_back(landmarks_[p.slot].position_m);
    }
    return ransac_rigid(src, dst, options_.ransac);
  };
  std::vector<Pair> pairs;
  RigidFit fit;
  auto match_from = [&](const PlanarPose& prior) {
    pairs = guided_matches(obs, prior, loop);
    fit = fit_pairs(pairs);
    if (loop && !fit.found) {  // no recent chain to compare with: match as without the feature
      pairs = guided_matches(obs, prior, false);
      fit = fit_pairs(pairs);
    }
  };
  match_from(predicted.value_or(last_pose_));
  if (!fit.found && !predicted) {
    // Lost: a search without a prior may give the frame a prior the guided matching can use.
    // (With odometry the guided matching already searched where the robot is; a search
    // elsewhere could only find a place the odometry contradicts.)
    if (const std::optional<PlanarPose> T_fix = relocalise(obs, false)) {
      match_from(*T_fix);
      result.relocalised = fit.found;
    }
  } else if (fit.found && lost_frames_ > 0 && !predicted) {
    // Posed again by the guided matching after a loss: from a last good pose that may be far
    // behind, a repeated ceiling (tiles) can lock it onto the wrong place. Checked once against
    // a search without a prior: where the two disagree, the prior whose fit explains more of the
    // view wins.
    if (const std::optional<PlanarPose> T_fix = relocalise(obs, true)) {
      double apart_m = 0.0;  // how far apart the two poses put the frame's landmarks
      for (const cv::Point2d& p : obs.p_base_m)
        apart_m = std::max(apart_m, cv::norm(fit.T_dst_src.apply(p) - T_fix->apply(p)));
      if (apart_m > options_.ransac.inlier_threshold_m) {
        std::vector<Pair> guided_pairs = std::move(pairs);
        RigidFit guided_fit = std::move(fit);
        match_from(*T_fix);
        result.relocalised = fit.found && fit.inliers > guided_fit.inliers;
        if (!result.relocalised) {
          pairs = std::move(guided_pairs);
          fit = std::move(guided_fit);
        }
      }
    }
  }
  std::vector<uint8_t> claimed(n, 0);  // matched to an old landmark: not a new landmark
  double step_m = 0.0;  // from the last good pose (after a loss: the straight line across it)
  if (fit.found) {
    step_m = std::hypot(fit.T_dst_src.x_m - last_pose_.x_m, fit.T_dst_src.y_m - last_pose_.y_m);
    const double travelled_m = travelled_m_ + step_m;
    const LoopCheck check = loop ? close_loop(obs, fit.T_dst_src, frame, travelled_m) : LoopCheck{};
    if (check.verdict == LoopVerdict::kCorrected) {
      // The mosaic moved under the frame: match it again from its corrected pose, old included.
      result.closed_loop = true;
      pairs = guided_matches(obs, last_pose_, false);
      fit = fit_pairs(pairs);
    } else if (check.verdict == LoopVerdict::kAgree) {
      // The old landmarks agree with the chain: they join the frame's fit.
      std::vector<uint8_t> used(n, 0);
      for (const Pair& p : pairs) used[p.obs] = 1;
      std::vector<Pair> all = pairs;
      for (size_t j = 0; j < check.old_pairs.size(); ++j)
        if (check.inlier[j] && !used[check.old_pairs[j].obs]) all.push_back(check.old_pairs[j]);
      RigidFit all_fit = fit_pairs(all);
      if (all_fit.found) {
        pairs = std::move(all);
        fit = std::move(all_fit);
      }
    }
    for (const Pair& p : check.old_pairs) claimed[p.obs] = 1;
    travelled_m_ = travelled_m;
    turned_rad_ += std::abs(wrap_angle_rad(fit.T_dst_src.theta_rad - last_pose_.theta_rad));
  }
  result.travelled_m = travelled_m_;
  std::vector<int> match_of_obs(n, -1);
  for (size_t p = 0; p < pairs.size(); ++p) match_of_obs[pairs[p].obs] = static_cast<int>(p);
  result.matches = static_cast<int>(pairs.size());
  if (!fit.found && predicted) {
    // No fit, but the odometry knows where the robot is: the view is ceiling the mosaic does not
    // have yet (a turn into a new corridor whose start a wall hid), too little of it, or none
    // (the whole view a wall). The frame is posed by the odometry and its unmatched landmarks
    // become candidates there, so that the next frames chain on them; the prior stays the last
    // fitted pose moved by the odometry.
    result.localised = true;
    result.odometry_posed = true;
    result.T_mosaic_base = *predicted;
    result.travelled_m =
        travelled_m_ + std::hypot(predicted->x_m - last_pose_.x_m, predicted->y_m - last_pose_.y_m);
    add_new_landmarks(obs, *predicted, match_of_obs, std::vector<uint8_t>(n, 0), frame, result);
    frames_.push_back(result);
    prune(frame);
    return result;
  }
  if (!fit.found) {
    ++lost_frames_;
    frames_.push_back(result);
    prune(frame);
    return result;
  }
  result.localised = true;
  result.T_mosaic_base = fit.T_dst_src;
  result.inliers = fit.inliers;
  result.rms_m = fit.rms_m;
  if (result.relocalised) {
    Relocalisation r;
    r.frame = frame;
    r.last_good_frame = last_good_frame_;
    r.attempts = loss_attempts_;
    r.inliers = fit.inliers;
    r.gap_m = step_m;
    relocalisations_.push_back(r);
  }
  last_pose_ = fit.T_dst_src;
  last_good_frame_ = frame;
  odom_at_good_ = odom;
  lost_frames_ = 0;
  loss_attempts_ = 0;
  lost_localiser_.reset();

  // Inlier sightings: one more consistent observation of an existing landmark (its pose stays).
  for (size_t p = 0; p < pairs.size(); ++p) {
    if (!fit.inlier[p]) continue;
    const size_t i = pairs[p].obs;
    Landmark& l = landmarks_[pairs[p].slot];
    ++l.observations;
    l.last_seen_frame = frame;
    l.last_seen_travelled_m = travelled_m_;
    sighting(l.id, i);
  }
  add_new_landmarks(obs, last_pose_, match_of_obs, claimed, frame, result);
  frames_.push_back(result);
  prune(frame);
  return result;
}

void MosaicBuilder::add_new_landmarks(const CeilingObservation& obs, const PlanarPose& T,
                                      const std::vector<int>& match_of_obs,
                                      const std::vector<uint8_t>& claimed, int64_t frame,
                                      MosaicFrameResult& result) {
  // Unmatched observations become candidates, chained through this frame's pose; those matched
  // but rejected by RANSAC do not (their match may be wrong, the point may be off the plane).
  const bool create =
      std::hypot(T.x_m - creation_pose_.x_m, T.y_m - creation_pose_.y_m) >=
          options_.landmark_step_m ||
      std::abs(wrap_angle_rad(T.theta_rad - creation_pose_.theta_rad)) >=
          options_.landmark_step_rad;
  if (!create) return;
  creation_pose_ = T;
  for (size_t i = 0; i < obs.size(); ++i) {
    if (match_of_obs[i] >= 0 || claimed[i]) continue;
    const cv::Point2d p_m = T.apply(obs.p_base_m[i]);
    if (options_.min_separation_m > 0.0 && !near(p_m, options_.min_separation_m).empty()) continue;
    add_landmark(p_m, T.theta_rad + obs.orientation_base_rad[i],
                 obs.descriptors.row(static_cast<int>(i)), frame);
    result.sightings.push_back(
        {landmarks_.back().id, cv::Point2d(obs.p_canon_px[i]), obs.orientation_canon_rad[i]});
    ++result.added;
  }
}

// A search without a prior after a loss (see the header's comment): on a lost frame, due on the
// first one and then every relocalisation.every_frames lost frames; `always` for the check of
// the first frame posed again.
std::optional<PlanarPose> MosaicBuilder::relocalise(const CeilingObservation& obs, bool always) {
  const RelocalisationOptions& ro = options_.relocalisation;
  if (!ro.enabled || (!always && lost_frames_ % ro.every_frames != 0)) return std::nullopt;
  if (!lost_localiser_) {
    Mosaic kept = mosaic();
    if (kept.landmarks.empty()) return std::nullopt;
    lost_localiser_.emplace(std::move(kept), ro.localiser);
  }
  ++loss_attempts_;
  ++relocalisation_attempts_;
  const MosaicFix fix = lost_localiser_->localise(obs);
  if (!fix.found) return std::nullopt;
  return fix.T_mosaic_base;
}

// Guided matching from `prior`; each mosaic landmark keeps its closest observation.
std::vector<MosaicBuilder::Pair> MosaicBuilder::guided_matches(const CeilingObservation& obs,
                                                               const PlanarPose& prior,
                                                               bool skip_old) const {
  const size_t n = obs.size();
  std::unordered_map<size_t, std::pair<size_t, int>> best_obs_of_landmark;  // slot -> (obs, dist)
  for (size_t i = 0; i < n; ++i) {
    const cv::Point2d q = prior.apply(obs.p_base_m[i]);
    const uchar* d_i = obs.descriptors.ptr<uchar>(static_cast<int>(i));
    int best = std::numeric_limits<int>::max();
    size_t best_k = 0;
    for (size_t k : near(q, options_.search_radius_m)) {
      if (skip_old && old_landmark(landmarks_[k])) continue;
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
  std::vector<Pair> pairs;
  for (const auto& [k, od] : best_obs_of_landmark) pairs.push_back({od.first, k});
  return pairs;
}

// Old: kept, and not seen as an inlier for loop.min_gap_m of travel up to the last frame.
bool MosaicBuilder::old_landmark(const Landmark& l) const {
  return l.observations >= options_.min_observations &&
         travelled_m_ - l.last_seen_travelled_m >= options_.loop.min_gap_m;
}

MosaicBuilder::LoopCheck MosaicBuilder::close_loop(const CeilingObservation& obs,
                                                   const PlanarPose& T_mosaic_base, int64_t frame,
                                                   double travelled_m) {
  LoopCheck check;
  const LoopClosureOptions& lo = options_.loop;
  const size_t n = obs.size();
  // 1. The old kept landmarks around the view, in a grid of search_radius_m cells (cheap when
  // there are none: the cells the frame's landmarks fall in, grown by the search radius).
  std::vector<cv::Point2d> q(n);
  std::unordered_set<int64_t> cells;
  for (size_t i = 0; i < n; ++i) {
    q[i] = T_mosaic_base.apply(obs.p_base_m[i]);
    cells.insert(cell_key(q[i]));
  }
  const int64_t reach =
      static_cast<int64_t>(std::ceil(lo.search_radius_m / options_.search_radius_m));
  std::unordered_set<int64_t> grown;
  for (int64_t c : cells) {
    const int64_t cx = c >> 32, cy = static_cast<int32_t>(c & 0xffffffffLL);
    for (int64_t dx = -reach; dx <= reach; ++dx)
      for (int64_t dy = -reach; dy <= reach; ++dy) grown.insert(pack(cx + dx, cy + dy));
  }
  std::unordered_map<int64_t, std::vector<size_t>> old_grid;  // search_radius_m cells
  size_t n_old = 0;
  for (int64_t c : grown) {
    const auto it = grid_.find(c);
    if (it == grid_.end()) continue;
    for (size_t k : it->second) {
      if (!landmarks_[k].alive() || !old_landmark(landmarks_[k])) continue;
      old_grid[cell_of(landmarks_[k].position_m, lo.search_radius_m)].push_back(k);
      ++n_old;
    }
  }
  if (n_old == 0) return check;

  // 2. Each frame landmark's nearest old descriptor within search_radius_m of where the chain
  // puts it; each old landmark keeps its closest frame landmark.
  std::unordered_map<size_t, std::pair<size_t, int>> best_obs_of_old;  // slot -> (obs, dist)
  const double r2 = lo.search_radius_m * lo.search_radius_m;
  for (size_t i = 0; i < n; ++i) {
    const uchar* d_i = obs.descriptors.ptr<uchar>(static_cast<int>(i));
    const int64_t cx = static_cast<int64_t>(std::floor(q[i].x / lo.search_radius_m));
    const int64_t cy = static_cast<int64_t>(std::floor(q[i].y / lo.search_radius_m));
    int best = std::numeric_limits<int>::max();
    size_t best_k = 0;
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy) {
        const auto it = old_grid.find(pack(cx + dx, cy + dy));
        if (it == old_grid.end()) continue;
        for (size_t k : it->second) {
          const cv::Point2d d = landmarks_[k].position_m - q[i];
          if (d.x * d.x + d.y * d.y > r2) continue;
          const int dist = cv::hal::normHamming(d_i, landmarks_[k].descriptor.ptr<uchar>(),
                                                kMosaicDescriptorBytes);
          if (dist < best) {
            best = dist;
            best_k = k;
          }
        }
      }
    if (best > options_.max_hamming) continue;
    auto it = best_obs_of_old.find(best_k);
    if (it == best_obs_of_old.end() || best < it->second.second)
      best_obs_of_old[best_k] = {i, best};
  }
  std::vector<cv::Point2d> old_src, old_dst;
  for (const auto& [k, od] : best_obs_of_old) {
    check.old_pairs.push_back({od.first, k});
    old_src.push_back(obs.p_base_m[od.first]);
    old_dst.push_back(landmarks_[k].position_m);
  }
  if (check.old_pairs.size() < static_cast<size_t>(lo.min_inliers)) return check;
  RigidRansacOptions old_ransac = options_.ransac;
  old_ransac.min_inliers = lo.min_inliers;
  const RigidFit old_fit = ransac_rigid(old_src, old_dst, old_ransac);
  if (!old_fit.found) return check;

  // 3. Against the frame's pose on the recent chain (T_mosaic_base: the old were left out).
  std::vector<double> misplaced, created, created_turned;
  for (size_t j = 0; j < old_src.size(); ++j) {
    if (!old_fit.inlier[j]) continue;
    misplaced.push_back(cv::norm(T_mosaic_base.apply(old_src[j]) - old_dst[j]));
    created.push_back(landmarks_[check.old_pairs[j].slot].created_travelled_m);
    created_turned.push_back(landmarks_[check.old_pairs[j].slot].created_turned_rad);
  }
  const double error_m = median(misplaced);
  if (error_m <= lo.min_error_m) {
    check.verdict = LoopVerdict::kAgree;
    check.inlier = old_fit.inlier;
    return check;
  }

  // 4. The correction, in full at this frame, interpolated back to the loop's start.
  LoopClosure closure;
  closure.frame = frame;
  closure.from_travelled_m = median(created);
  closure.to_travelled_m = travelled_m;
  closure.T_corrected_chained = old_fit.T_dst_src * T_mosaic_base.inverse();
  closure.old_inliers = old_fit.inliers;
  closure.error_before_m = error_m;
  const double span_m = std::max(travelled_m - closure.from_travelled_m, 1e-9);
  // A chain drifts by a small fraction of what it travelled and turned since the loop's start: a
  // correction beyond that is a false closure (a repeated or symmetric ceiling: plain tiles look
  // the same a tile away and turned by a right angle), not drift. Refused: the frame stays on the
  // recent chain and the old landmarks are left out of its fit.
  const double turned_now_rad =
      turned_rad_ + std::abs(wrap_angle_rad(T_mosaic_base.theta_rad - last_pose_.theta_rad));
  const double turn_span_rad = std::max(turned_now_rad - median(created_turned), 0.0);
  const double moved_m = std::hypot(old_fit.T_dst_src.x_m - T_mosaic_base.x_m,
                                    old_fit.T_dst_src.y_m - T_mosaic_base.y_m);
  if (moved_m > lo.max_correction_m + lo.max_correction_per_m * span_m ||
      std::abs(wrap_angle_rad(closure.T_corrected_chained.theta_rad)) >
          lo.max_correction_rad + lo.max_correction_per_rad * turn_span_rad) {
    ++implausible_closures_;
    return check;
  }
  auto correction = [&](double s_m) {
    return se2_power(closure.T_corrected_chained,
                     std::clamp((s_m - closure.from_travelled_m) / span_m, 0.0, 1.0));
  };
  for (Landmark& l : landmarks_) {
    if (!l.alive() || l.created_travelled_m <= closure.from_travelled_m) continue;
    const PlanarPose C = correction(l.created_travelled_m);
    l.position_m = C.apply(l.position_m);
    l.orientation_rad = wrap_angle_rad(l.orientation_rad + C.theta_rad);
    ++closure.landmarks_moved;
  }
  for (MosaicFrameResult& f : frames_) {
    if (!f.localised || f.travelled_m <= closure.from_travelled_m) continue;
    f.T_mosaic_base = correction(f.travelled_m) * f.T_mosaic_base;
    ++closure.frames_moved;
  }
  creation_pose_ = closure.T_corrected_chained * creation_pose_;
  last_pose_ = closure.T_corrected_chained * T_mosaic_base;
  rebuild_grid();
  closures_.push_back(closure);
  check.verdict = LoopVerdict::kCorrected;
  return check;
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

size_t MosaicBuilder::kept_landmarks() const {
  size_t n = 0;
  for (const Landmark& l : landmarks_)
    if (l.observations >= options_.min_observations) ++n;
  return n;
}

size_t MosaicBuilder::candidates() const {
  size_t n = 0;
  for (const Landmark& l : landmarks_)
    if (l.alive() && l.observations < options_.min_observations) ++n;
  return n;
}

}  // namespace pepper::core::ceiling
