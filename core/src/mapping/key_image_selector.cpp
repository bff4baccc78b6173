#include "core/mapping/key_image_selector.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pepper::core::mapping {

std::vector<std::string> KeyImageSelectorOptions::validate() const {
  std::vector<std::string> errors;
  if (epsilon < 1) {
    errors.push_back("mapping.epsilon = " + std::to_string(epsilon) + " must be >= 1");
  }
  if (min_frame_gap < 1) {
    errors.push_back("mapping.min_frame_gap = " + std::to_string(min_frame_gap) + " must be >= 1");
  }
  if (!(relative >= 0.0 && relative < 1.0)) {
    errors.push_back("mapping.relative = " + std::to_string(relative) +
                     " must be in [0, 1) (0: absolute epsilon only)");
  }
  if (relative > 0.0 && relative < 1.0 && !(max_fraction > relative && max_fraction <= 1.0)) {
    errors.push_back("mapping.max_fraction = " + std::to_string(max_fraction) +
                     " must be in (relative, 1]");
  }
  if (!(max_heading_change_rad >= 0.0 && max_heading_change_rad <= M_PI)) {
    errors.push_back("mapping.max_heading_change_rad = " + std::to_string(max_heading_change_rad) +
                     " must be in [0, pi] (0: off)");
  }
  return errors;
}

const char* to_string(KeyImageRule rule) {
  switch (rule) {
    case KeyImageRule::kFirst:
      return "first";
    case KeyImageRule::kFeatures:
      return "features";
    case KeyImageRule::kHeading:
      return "heading";
    case KeyImageRule::kLast:
      return "last";
  }
  return "?";
}

KeyImageSelector::KeyImageSelector(const KeyImageSelectorOptions& options) : options_(options) {
  if (const auto errors = options_.validate(); !errors.empty()) {
    throw std::invalid_argument("KeyImageSelector: " + errors.front());
  }
  threshold_ = options_.epsilon;
}

std::optional<int64_t> KeyImageSelector::on_frame(int64_t c, int count,
                                                  std::optional<double> heading_change_rad) {
  if (finished_) throw std::invalid_argument("KeyImageSelector::on_frame after finish()");
  if (c != last_ + 1) {
    throw std::invalid_argument("KeyImageSelector::on_frame: frame " + std::to_string(c) +
                                " after " + std::to_string(last_));
  }
  last_ = c;
  if (options_.relative > 0.0 && c == key_ + 2) {
    reference_ = count;
    // At least 1: a reference of 0 (nothing shared) must still let the count fall below it.
    threshold_ = std::max(1.0, std::min(std::max<double>(options_.epsilon, options_.relative * count),
                                        options_.max_fraction * count));
  }
  last_threshold_ = threshold_;
  last_reference_ = reference_;
  const bool few_features = count < threshold_;
  const bool turned = options_.max_heading_change_rad > 0.0 && heading_change_rad &&
                      std::abs(*heading_change_rad) > options_.max_heading_change_rad;
  if (!few_features && !turned) return std::nullopt;
  const int64_t candidate = (c - 1 == key_) ? c : c - 1;
  if (candidate - key_ < options_.min_frame_gap) return std::nullopt;
  last_rule_ = few_features ? KeyImageRule::kFeatures : KeyImageRule::kHeading;
  key_ = candidate;
  keys_.push_back(key_);
  // A new key image: its reference is measured again two frames later (when key_ == c, the
  // scene changed within one frame; the same rule applies from c).
  reference_ = -1;
  threshold_ = options_.epsilon;
  return key_;
}

std::optional<int64_t> KeyImageSelector::finish() {
  if (finished_) return std::nullopt;
  finished_ = true;
  if (last_ == key_) return std::nullopt;
  key_ = last_;
  keys_.push_back(key_);
  last_rule_ = KeyImageRule::kLast;
  return key_;
}

}  // namespace pepper::core::mapping
