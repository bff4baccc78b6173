// Relay images by the paper's two conditions (see relay_images.hpp).
#include "core/ceiling/relay_images.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "core/ceiling/planar_rigid.hpp"

namespace pepper::core::ceiling {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

void RelayOptions::check() const {
  if (min_shared_landmarks < 1)
    throw std::invalid_argument("select_relay_images: min_shared_landmarks must be >= 1");
  if (!(max_orientation_change_rad > 0.0 && max_orientation_change_rad < kPi))
    throw std::invalid_argument(
        "select_relay_images: max_orientation_change_rad must be in (0, pi)");
  if (!(linked_step_m >= 0.0) || !std::isfinite(linked_step_m))
    throw std::invalid_argument("select_relay_images: linked_step_m must be finite and >= 0");
  if (!(linked_step_rad >= 0.0) || !std::isfinite(linked_step_rad))
    throw std::invalid_argument("select_relay_images: linked_step_rad must be finite and >= 0");
}

RelayPairCheck check_relay_pair(const std::vector<LandmarkSighting>& a,
                                const std::vector<LandmarkSighting>& b,
                                const RelayOptions& options) {
  options.check();
  std::unordered_map<int64_t, double> orientation_in_a;
  for (const LandmarkSighting& s : a) orientation_in_a[s.id] = s.orientation_canon_rad;
  std::vector<double> changes;
  for (const LandmarkSighting& s : b) {
    const auto it = orientation_in_a.find(s.id);
    if (it != orientation_in_a.end())
      changes.push_back(std::abs(wrap_angle_rad(s.orientation_canon_rad - it->second)));
  }
  RelayPairCheck check;
  check.shared_landmarks = static_cast<int>(changes.size());
  if (changes.empty()) return check;
  const auto mid = changes.begin() + static_cast<std::ptrdiff_t>(changes.size() / 2);
  std::nth_element(changes.begin(), mid, changes.end());
  check.orientation_change_rad = *mid;
  check.ok = check.shared_landmarks >= options.min_shared_landmarks &&
             check.orientation_change_rad < options.max_orientation_change_rad;
  return check;
}

RelaySelection select_relay_images(const std::vector<std::vector<LandmarkSighting>>& frames,
                                   const RelayOptions& options) {
  options.check();
  RelaySelection out;
  if (frames.empty()) return out;
  out.relay_frames.push_back(0);
  size_t last = 0;
  // The latest frame after `last` that satisfies the conditions with it; kNone: none yet.
  constexpr size_t kNone = static_cast<size_t>(-1);
  size_t reachable = kNone;
  size_t i = 1;
  while (i < frames.size()) {
    if (check_relay_pair(frames[last], frames[i], options).ok) {
      reachable = i++;
      continue;
    }
    if (reachable != kNone) {
      // Frame i is too far from `last`: the latest reachable frame becomes the next relay image,
      // and frame i is checked again against it.
      last = reachable;
      out.relay_frames.push_back(last);
      reachable = kNone;
      continue;
    }
    // Not even the next frame satisfies the conditions: a break in the chain.
    out.breaks.push_back(out.relay_frames.size() - 1);
    last = i;
    out.relay_frames.push_back(last);
    ++i;
  }
  if (last != frames.size() - 1) out.relay_frames.push_back(frames.size() - 1);
  return out;
}

std::vector<size_t> thin_linked_relays(const std::vector<PlanarPose>& relay_poses,
                                       const std::vector<uint8_t>& linked, double min_step_m,
                                       double min_step_rad) {
  if (!relay_poses.empty() && linked.size() != relay_poses.size() - 1)
    throw std::invalid_argument("thin_linked_relays: " + std::to_string(linked.size()) +
                                " pair flags for " + std::to_string(relay_poses.size()) +
                                " relay images");
  if (!(min_step_m >= 0.0) || !(min_step_rad >= 0.0))
    throw std::invalid_argument("thin_linked_relays: the steps must be >= 0");
  std::vector<size_t> kept;
  for (size_t i = 0; i < relay_poses.size(); ++i) {
    // Inside a run: both the pair before and the pair after are linked.
    const bool inside = i > 0 && i + 1 < relay_poses.size() && linked[i - 1] && linked[i];
    if (inside) {
      const PlanarPose& a = relay_poses[kept.back()];
      const PlanarPose& b = relay_poses[i];
      const bool far = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m) >= min_step_m ||
                       std::abs(wrap_angle_rad(b.theta_rad - a.theta_rad)) >= min_step_rad;
      if (!far) continue;
    }
    kept.push_back(i);
  }
  return kept;
}

}  // namespace pepper::core::ceiling
