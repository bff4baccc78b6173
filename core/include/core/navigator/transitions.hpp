#pragma once
// The navigator's decisions as one table: in state S, on condition C (a named predicate over the
// facts one frame's stages found, set by the option it names), do action A and go to state T.
//
// Navigator::step runs its stages in order (perceive, localise, associate with the key images,
// switch, control, speed) and asks this table at four points (phases): on entry (terminal
// states), after a localisation attempt, after the key-image switcher, and after the control
// law. Within a phase the first row that applies in the current state and whose condition holds
// decides; the table is complete (every state of a phase has a row that always holds last).
// The key-image switching rules (when a switch is "wanted", paper and additions) are the
// switcher's own table, localization::switch_rules() (key_image_logic.hpp).
//
// docs/method/navigator.md prints both tables from the code (test
// NavigatorTransitions.DocsShowTheTablesOfTheCode).

#include <initializer_list>
#include <span>
#include <string>

#include "core/navigator/telemetry.hpp"

namespace pepper::core::navigator {

/// What one frame's stages found (each field read by one predicate of the table).
struct StepFacts {
  bool localised = false;      ///< the localisation attempt on this frame found a segment
  bool final_reached = false;  ///< the switcher confirmed arrival at the final image
  bool switched = false;       ///< the switcher advanced IP <- IN <- INN
  bool overdue = false;        ///< the segment lasted longer than segment_overdue_* allow
  bool has_demand = false;     ///< a control law produced a yaw-rate demand
  bool within_hold = false;    ///< an earlier command exists, younger than hold_s
  /// The frame has odometry, the map its key images' taught poses, the robot's place on the
  /// taught path is known, and the dead reckoning so far is within dead_reckoning_max_*.
  bool can_dead_reckon = false;
};

enum class Phase { kEntry, kLocalise, kSegment, kControl };

enum class Action {
  kStopTourComplete,  ///< stop for good: the tour is complete
  kStopOverdue,       ///< stop for good: unsure where the robot is
  kStopNotLocalised,  ///< stop, try to localise again on the next frame
  kStopFeaturesLost,  ///< stop, try to relocalise on the next frame
  kBeginSegment,      ///< a segment starts (its clock and commanded distance from zero)
  kContinue,          ///< nothing to decide here: the next stage runs
  kDrive,             ///< the demand through the velocity schedule
  kHold,              ///< repeat the last command
  kDeadReckon,        ///< follow the taught path on odometry
  kLose,              ///< stop, forget the segment, relocalise on the next frame
};

/// A set of states (bit 1 << NavState).
using StateSet = unsigned;
constexpr StateSet states_of(std::initializer_list<NavState> list) {
  StateSet s = 0;
  for (const NavState n : list) s |= 1u << static_cast<unsigned>(n);
  return s;
}
constexpr bool contains(StateSet set, NavState s) {
  return (set & (1u << static_cast<unsigned>(s))) != 0;
}

struct Transition {
  Phase phase;
  StateSet from;
  const char* condition;  ///< the predicate's name, e.g. "final image reached"
  const char* option;     ///< the option(s) behind it ("" for the paper's own structure)
  bool (*holds)(const StepFacts&);
  Action action;
  NavState to;  ///< for kBeginSegment and kContinue in the segment phase: the state stays
  bool keeps_state;
  const char* why;
};

const char* to_string(Phase p);
const char* to_string(Action a);

/// Every row, in the order they are tried.
std::span<const Transition> transition_table();

/// The first row of `phase` for `state` whose condition holds; nullptr when the phase has no
/// row for that state (the stage does not run in it).
const Transition* decide(Phase phase, NavState state, const StepFacts& facts);

/// The table as Markdown (one row per transition), as printed in docs/method/navigator.md.
std::string transition_table_markdown();

/// The key-image switcher's rules (localization::switch_rules()) as Markdown, as printed in
/// docs/method/navigator.md.
std::string switch_rules_markdown();

}  // namespace pepper::core::navigator
