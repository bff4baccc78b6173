#include "session/teach_feedback.hpp"

#include <cmath>
#include <cstdio>

namespace pepper::app {

namespace {

constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;

std::string format(const char* fmt, auto... args) {
  char buf[512];
  std::snprintf(buf, sizeof buf, fmt, args...);
  return buf;
}

int slot(TeachWarningKind kind) { return static_cast<int>(kind); }

}  // namespace

std::vector<std::string> TeachFeedbackLimits::validate() const {
  std::vector<std::string> e;
  if (min_view_features < 1) e.push_back("min_view_features must be >= 1");
  if (min_verified_matches < 1) e.push_back("min_verified_matches must be >= 1");
  if (!(max_heading_change_rad >= 0)) e.push_back("max_heading_change_rad must be >= 0");
  if (min_frame_gap < 1) e.push_back("min_frame_gap must be >= 1");
  if (!(half_view_rad > 0 && half_view_rad < 1.6)) e.push_back("half_view_rad must be in (0, pi/2)");
  if (hold_frames < 1) e.push_back("hold_frames must be >= 1");
  if (!(clear_ratio >= 1)) e.push_back("clear_ratio must be >= 1");
  return e;
}

const char* to_string(TeachWarningKind kind) {
  switch (kind) {
    case TeachWarningKind::kFewFeatures: return "few_features";
    case TeachWarningKind::kTurningFast: return "turning_fast";
    case TeachWarningKind::kOverlapLost: return "overlap_lost";
  }
  return "?";
}

bool TeachFeedback::has(TeachWarningKind kind) const {
  for (const auto& w : warnings) {
    if (w.kind == kind) return true;
  }
  return false;
}

TeachFeedback teach_feedback(const TeachView& view, const TeachFeedbackLimits& limits,
                             const TeachFeedback& previous) {
  // What holds on this frame, with its text; empty text: the condition does not hold.
  std::string now[3];
  const int features = view.n_lines + view.n_points;
  // Hysteresis: once shown, few_features stays until the view is clearly richer than the bound,
  // so a count hovering around it does not blink.
  const double few_bound = previous.has(TeachWarningKind::kFewFeatures)
                               ? limits.clear_ratio * limits.min_view_features
                               : limits.min_view_features;
  if (features < few_bound) {
    now[slot(TeachWarningKind::kFewFeatures)] = format(
        "Few features in view: %d lines + points, a key image needs %d. A blank wall or a dark "
        "corner cannot be replayed: turn towards something textured, light it, or put up a "
        "poster here.",
        features, limits.min_view_features);
  }
  const bool gap_too_fast = view.turned_over_gap_rad &&
                            *view.turned_over_gap_rad > limits.max_heading_change_rad;
  const bool keys_too_far = view.heading_since_key_rad &&
                            *view.heading_since_key_rad > limits.half_view_rad;
  if (gap_too_fast) {
    now[slot(TeachWarningKind::kTurningFast)] = format(
        "Turning too fast: %.0f deg in %d frames, key images can follow at most %.0f deg in that "
        "time. Slow down and turn less sharply.",
        *view.turned_over_gap_rad * kDegPerRad, limits.min_frame_gap,
        limits.max_heading_change_rad * kDegPerRad);
  } else if (keys_too_far) {
    now[slot(TeachWarningKind::kTurningFast)] = format(
        "Turning faster than key images follow: %.0f deg since the last key image, more than half "
        "the camera's view (%.0f deg). Slow down and turn less sharply.",
        *view.heading_since_key_rad * kDegPerRad, limits.half_view_rad * kDegPerRad);
  }
  // Only when the view itself has features: otherwise few_features already says why.
  const bool key_was_rich = !view.key_features || *view.key_features >= limits.min_view_features;
  if (view.verified_with_key && *view.verified_with_key < limits.min_verified_matches &&
      features >= limits.min_view_features && key_was_rich) {
    now[slot(TeachWarningKind::kOverlapLost)] = format(
        "The view changed too fast: only %d features still match the last key image, the replay "
        "needs %d to follow from one key image to the next. Slow down and turn less sharply; "
        "back up to where this warning began.",
        *view.verified_with_key, limits.min_verified_matches);
  }

  TeachFeedback out;
  for (int k = 0; k < 3; ++k) {
    if (!now[k].empty()) {
      out.hold_left[k] = limits.hold_frames;
      out.held_text[k] = now[k];
    } else if (previous.hold_left[k] > 1) {
      out.hold_left[k] = previous.hold_left[k] - 1;
      out.held_text[k] = previous.held_text[k];
    }
    if (out.hold_left[k] > 0) {
      out.warnings.push_back({static_cast<TeachWarningKind>(k), out.held_text[k]});
    }
  }
  return out;
}

nlohmann::json to_json(const TeachFeedback& feedback) {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& w : feedback.warnings) {
    list.push_back({{"kind", to_string(w.kind)}, {"text", w.text}});
  }
  return {{"warnings", list}};
}

}  // namespace pepper::app
