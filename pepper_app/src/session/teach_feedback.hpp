#pragma once
// Teach feedback (issue 25): while teaching, tell the operator at once when the tour being
// taught will be hard to replay, and what to do about it, instead of finding out from a weak map
// afterwards. Three warnings, each judged on one frame's figures against what the replay and the
// teach's own key-image rules need (docs/teach_ui.md "Teach feedback" says where each number
// comes from):
//  - few_features: the view has fewer detected lines + points than a key image needs (a blank
//    wall, a dark corner): a key image taken here would be weak (the saved map and `map show`
//    flag it with the same number).
//  - turning_fast: the base turns faster than key images can follow: over the last
//    `min_frame_gap` frames (the closest two key images may be) it turned more than the heading
//    rule allows between two key images, or the heading since the current key image is already
//    more than half the camera's field of view (neighbouring key images would share less than
//    half their view).
//  - overlap_lost: the view still has features, but fewer of them are verified against the
//    current key image than the replay needs to recognise a key image: the view changed faster
//    than the teach could take key images.
// A pure function over plain values (no session, no clock), so the rules are tested alone
// (tests/app/session/test_teach_feedback.cpp). To keep a warning from flickering on noisy
// counts it is held for `hold_frames` frames after its condition last held, and few_features
// clears only above `clear_ratio` times its threshold; the caller passes the previous result in.

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace pepper::app {

/// The bounds, taken from the configuration the teach and the replay run with (cmd_teach.cpp).
struct TeachFeedbackLimits {
  /// Lines + points a view needs: the weak-key-image bound (TeachSessionOptions::min_key_features).
  int min_view_features = 40;
  /// Verified matches with the current key image below which the replay could not recognise it
  /// (navigator.localization.min_best_count).
  int min_verified_matches = 15;
  /// The heading rule's bound between key images (key_images.max_heading_change_rad) and the
  /// closest two key images may be (key_images.min_frame_gap).
  double max_heading_change_rad = 0.35;
  int min_frame_gap = 3;
  /// Half the camera's horizontal field of view (atan(width / 2 / fx)).
  double half_view_rad = 0.49;
  int hold_frames = 8;       ///< a warning stays this many frames after its condition last held
  double clear_ratio = 1.25; ///< few_features clears at this x min_view_features
  std::vector<std::string> validate() const;
};

/// One frame of the teach, as the session sees it.
struct TeachView {
  int n_lines = 0;   ///< detected in this frame
  int n_points = 0;
  /// Lines (three views) + points (two views) verified against the current key image
  /// (TeachStep::count); nullopt on the first frame.
  std::optional<int> verified_with_key;
  /// Lines + points the current key image had when it was taken; nullopt: unknown. A poor key
  /// image matches nothing whatever the speed (few_features said so when it was taken), so
  /// overlap_lost is judged only against a key image with at least min_view_features.
  std::optional<int> key_features;
  /// |heading turned| over the last min_frame_gap frames (odometry, else the commanded rate).
  std::optional<double> turned_over_gap_rad;
  /// |heading(now) - heading(current key image)| (TeachStep::heading_change_rad).
  std::optional<double> heading_since_key_rad;
};

enum class TeachWarningKind { kFewFeatures, kTurningFast, kOverlapLost };
const char* to_string(TeachWarningKind kind);

struct TeachWarning {
  TeachWarningKind kind;
  std::string text;  ///< what is wrong, with the figures, and what to do
};

struct TeachFeedback {
  std::vector<TeachWarning> warnings;  ///< in TeachWarningKind order; empty: all well
  /// Frames each warning is still held for (index: TeachWarningKind), and its last text.
  int hold_left[3] = {0, 0, 0};
  std::string held_text[3];
  bool has(TeachWarningKind kind) const;
};

/// The warnings for `view`, given the previous frame's result (default: none).
TeachFeedback teach_feedback(const TeachView& view, const TeachFeedbackLimits& limits,
                             const TeachFeedback& previous = {});

/// {"warnings":[{"kind":"few_features","text":"..."}]}, the UI's `teach_feedback` state.
nlohmann::json to_json(const TeachFeedback& feedback);

}  // namespace pepper::app
