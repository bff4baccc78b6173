#include "core/mapping/teacher.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace pepper::core::mapping {

namespace {
// FrameMatcher ids: key image = 0, previous frame = 1 (both refer to stored images).
constexpr int64_t kKeyId = 0;
constexpr int64_t kPrevId = 1;
}  // namespace

std::vector<std::string> TeachOptions::validate() const {
  std::vector<std::string> errors = selector.validate();
  for (auto& e : extractor.validate()) errors.push_back("features." + e);
  for (auto& e : matcher.validate()) errors.push_back("matching." + e);
  return errors;
}

Teacher::Teacher(const CameraIntrinsics& camera, const TeachOptions& options)
    : camera_(camera),
      options_(options),
      extractor_(camera, options.extractor),
      selector_(options.selector) {
  if (const auto errors = options_.validate(); !errors.empty()) {
    throw std::invalid_argument("Teacher: " + errors.front());
  }
}

void Teacher::store_key(const Stored& s) {
  memory::KeyImage k;
  k.source_frame_index = s.source_frame_index;
  k.t_ns = s.t_ns;
  k.travelled_m = s.travelled_m;
  k.odom = s.odom;
  k.features = s.features;
  k.features.klt_pyramid.clear();  // derived; the map does not keep it
  keys_.push_back(std::move(k));
}

TeachStep Teacher::add_frame(const Frame& frame, double travelled_m) {
  if (finished_) throw std::invalid_argument("Teacher::add_frame after finish()");
  // Known on every frame or on none, never decreasing (the map's rule for its key images).
  const bool known = !std::isnan(travelled_m);
  if (frames_ > 0 && known != !std::isnan(prev_->travelled_m)) {
    throw std::invalid_argument(
        "Teacher::add_frame: travelled_m must be given with every frame of a tour or with none");
  }
  if (known && !(std::isfinite(travelled_m) && travelled_m >= 0.0 &&
                 (frames_ == 0 || travelled_m >= prev_->travelled_m))) {
    throw std::invalid_argument("Teacher::add_frame: travelled_m " + std::to_string(travelled_m) +
                                " must be finite, >= 0 and never decrease");
  }
  if (frame.odom && !(std::isfinite(frame.odom->x_m) && std::isfinite(frame.odom->y_m) &&
                      std::isfinite(frame.odom->yaw_rad))) {
    throw std::invalid_argument("Teacher::add_frame: frame " + std::to_string(frame.index) +
                                " has non-finite odometry");
  }
  if (frame.gray.empty() || frame.gray.type() != CV_8UC1) {
    throw std::invalid_argument("Teacher::add_frame: frame " + std::to_string(frame.index) +
                                " is not a non-empty CV_8UC1 image");
  }
  if (frames_ > 0 && frame.gray.size() != size_) {
    throw std::invalid_argument("Teacher::add_frame: image size changed during the tour");
  }
  size_ = frame.gray.size();
  Stored cur;
  cur.features = extractor_.extract(frame.gray, features::kPartsAll);
  cur.source_frame_index = frame.index >= 0 ? frame.index : frames_;
  cur.t_ns = frame.t_ns;
  cur.travelled_m = travelled_m;
  cur.odom = frame.odom;
  cur.frame_number = frames_;

  TeachStep step;
  step.frame_number = frames_;
  if (frames_ == 0) {
    key_ = cur;
    store_key(cur);
  } else {
    features::FrameMatcher fm(cur.features, options_.matcher);
    if (prev_->frame_number == key_->frame_number) {
      // Ic-1 is the key image: the three views degenerate to two; count the key's own lines
      // matched over (Ik, Ic) as the three-view set.
      step.n_lines_three_view = fm.two_view(kKeyId, key_->features).n_lines();
    } else {
      step.n_lines_three_view =
          fm.three_view(kKeyId, key_->features, kPrevId, prev_->features).n_lines();
    }
    step.n_points_two_view = fm.two_view(kKeyId, key_->features).n_points();
    step.count = step.n_lines_three_view + step.n_points_two_view;
    if (cur.odom && key_->odom) {
      step.heading_change_rad =
          std::abs(std::remainder(cur.odom->yaw_rad - key_->odom->yaw_rad, 2.0 * M_PI));
    }
    const auto k = selector_.on_frame(frames_, step.count, step.heading_change_rad);
    step.threshold = selector_.last_threshold();
    step.reference_count = selector_.last_reference();
    if (k) {
      step.new_key_frame = *k;
      step.new_key_rule = selector_.last_rule();
      key_ = (*k == frames_) ? cur : *prev_;
      store_key(*key_);
    }
  }
  prev_ = std::move(cur);
  prev_->features.klt_pyramid.clear();  // the previous frame is only tracked *into*
  ++frames_;
  step.key_image_count = key_image_count();
  return step;
}

const features::ImageFeatures& Teacher::last_frame_features() const {
  if (!prev_) throw std::logic_error("Teacher::last_frame_features: no frame (yet, or finished)");
  return prev_->features;
}

memory::VisualMemory Teacher::finish(const std::string& parameters_json) {
  if (finished_) throw std::invalid_argument("Teacher::finish called twice");
  if (frames_ < 2) {
    throw std::invalid_argument("Teacher::finish: a tour needs at least 2 frames, got " +
                                std::to_string(frames_));
  }
  finished_ = true;
  if (selector_.finish()) store_key(*prev_);
  memory::VisualMemory map;
  map.camera = camera_.scaled_to(size_.width, size_.height);
  map.key_images = std::move(keys_);
  map.parameters_json = parameters_json;
  keys_.clear();
  key_.reset();
  prev_.reset();
  return map;
}

memory::VisualMemory teach_offline(std::span<const Frame> frames, const CameraIntrinsics& camera,
                                   const TeachOptions& options, const std::string& parameters_json,
                                   std::vector<TeachStep>* steps) {
  Teacher teacher(camera, options);
  for (const Frame& f : frames) {
    TeachStep s = teacher.add_frame(f);
    if (steps) steps->push_back(s);
  }
  return teacher.finish(parameters_json);
}

}  // namespace pepper::core::mapping
