#pragma once
// QiBridge: RobotBridge for a real Pepper (or our mock NAOqi server) over qi messaging.
//
// Services: ALVideoDevice (subscribeCamera on the top camera in grey kYuv, getImageRemote,
// unsubscribe), ALMotion (wakeUp, setStiffnesses, setAngles/getAngles for HeadYaw, HeadPitch,
// HipRoll, HipPitch, KneePitch, move(fff), stopMove; external collision protection is left as
// the robot has it), ALAutonomousLife and ALBasicAwareness (turned off by lock_head() so the
// head stays still; the previous states come back with release()). Methods are resolved by name
// and parameter signature through each service's MetaObject, never by hard-coded uid.
//
// Frames: one getImageRemote request is always kept in flight while the caller processes the
// previous frame (hides WiFi latency); frames carry the robot's timestamp (s, us -> t_ns); a
// reply with a timestamp not newer than the last one (the robot had no new image) is skipped.
// Odometry: with each image request, ALMotion.getRobotPosition(true) is sent just before it
// (asynchronously, so it adds no round trip: its small reply is normally back before the image's)
// and its [x, y, theta] becomes the frame's Frame::odom. When the reply is not there
// `odometry_grace` after the image, is an Error, or is not three finite numbers, or the robot has
// no getRobotPosition(b), the frame comes without odometry: counted, the reason kept in
// odometry_problem(), never fatal.
//
// Robot-side deadman (docs/naoqi_bridge.md): a non-zero velocity is sent as the
// time-constrained ALMotion.moveTo towards the pose it reaches in `deadman_horizon`
// (bounded_move.hpp), so the robot stops by itself when the laptop stops talking; its Call is
// answered only when the move ends, so move() does not wait for it (an Error answer is counted
// and kept in last_move_error()). Zero velocities and stops use move(0,0,0) + stopMove. Robots
// without moveTo(ffff) get plain move(fff) and only the laptop-side stops below.
//
// Safety (docs/naoqi_bridge.md): a watchdog thread stops the base (move(0,0,0) then stopMove)
// when no fresh move() arrives within `watchdog_timeout` while moving, when frames stall while
// moving, and any exception in a bridge call stops the base before it propagates. A lost
// connection latches "needs operator": move() then refuses (BridgeError) until the operator
// calls clear_fault() (after reconnect()); a real NAOqi (and our mock server) keeps the last
// plain move() velocity after a disconnect, which is why commands carry their own horizon.
// stop() is callable from any thread at any time and never throws.
//
// Supervision (supervise(), called by sessions every loop iteration, never blocking): every
// `supervise_period` it sends ALMotion.getRobotVelocity and moveIsActive and, while the head is
// locked, ALAutonomousLife.getState, ALBasicAwareness.isEnabled and getAngles of the head, all
// asynchronously, and judges the replies on a later call (MotionSupervisor): a velocity the robot
// does not execute becomes a warning (with ALMemory's ALMotion/MoveFailed cause when the robot
// has it); a head the robot took back is re-taken (Autonomous Life and awareness off again, the
// angles re-sent) with a warning; a head that cannot be held stops the base, latches the fault
// and is reported as head_lock_lost.
//
// Threading: as RobotBridge. One watchdog thread, started by connect() and joined by the
// destructor. The password is never logged; describe() shows URL and user only.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "naoqi_bridge/qi/motion_supervisor.hpp"
#include "naoqi_bridge/qi/session.hpp"
#include "naoqi_bridge/robot_bridge.hpp"

namespace pepper::naoqi_bridge::qi {

struct QiBridgeOptions {
  std::string url = "tcp://127.0.0.1:9559";  ///< tcp://HOST:9559 or tcps://HOST:9503
  std::string user;                          ///< e.g. "nao" for NAOqi 2.9; empty: no login
  std::string password;                      ///< from a prompt, file or env; never logged
  std::string tls_pin_sha256;                ///< empty: accept the robot's self-signed cert
  /// SessionOptions::verify_certificate (trust on first use); empty: no check beyond the pin.
  std::function<void(const std::string& url, const std::string& sha256)> verify_certificate;
  std::chrono::milliseconds connect_timeout{5000};
  std::chrono::milliseconds call_timeout{3000};         ///< per remote call
  std::chrono::milliseconds stop_call_timeout{500};     ///< per call inside stop()
  std::chrono::milliseconds watchdog_timeout{300};      ///< stop if no move() for this long
  std::chrono::milliseconds frame_stall_timeout{1000};  ///< stop if moving and no frame this long
  std::chrono::milliseconds watchdog_period{20};        ///< watchdog check period
  /// Robot-side deadman: each non-zero velocity goes out as ALMotion.moveTo(x, y, theta, time)
  /// towards the pose it would reach in this time, so the robot stops by itself when no fresh
  /// command follows (frozen or killed laptop, lost link). 0 = plain move(x, y, theta), which a
  /// real NAOqi keeps executing until told otherwise. Used only when the robot's ALMotion has
  /// moveTo(ffff) (robot_side_deadman() says whether it has).
  std::chrono::milliseconds deadman_horizon{250};
  int reconnect_attempts = 5;                           ///< reconnect(): tries before giving up
  std::chrono::milliseconds reconnect_initial_backoff{250};  ///< doubles after each failure
  std::chrono::milliseconds reconnect_max_backoff{4000};
  std::string subscriber_name = "pepper_nav";  ///< ALVideoDevice subscriber prefix (ours)
  bool disable_autonomous_life = true;   ///< lock_head(): ALAutonomousLife "disabled" + wakeUp
  bool disable_basic_awareness = true;   ///< lock_head(): ALBasicAwareness.setEnabled(false)
  double head_max_speed_fraction = 0.2;  ///< setAngles fractionMaxSpeed, (0, 1]
  std::chrono::milliseconds head_settle_timeout{2000};  ///< lock_head(): wait for read-back
  std::chrono::milliseconds head_resend_period{1000};   ///< re-send head angles; 0 = off
  /// supervise(): read-back period of the robot's motion and head-lock state; 0 = off.
  std::chrono::milliseconds supervise_period{500};
  MotionSupervisorOptions supervisor;
  bool read_odometry = true;  ///< ALMotion.getRobotPosition(true) with each frame (Frame::odom)
  /// How long a frame waits for its odometry reply after the image arrived (normally 0: the
  /// reply is already there); beyond it the frame goes on without odometry.
  std::chrono::milliseconds odometry_grace{5};
  CodecLimits limits;

  /// Messages naming each invalid field and its allowed range; empty when valid.
  std::vector<std::string> validate() const;
};

class QiBridge : public RobotBridge {
 public:
  explicit QiBridge(QiBridgeOptions options);
  ~QiBridge() override;

  void connect() override;
  core::CameraIntrinsics start_camera(const CameraRequest& request) override;
  std::optional<core::Frame> next_frame(std::chrono::milliseconds timeout) override;
  HeadLockStatus lock_head(const HeadLockRequest& request) override;
  void move(const BaseVelocity& velocity) override;
  void stop() noexcept override;
  void release() noexcept override;
  ConnectionState state() const override;
  std::string describe() const override;
  RobotSupervision supervise() override;

  /// Operator action after a fault: re-arms move(). Throws BridgeError when not connected.
  void clear_fault();
  /// True after a disconnect or protocol violation until clear_fault().
  bool needs_operator() const;
  std::string fault_reason() const;
  /// Operator action: reconnect with bounded exponential backoff, re-subscribe the camera and
  /// re-lock the head if they were active. The fault stays latched (clear_fault() re-arms).
  void reconnect();

  /// Why the last frame came without odometry ("" when it had it, or before the first frame).
  std::string odometry_problem() const override;
  /// True when connected to an ALMotion with moveTo(x, y, theta, time) and deadman_horizon > 0:
  /// every velocity command then ends by itself on the robot after deadman_horizon.
  bool robot_side_deadman() const;
  /// One line for operators: which robot-side stop is in force and what it means.
  std::string robot_side_deadman_summary() const;

  /// SHA-256 of the robot's TLS certificate (tcps), "" on tcp.
  std::string tls_fingerprint() const;
  QiSession& session() { return *session_; }

  struct Counters {
    std::uint64_t frames = 0;          ///< frames returned by next_frame
    std::uint64_t stale_replies = 0;   ///< replies with no newer image
    std::uint64_t moves = 0;           ///< move commands sent
    std::uint64_t stops = 0;           ///< stop sequences sent
    std::uint64_t watchdog_stops = 0;  ///< of which triggered by the watchdog
    std::uint64_t frames_without_odometry = 0;  ///< frames returned with Frame::odom empty
    std::uint64_t bounded_move_errors = 0;  ///< moveTo Calls the robot answered with an Error
    std::uint64_t supervision_probes = 0;   ///< read-backs judged by supervise()
    std::uint64_t move_failures = 0;        ///< move-failure episodes seen
    std::uint64_t head_retakes = 0;         ///< head lock re-taken after the robot took it
  };
  Counters counters() const;
  /// Why the last automatic stop happened ("watchdog: ...", "frames stalled ..."), for logs.
  std::string last_stop_reason() const;
  /// Text of the last Error the robot answered to a bounded move (moveTo), "" if none.
  std::string last_move_error() const;

 private:
  void open_session();
  void subscribe_camera_locked();
  PendingCall request_image();
  /// Sends getRobotPosition(true) and getImageRemote, in that order, as the call in flight.
  void request_frame_locked();
  /// The odometry of a frame from its getRobotPosition call; nullopt (and the reason kept) when
  /// there is none.
  std::optional<core::OdometryPose> take_odometry(PendingCall& call);
  void latch_fault(const std::string& why);
  void stop_base(const std::string& why) noexcept;
  void watchdog_loop();
  void send_bounded_move(const ServiceHandle& motion, const BaseVelocity& velocity);
  void reap_bounded_move();
  /// supervise(): one set of read-back calls in flight and what was commanded when it was sent.
  struct Probe {
    bool active = false;
    std::int64_t sent_ns = 0;
    MotionSupervisor::CommandSnapshot command;
    PendingCall velocity, move_active, life, awareness, head_angles;
    std::optional<HeadLockRequest> head;  ///< the lock in force when sent
  };
  void send_probe_locked(std::int64_t now_ns);
  void judge_probe(Probe& probe, RobotSupervision& out);
  bool connected() const { return state_.load() == ConnectionState::kConnected; }

  QiBridgeOptions options_;
  std::unique_ptr<QiSession> session_;
  std::atomic<ConnectionState> state_{ConnectionState::kDisconnected};

  mutable std::mutex mutex_;  // services, camera and head state, fault, counters
  std::optional<ServiceHandle> motion_, video_, life_, awareness_;
  std::optional<CameraRequest> camera_;
  int resolution_code_ = 2;
  std::string camera_handle_;
  PendingCall inflight_;
  PendingCall odometry_inflight_;    ///< getRobotPosition sent with inflight_ (invalid when none)
  bool odometry_available_ = false;  ///< read_odometry and the robot has getRobotPosition(b)
  std::string odometry_problem_;
  std::chrono::steady_clock::time_point inflight_since_{};
  std::int64_t last_t_ns_ = -1;
  std::int64_t frame_index_ = 0;
  std::optional<HeadLockRequest> head_;
  std::optional<std::string> previous_life_state_;
  std::optional<bool> previous_awareness_;
  bool needs_operator_ = false;
  std::string fault_reason_;
  std::string last_stop_reason_;
  std::string last_move_error_;
  Counters counters_;
  bool bounded_moves_ = false;  // ALMotion has moveTo(ffff) and deadman_horizon > 0
  PendingCall last_bounded_;    // the latest moveTo in flight (answered when it ends)
  std::optional<ServiceHandle> memory_;  // ALMemory, for ALMotion/MoveFailed (optional)
  MotionSupervisor supervisor_;
  Probe probe_;
  std::int64_t last_probe_ns_ = 0;
  PendingCall move_failed_call_;  // ALMemory.getData("ALMotion/MoveFailed") after a failure
  std::optional<BaseVelocity> measured_velocity_;
  std::optional<bool> move_active_;
  bool head_retaking_ = false;
  bool head_lock_lost_ = false;
  std::string head_lock_detail_;

  std::mutex motion_send_mutex_;  // orders move/stop sends on the wire
  std::atomic<bool> moving_{false};
  std::atomic<std::int64_t> last_move_ns_{0};
  std::atomic<std::int64_t> last_frame_ns_{0};
  std::atomic<std::int64_t> last_head_resend_ns_{0};

  std::mutex wd_mutex_;
  std::condition_variable wd_cv_;
  bool wd_quit_ = false;
  std::thread watchdog_;
};

}  // namespace pepper::naoqi_bridge::qi
