#pragma once
// MockNaoqiServer: a NAOqi stand-in that speaks the qi-messaging wire protocol on behalf of a
// simulated robot (any sim::SimRobot), so tests and offline replays cross the real wire format.
//
// Serves service 0 (authenticate, optional user/password check), the ServiceDirectory (service
// 1: service, services, machineId) and ALMotion, ALVideoDevice, ALRobotPosture, ALAutonomousLife,
// ALBasicAwareness with NAOqi's method names, signatures and uids (PROTOCOL.md section 7), each
// with its MetaObject, plus the robot-state services `doctor` reads: ALSystem.systemVersion,
// ALBattery.getBatteryCharge and ALMemory.getData for the battery keys and ALMotion/MoveFailed
// (docs/mock_robot.md lists them and their sources). MockRobotState sets the state they report
// (NAOqi version, battery, charger, awake or resting, Autonomous Life, collision protection, and
// services left out); the robot-state hooks below change it while clients are connected.
// Backing: getImageRemote renders SimRobot::capture() at the subscribed resolution;
// move -> command_velocity; stopMove -> stop_move; setAngles/getAngles -> joints;
// getRobotPosition(useSensors) -> SimRobot::odometry (true: wheels, false: commands).
// moveTo(x, y, theta, time) drives the constant twist that reaches the pose in `time`, then
// stops the base by itself and answers the Call (bounded_move.hpp), like NAOqi's blocking
// time-constrained moveTo; any other motion command replaces it. Like a real NAOqi, the base
// keeps its last velocity when the commanding connection drops (stop_base_on_disconnect turns
// the old behaviour back on). getRobotVelocity and moveIsActive report what the base executes
// (zero after every stop); non-finite velocities are refused with an Error reply. Errors follow
// libqi's texts (3.2); a request the SimRobot refuses (sim::SimError) becomes an Error reply.
//
// tcp:// or tcps:// (TLS 1.2, certificate and key from files, or a self-signed EC certificate
// generated at start-up). Port 0 picks an ephemeral port: read url() after start().
//
// Frames are served as fast as they are asked for (lockstep simulation) unless pace_frames.
// Fault injection (MockServerOptions and the setters): reply latency, frame drops (the previous
// image served again), stalled frames (getImageRemote never answered), disconnect after N
// messages or on demand, malformed replies.
//
// Threading: one I/O thread of its own, started by start() and joined by stop()/destructor.
// Every public method is thread-safe. The SimRobot must outlive the server.

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "naoqi_bridge/qi/codec.hpp"
#include "naoqi_bridge/robot_bridge.hpp"
#include "sim/sim_robot.hpp"

namespace pepper::naoqi_bridge::qi {

/// The robot state the mock reports (and acts on), as a real Pepper would show it.
struct MockRobotState {
  std::string naoqi_version = "2.5.10.7";  ///< ALSystem.systemVersion and every ALModule.version
  int battery_percent = 87;                ///< ALBattery.getBatteryCharge, 0..100
  /// Charger plugged (power hatch open): the battery current reads positive and, as on a Pepper,
  /// locomotion is refused (the base stays still, ALMotion/MoveFailed is raised).
  bool charging = false;
  /// false: resting (motors off, ALMotion.robotIsWakeUp false) until wakeUp; moves then leave
  /// the base still and raise ALMotion/MoveFailed.
  bool awake = true;
  std::string autonomous_life = "solitary";  ///< solitary, interactive, disabled or safeguard
  bool collision_protection = true;  ///< getExternalCollisionProtectionEnabled("Move"/"All")
  /// Services the directory does not know (e.g. "ALBattery"), to test clients on robots without
  /// them. ALMotion and ALVideoDevice can be left out too.
  std::vector<std::string> missing_services;

  std::vector<std::string> validate() const;
};

struct MockServerOptions {
  std::string listen_url = "tcp://127.0.0.1:0";  ///< tcp:// or tcps://; port 0 = ephemeral
  std::string tls_certificate_file;  ///< PEM; empty with tcps = self-signed generated at start
  std::string tls_private_key_file;  ///< PEM
  std::string user;                  ///< non-empty: require auth_user/auth_token to match
  std::string password;
  bool legacy_service_info = false;  ///< answer 6-field ServiceInfo (NAOqi 2.5) instead of 7
  std::chrono::milliseconds reply_latency{0};  ///< added before every reply
  int drop_every_nth_frame = 0;  ///< 0 off; else every nth getImageRemote repeats the last image
  int disconnect_after_messages = 0;  ///< 0 off; else close each connection after n received
  int malformed_reply_every_nth = 0;  ///< 0 off; else every nth non-void reply is corrupted
  /// Stop the base when a connection that commanded it drops. Off by default, as on a real
  /// NAOqi, which keeps executing the last ALMotion.move velocity after its client went away
  /// (only a time-constrained moveTo ends by itself).
  bool stop_base_on_disconnect = false;
  /// Non-empty: append one JSON line per call received (service, method, arguments, time) and
  /// per base event (a moveTo ending) to this file. Login tokens are logged by length only.
  std::string call_log_file;
  /// Serve each subscriber at most at its subscribed fps, like a real camera (wall-clock paced).
  /// Off (default): every getImageRemote renders a new frame at once (lockstep, faster than real
  /// time, for tests and offline replay).
  bool pace_frames = false;
  /// Send a Capability message (type 6) as soon as a client connects, before authentication,
  /// as libqi 2.5 servers may (PROTOCOL.md 3.2); clients must merge it.
  bool announce_capabilities = false;
  /// Answer method calls with the DynamicPayload flag (payload = one `m`), which clients must
  /// accept (PROTOCOL.md 1.3).
  bool dynamic_replies = false;
  /// A connection must finish its TLS handshake and log in (authenticate) within this; 0 = off.
  std::chrono::milliseconds handshake_timeout{5000};
  /// A connection that sends nothing for this long is closed; 0 = off. Clients of a session
  /// request frames continuously, so only abandoned or hostile connections reach it.
  std::chrono::milliseconds idle_timeout{60000};
  /// Connections (including TLS handshakes) served at once; more are closed on accept.
  int max_connections = 64;
  MockRobotState robot_state;
  CodecLimits limits;

  std::vector<std::string> validate() const;
};

class MockNaoqiServer {
 public:
  MockNaoqiServer(sim::SimRobot& robot, MockServerOptions options = {});
  ~MockNaoqiServer();
  MockNaoqiServer(const MockNaoqiServer&) = delete;
  MockNaoqiServer& operator=(const MockNaoqiServer&) = delete;

  /// Binds and starts serving. Throws BridgeError (bad options, port in use, bad certificate).
  void start();
  /// Closes every connection and joins the I/O thread. Idempotent, never throws.
  void stop() noexcept;

  /// The URL clients should use, with the bound port (e.g. "tcp://127.0.0.1:40123").
  std::string url() const;
  std::uint16_t port() const;
  /// SHA-256 fingerprint of the served certificate (tcps), "" on tcp.
  std::string certificate_sha256() const;

  /// Fault injection at run time.
  void disconnect_all();
  void set_stall_frames(bool stall);
  void set_reply_latency(std::chrono::milliseconds latency);

  /// Robot-state hooks (tests, `mock-robot` options): what a real robot does by itself.
  /// A non-empty cause makes every later move/moveTo fail as NAOqi's external collision
  /// protection does near an obstacle: the Call is answered, the base stays still,
  /// getRobotVelocity and moveIsActive say so and ALMemory "ALMotion/MoveFailed" holds
  /// [cause, status 1, getRobotPosition(false)]. "" ends it.
  void set_move_failure(const std::string& cause);
  /// Autonomous Life takes the head back, as when it re-enters "solitary" during a session:
  /// state solitary, ALBasicAwareness enabled, and the head turned to `head_yaw_rad` (a person
  /// tracked). While awareness stays enabled it keeps the head there against setAngles. With
  /// `sticky`, setState("disabled") and setEnabled(false) no longer take (something on the robot
  /// keeps re-enabling them): the head cannot be held.
  void take_head_back(double head_yaw_rad, bool sticky);
  void set_awake(bool awake);
  void set_charging(bool charging);
  void set_battery_percent(int percent);

  /// State of the simulated services (for tests).
  std::string autonomous_life_state() const;
  bool basic_awareness_enabled() const;
  bool external_collision_protection() const;
  bool awake() const;
  double stiffness(const std::string& joint) const;  ///< 0 when never set
  std::vector<std::string> video_subscribers() const;

  struct Stats {
    std::uint64_t connections_accepted = 0;
    std::uint64_t connections_open = 0;
    std::uint64_t messages_received = 0;
    std::uint64_t frames_served = 0;
    std::uint64_t auth_failures = 0;
    std::uint64_t protocol_errors = 0;
    std::uint64_t base_stops_on_disconnect = 0;
    std::uint64_t bounded_moves_ended = 0;  ///< moveTo(x, y, theta, time) ran to its end
    std::uint64_t connections_refused = 0;  ///< closed on accept: max_connections reached
    std::uint64_t connections_timed_out = 0;  ///< closed by handshake_timeout / idle_timeout
  };
  Stats stats() const;

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;
};

}  // namespace pepper::naoqi_bridge::qi
