#pragma once
// The per-frame replay state machine: one call per frame, returning the base command and a
// telemetry record (ARCHITECTURE.md: frames with timestamps in, commands and telemetry out).
// It ties together features (core/features), localisation and switching (core/localization)
// and the control laws (core/control); METHOD.md "Replay".
//
// States:
//   kNotLocalized  no segment yet: every frame runs initial localisation (initial_localizer.hpp);
//                  command: stop (reason kNotLocalized) until it succeeds.
//   kNavigating    segment (IP, IN, INN) known: counts for switching, control law, command.
//   kHolding       the control law has no usable feature (too few verified matches with IN):
//                  the last command is held for at most `hold_ns` (measured with frame stamps).
//   kLost          the hold expired: command stop (reason kFeaturesLost) and relocalise over the
//                  whole map on each frame; back to kNavigating when that succeeds.
//   kTourComplete  IN was the final image and arrival was seen (key_image_logic.hpp): stop
//                  (reason kTourComplete) on every further frame.
// Per frame in kNavigating: with a FrameMatcher on the current frame: n(Ia, IN), n(Ia, INN),
// and, only when they can change the decision (lazy, same outcome), n(IP, Ia) and the
// three-view counts (IP, Ia, IN), (Ia, IN, INN) -> KeyImageSwitcher; then, on the (new)
// segment, the line and point features of Ia vs IN and INN -> IBVS (or VNHV) law -> velocity
// schedule (turn-dependent speed, saturation and rate limit on omega by frame stamps).
//
// Determinism: the command is a function of the frames (pixels, t_ns) and the options only
// (seeded RANSAC, no wall clock). Wall-clock (std::chrono::steady_clock) durations appear in
// the telemetry's timings only. Units and signs: docs/conventions.md.
// Errors: a frame that is empty, not CV_8UC1, of another size than the map's images, or with
// t_ns before the previous frame's throws std::invalid_argument (the app stops the robot);
// invalid options throw at construction. Not thread-safe: one Navigator per replay.

#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/control/ibvs_law.hpp"
#include "core/control/velocity_schedule.hpp"
#include "core/control/vnhv_law.hpp"
#include "core/features/image_features.hpp"
#include "core/features/matching.hpp"
#include "core/frame.hpp"
#include "core/localization/initial_localizer.hpp"
#include "core/localization/key_image_logic.hpp"
#include "core/memory/visual_memory.hpp"
#include "core/navigator/telemetry.hpp"

namespace pepper::core::navigator {

enum class ControllerKind { kIbvs, kVnhv };
const char* to_string(ControllerKind k);

struct NavigatorOptions {
  ControllerKind controller = ControllerKind::kIbvs;
  control::IbvsOptions ibvs;
  control::VnhvOptions vnhv;
  control::VelocityScheduleOptions schedule;
  localization::InitialLocalizerOptions initial;
  localization::SwitcherOptions switching;
  features::FeatureExtractorOptions extractor;
  features::MatcherOptions matcher;
  /// How long the last command is held when features vanish, ns of frame time, >= 0.
  int64_t hold_ns = 1'000'000'000;
  /// Fewer verified line matches with IN than this: the line modality is absent. >= 1.
  int min_line_matches = 3;
  /// Fewer verified point matches with IN than this: the point modality is absent. >= 1.
  int min_point_matches = 8;
  /// Point matches whose location in the current image has a structure-tensor minimum
  /// eigenvalue (7x7 window, grey levels^2 / px^2) below this are not used by the control law:
  /// guards against KLT "tracks" into textureless images (measured: 0 on a uniform image, ~4 on
  /// pure sensor-like noise sigma 3, 5th percentile ~20 on textured scenes). >= 0.
  double min_point_texture = 10.0;
  /// The apparent-scale ratio vs IN (switch guard, "passed IN", arrival) is computed only from
  /// at least this many verified point matches (fewer: unknown). Measured: with ~15 matches far
  /// from IN the ratio read 1.1..1.2 and fired "passed IN" spuriously. >= 3.
  int min_scale_points = 20;
  /// Arrival at the final image: median scale ratio (key -> current) of the point matches with
  /// IN at least this (1 = exactly the key image's apparent scale), in (0, 2).
  double arrival_scale_ratio = 0.98;
  std::vector<std::string> validate() const;
};

struct StepResult {
  Command command;
  Telemetry telemetry;
};

class Navigator {
 public:
  /// Takes the map (moved in). Builds the key images' KLT pyramids once (tracking from key
  /// images every frame). Throws std::invalid_argument on invalid options or a map with fewer
  /// than 2 key images.
  Navigator(memory::VisualMemory map, const NavigatorOptions& options = {});

  StepResult step(const Frame& frame);
  /// Forget the segment and the command history (next frame relocalises from scratch).
  void reset();

  NavState state() const { return state_; }
  const memory::VisualMemory& map() const { return map_; }
  const NavigatorOptions& options() const { return options_; }

 private:
  void localize(features::FrameMatcher& fm, Telemetry& tel);
  std::optional<double> ibvs_omega(features::FrameMatcher& fm, Telemetry& tel);
  void ensure_pyramids(const localization::Segment& seg);
  std::optional<double> vnhv_omega(features::FrameMatcher& fm, Telemetry& tel);
  void remember_tracks(const features::FrameMatcher& fm);
  const features::ImageFeatures& key(int i) const { return map_.key_images[i].features; }

  memory::VisualMemory map_;
  NavigatorOptions options_;
  features::FeatureExtractor extractor_;
  control::VelocitySchedule schedule_;
  std::optional<localization::KeyImageSwitcher> switcher_;
  NavState state_ = NavState::kNotLocalized;
  Command last_command_;
  bool has_command_ = false;
  int64_t last_good_t_ns_ = 0;
  std::optional<int64_t> last_t_ns_;
  // VNHV: planar pose of IP in IN's frame, per segment (computed once when the segment starts).
  int vnhv_segment_next_ = -1;
  std::optional<control::PlanarPose> vnhv_prev_in_next_;
  // Speed: the verified point matches of the previous frame per key image of the segment, the
  // KLT starting points of this frame (features::match_two_view's prior). Cleared whenever the
  // segment is forgotten, so it depends on the frames only.
  std::unordered_map<int, std::vector<features::PointMatch>> klt_priors_;
};

}  // namespace pepper::core::navigator
