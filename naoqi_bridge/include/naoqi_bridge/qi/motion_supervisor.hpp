#pragma once
// MotionSupervisor: the decisions behind QiBridge::supervise(), kept free of sockets so they can
// be tested on their own. QiBridge feeds it every command it sends and the robot's read-backs
// (ALMotion.getRobotVelocity and moveIsActive; ALAutonomousLife.getState, ALBasicAwareness
// .isEnabled and the head angles); it answers whether the robot executes the commanded move and
// whether the head lock holds, needs re-taking, or is lost.
//
// Move failure (a MoveFailed as NAOqi raises it when external collision protection refuses or
// stops a move, when the charging hatch is open or the robot rests): a non-zero command that has
// been in force for `move_settle` (ALMotion ramps the velocity at its acceleration limits; a
// command after a gap longer than `command_fresh` starts a new ramp) and
// was refreshed within `command_fresh` (older commands may have ended by their robot-side
// horizon), while the robot reads back moveIsActive false or a speed and turn rate below
// `executed_fraction` of the command, on `failing_probes` read-backs in a row. getRobotVelocity
// is in NAOqi's world frame, so speeds are compared by magnitude.
//
// Head lock: a read-back is "taken" when Autonomous Life is not "disabled" or awareness is on
// although the bridge turned them off, and "off target" when a head joint is further than the
// tolerance from its target. Either gives kRetake (turn them off again, re-send the angles); on
// `lost_probes` such read-backs in a row the lock counts as lost (kLost): the session must stop.
//
// Times are monotonic nanoseconds. Not thread-safe: QiBridge guards it.

#include <cstdint>
#include <optional>
#include <string>

#include "naoqi_bridge/robot_bridge.hpp"

namespace pepper::naoqi_bridge::qi {

struct MotionSupervisorOptions {
  std::int64_t move_settle_ns = 700'000'000;    ///< command age before a read-back counts
  std::int64_t command_fresh_ns = 200'000'000;  ///< last command at most this old at the probe
  double executed_fraction = 0.25;  ///< read-back below this fraction of the command: not moving
  int failing_probes = 2;           ///< disagreeing read-backs in a row for a move failure
  int lost_probes = 3;              ///< head read-backs not holding in a row for a lost lock
};

class MotionSupervisor {
 public:
  explicit MotionSupervisor(MotionSupervisorOptions options = {}) : options_(options) {}

  /// Every velocity command sent to the robot (zero for stops).
  void on_command(const BaseVelocity& velocity, std::int64_t t_ns);

  /// The command state when a read-back was requested (evaluated when its reply arrives).
  struct CommandSnapshot {
    BaseVelocity velocity;
    bool counts = false;  ///< settled and fresh: a read-back then says whether it is executed
  };
  CommandSnapshot snapshot(std::int64_t t_ns) const;

  /// A motion read-back for a snapshot. Returns the warning to show when a failure starts or
  /// ends (nullopt otherwise).
  std::optional<std::string> on_motion_readback(const CommandSnapshot& command,
                                                const BaseVelocity& measured,
                                                std::optional<bool> move_active);
  bool move_failing() const { return failing_; }

  struct HeadReadback {
    std::optional<std::string> life_state;  ///< when ALAutonomousLife answered
    std::optional<bool> awareness_enabled;  ///< when ALBasicAwareness answered
    std::optional<double> max_error_rad;    ///< |target - measured| over the head joints
  };
  enum class HeadVerdict { kHolding, kRetake, kLost };
  /// `expect_life_disabled` / `expect_awareness_off`: the bridge turned them off at lock time.
  /// `detail` says what was seen (for warnings and the stop reason).
  HeadVerdict on_head_readback(const HeadReadback& r, bool expect_life_disabled,
                               bool expect_awareness_off, double tolerance_rad,
                               std::string& detail);

 private:
  MotionSupervisorOptions options_;
  BaseVelocity command_;
  std::int64_t command_since_ns_ = -1;  ///< when the current non-zero command began
  std::int64_t last_command_ns_ = -1;
  int disagreeing_ = 0;
  bool failing_ = false;
  int head_bad_ = 0;
};

}  // namespace pepper::naoqi_bridge::qi
