#include "core/navigator/transitions.hpp"

#include <array>
#include <sstream>
#include <stdexcept>

#include "core/localization/key_image_logic.hpp"

namespace pepper::core::navigator {
namespace {

using S = NavState;

bool always(const StepFacts&) { return true; }
bool localised(const StepFacts& f) { return f.localised; }
bool final_reached(const StepFacts& f) { return f.final_reached; }
bool switched(const StepFacts& f) { return f.switched; }
bool overdue(const StepFacts& f) { return f.overdue; }
bool has_demand(const StepFacts& f) { return f.has_demand; }
bool within_hold(const StepFacts& f) { return f.within_hold; }
bool can_dead_reckon(const StepFacts& f) { return f.can_dead_reckon; }

constexpr StateSet kNavigatingOrHolding =
    states_of({S::kNavigating, S::kHolding, S::kDeadReckoning});

// clang-format off
const std::array<Transition, 13> kTable{{
  // Entry: terminal states stay stopped, nothing else runs.
  {Phase::kEntry, states_of({S::kTourComplete}), "always", "", always,
   Action::kStopTourComplete, S::kTourComplete, false,
   "the tour ended: the robot stays stopped"},
  {Phase::kEntry, states_of({S::kOverdue}), "always", "", always,
   Action::kStopOverdue, S::kOverdue, false,
   "unsure where the robot is: it stays stopped for good"},
  // After a localisation attempt (initial, or after features were lost).
  {Phase::kLocalise, states_of({S::kNotLocalized, S::kLost}), "localised",
   "navigator.localization.min_best_count", localised,
   Action::kBeginSegment, S::kNavigating, false,
   "the best key image and its better neighbour give IP, IN, INN (METHOD.md)"},
  {Phase::kLocalise, states_of({S::kNotLocalized}), "always", "", always,
   Action::kStopNotLocalised, S::kNotLocalized, false,
   "no key image verified enough matches: stay still, try again on the next frame"},
  {Phase::kLocalise, states_of({S::kLost}), "always", "", always,
   Action::kStopFeaturesLost, S::kLost, false,
   "still lost: stay still, try again on the next frame"},
  // After the key-image switcher (its rules: localization::switch_rules()).
  {Phase::kSegment, kNavigatingOrHolding, "final image reached",
   "navigator.arrival_scale_ratio, navigator.switching.consecutive_frames", final_reached,
   Action::kStopTourComplete, S::kTourComplete, false,
   "arrival at the final key image on consecutive frames: stop for good"},
  {Phase::kSegment, kNavigatingOrHolding, "switched", "navigator.switching.*", switched,
   Action::kBeginSegment, S::kNavigating, true,
   "IP <- IN <- INN: the new segment's clock and commanded distance start"},
  {Phase::kSegment, kNavigatingOrHolding, "segment overdue",
   "navigator.segment_overdue_factor, navigator.segment_overdue_min_s", overdue,
   Action::kStopOverdue, S::kOverdue, false,
   "no switch for far longer than teaching took (end of tour not recognised?): stop for good"},
  {Phase::kSegment, kNavigatingOrHolding, "always", "", always,
   Action::kContinue, S::kNavigating, true, "control on the segment"},
  // After the control law.
  {Phase::kControl, kNavigatingOrHolding, "demand", "navigator.controller", has_demand,
   Action::kDrive, S::kNavigating, false,
   "the law's yaw rate through the velocity schedule (speed, turn slow-down, limits)"},
  {Phase::kControl, kNavigatingOrHolding, "odometry on the taught path",
   "navigator.dead_reckoning_max_lateral_sigma_m", can_dead_reckon,
   Action::kDeadReckon, S::kDeadReckoning, false,
   "vision sees too little (a blank wall in a turn): drive the taught path on odometry until "
   "the key images are matched again, while the error it adds across the path stays bounded"},
  {Phase::kControl, kNavigatingOrHolding, "within hold", "navigator.hold_s", within_hold,
   Action::kHold, S::kHolding, false,
   "no usable feature this frame and no odometry: repeat the last command for a short while"},
  {Phase::kControl, kNavigatingOrHolding, "always", "", always,
   Action::kLose, S::kLost, false,
   "no usable feature, beyond the hold or the dead-reckoning bounds: stop, forget the segment, "
   "relocalise"},
}};
// clang-format on

std::string state_list(StateSet set) {
  std::string out;
  for (const S s : {S::kNotLocalized, S::kNavigating, S::kHolding, S::kDeadReckoning, S::kLost,
                    S::kTourComplete, S::kOverdue}) {
    if (!contains(set, s)) continue;
    out += (out.empty() ? "" : ", ") + std::string(to_string(s));
  }
  return out;
}

}  // namespace

const char* to_string(Phase p) {
  switch (p) {
    case Phase::kEntry: return "entry";
    case Phase::kLocalise: return "localise";
    case Phase::kSegment: return "segment";
    case Phase::kControl: return "control";
  }
  return "?";
}

const char* to_string(Action a) {
  switch (a) {
    case Action::kStopTourComplete: return "stop (tour_complete)";
    case Action::kStopOverdue: return "stop (segment_overdue)";
    case Action::kStopNotLocalised: return "stop (not_localized)";
    case Action::kStopFeaturesLost: return "stop (features_lost)";
    case Action::kBeginSegment: return "begin segment";
    case Action::kContinue: return "continue";
    case Action::kDrive: return "drive";
    case Action::kHold: return "hold last command";
    case Action::kDeadReckon: return "drive the taught path on odometry";
    case Action::kLose: return "stop (features_lost), forget segment";
  }
  return "?";
}

std::span<const Transition> transition_table() {
  return kTable;
}

const Transition* decide(Phase phase, NavState state, const StepFacts& facts) {
  for (const Transition& t : transition_table()) {
    if (t.phase == phase && contains(t.from, state) && t.holds(facts)) return &t;
  }
  return nullptr;
}

std::string transition_table_markdown() {
  std::ostringstream os;
  os << "| phase | in state | condition | option | action | next state | why |\n"
     << "| --- | --- | --- | --- | --- | --- | --- |\n";
  for (const Transition& t : transition_table()) {
    os << "| " << to_string(t.phase) << " | " << state_list(t.from) << " | " << t.condition
       << " | " << (*t.option ? std::string("`") + t.option + "`" : std::string()) << " | "
       << to_string(t.action) << " | " << (t.keeps_state ? "unchanged" : to_string(t.to))
       << " | " << t.why << " |\n";
  }
  return os.str();
}

std::string switch_rules_markdown() {
  std::ostringstream os;
  os << "| rule | kind | option | telemetry bit | why |\n"
     << "| --- | --- | --- | --- | --- |\n";
  for (const localization::SwitchRule& r : localization::switch_rules()) {
    os << "| " << r.name << " | " << localization::to_string(r.kind) << " | "
       << (*r.option ? std::string("`") + r.option + "`" : std::string()) << " | "
       << r.criterion_bit << " | " << r.why << " |\n";
  }
  return os.str();
}

}  // namespace pepper::core::navigator
