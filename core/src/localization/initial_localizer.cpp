#include "core/localization/initial_localizer.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <numeric>
#include <opencv2/core.hpp>
#include <sstream>
#include <stdexcept>

namespace pepper::core::localization {

std::vector<std::string> InitialLocalizerOptions::validate() const {
  std::vector<std::string> errors = rule.validate();
  auto check = [&](bool ok, const char* name, double value, const char* range) {
    if (!ok) {
      std::ostringstream os;
      os << "localization.initial." << name << " = " << value << " must be " << range;
      errors.push_back(os.str());
    }
  };
  check(top_k >= 1, "top_k", top_k, ">= 1");
  check(vote_ratio > 0.0 && vote_ratio <= 1.0, "vote_ratio", vote_ratio, "in (0, 1]");
  check(vote_current_features >= 1, "vote_current_features", vote_current_features, ">= 1");
  check(vote_key_features >= 1, "vote_key_features", vote_key_features, ">= 1");
  check(vote_max_hamming >= 0 && vote_max_hamming <= 256, "vote_max_hamming", vote_max_hamming,
        "in [0, 256]");
  return errors;
}

namespace {

// Rows of the `max_rows` strongest keypoints (response descending, index ascending on ties),
// as contiguous 32-byte descriptors.
std::vector<std::array<uint64_t, 4>> strongest(const std::vector<cv::KeyPoint>& keypoints,
                                               const cv::Mat& descriptors, int max_rows) {
  std::vector<std::array<uint64_t, 4>> out;
  if (descriptors.empty() || descriptors.cols != 32 || descriptors.type() != CV_8U ||
      descriptors.rows != static_cast<int>(keypoints.size())) {
    return out;
  }
  std::vector<int> order(keypoints.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return keypoints[a].response > keypoints[b].response; });
  order.resize(std::min<size_t>(order.size(), static_cast<size_t>(max_rows)));
  out.resize(order.size());
  for (size_t i = 0; i < order.size(); ++i) {
    std::memcpy(out[i].data(), descriptors.ptr<uint8_t>(order[i]), 32);
  }
  return out;
}

inline int hamming256(const std::array<uint64_t, 4>& a, const std::array<uint64_t, 4>& b) {
  return std::popcount(a[0] ^ b[0]) + std::popcount(a[1] ^ b[1]) + std::popcount(a[2] ^ b[2]) +
         std::popcount(a[3] ^ b[3]);
}

// 2-NN with the ratio test; returns the number of good matches.
int vote(const std::vector<std::array<uint64_t, 4>>& query,
         const std::vector<std::array<uint64_t, 4>>& train, double ratio, int max_hamming) {
  int good = 0;
  for (const auto& q : query) {
    int best = 1 << 20, second = 1 << 20;
    for (const auto& t : train) {
      const int d = hamming256(q, t);
      if (d < second) {
        if (d < best) {
          second = best;
          best = d;
        } else {
          second = d;
        }
      }
    }
    if (best <= max_hamming && best < ratio * second) ++good;
  }
  return good;
}

}  // namespace

std::vector<int> prefilter_votes(const features::ImageFeatures& current,
                                 const memory::VisualMemory& map,
                                 const InitialLocalizerOptions& options) {
  std::vector<int> votes(map.key_images.size(), 0);
  const auto query =
      strongest(current.keypoints, current.keypoint_descriptors, options.vote_current_features);
  for (size_t k = 0; k < map.key_images.size(); ++k) {
    const features::ImageFeatures& f = map.key_images[k].features;
    votes[k] =
        vote(query, strongest(f.keypoints, f.keypoint_descriptors, options.vote_key_features),
             options.vote_ratio, options.vote_max_hamming);
  }
  return votes;
}

InitialLocalizationReport localize_in_map(features::FrameMatcher& matcher,
                                          const memory::VisualMemory& map,
                                          const InitialLocalizerOptions& options,
                                          std::span<const int> expected) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument("localize_in_map: " + errors.front());
  }
  const int n = static_cast<int>(map.key_images.size());
  if (n < 2) throw std::invalid_argument("localize_in_map: map has fewer than 2 key images");
  InitialLocalizationReport report;
  report.counts.assign(static_cast<size_t>(n), -1);
  auto verify = [&](int k) {
    if (k < 0 || k >= n || report.counts[k] >= 0) return;
    report.counts[k] = matcher.wide_baseline(k, map.key_images[k].features).total();
    ++report.verified;
  };
  // The expected key images first: where one of them decides (below), the appearance vote and
  // its top_k verifications cannot change the outcome, so they are not computed (the costliest
  // part of a localisation: the vote over the whole map and up to top_k two-view matches).
  for (const int k : expected) verify(k);
  // The expected key images are a prior (where the replay starts, or where odometry puts the
  // robot after a loss). Where one of them has enough verified matches on its own, the robot is
  // there: a look-alike elsewhere on the tour (the same poster or door further on) must not
  // win by a few more matches. The rule then runs on the expected images and their neighbours.
  // With the prior, half the evidence suffices (the expected images are where the robot was
  // put or where odometry says it is: a chance match must also fall on them to mislead).
  InitialLocalizationOptions prior_rule = options.rule;
  prior_rule.min_best_count = (options.rule.min_best_count + 1) / 2;
  int best_expected = -1;
  for (const int k : expected) {
    if (k >= 0 && k < n && report.counts[k] >= prior_rule.min_best_count &&
        (best_expected < 0 || report.counts[k] > report.counts[best_expected])) {
      best_expected = k;
    }
  }
  if (best_expected >= 0) {
    verify(best_expected - 1);
    verify(best_expected + 1);
    std::vector<int> near(static_cast<size_t>(n), -1);
    for (int k = best_expected - 1; k <= best_expected + 1; ++k) {
      if (k >= 0 && k < n) near[k] = report.counts[k];
    }
    report.result = localize_from_counts(near, prior_rule);
    report.from_prior = true;
    return report;
  }
  report.votes = prefilter_votes(matcher.current(), map, options);
  std::vector<int> order(static_cast<size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  // Highest vote first; ties: lower index (deterministic).
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return report.votes[a] > report.votes[b]; });
  for (int r = 0; r < std::min(options.top_k, n); ++r) {
    if (report.votes[order[r]] <= 0 && r > 0) break;  // nothing in common with the rest
    verify(order[r]);
  }
  const int best = static_cast<int>(std::max_element(report.counts.begin(), report.counts.end()) -
                                    report.counts.begin());
  verify(best - 1);
  verify(best + 1);
  report.result = localize_from_counts(report.counts, options.rule);
  return report;
}

}  // namespace pepper::core::localization
