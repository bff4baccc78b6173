// MockNaoqiServer: qi-messaging server for a simulated Pepper (see the header).
#include "naoqi_bridge/qi/mock_server.hpp"

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/asio/steady_timer.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "connection.hpp"
#include "naoqi_bridge/qi/bounded_move.hpp"
#include "naoqi_bridge/qi/image_remote.hpp"
#include "naoqi_bridge/qi/message.hpp"
#include "naoqi_bridge/qi/meta.hpp"
#include "naoqi_bridge/qi/url.hpp"

namespace pepper::naoqi_bridge::qi {

namespace asio = boost::asio;
using tcp = asio::ip::tcp;

std::vector<std::string> MockRobotState::validate() const {
  std::vector<std::string> errors;
  if (naoqi_version.empty()) errors.push_back("robot_state.naoqi_version must not be empty");
  if (battery_percent < 0 || battery_percent > 100) {
    errors.push_back("robot_state.battery_percent must be in 0..100, got " +
                     std::to_string(battery_percent));
  }
  if (autonomous_life != "solitary" && autonomous_life != "interactive" &&
      autonomous_life != "disabled" && autonomous_life != "safeguard") {
    errors.push_back("robot_state.autonomous_life must be solitary, interactive, disabled or "
                     "safeguard, got '" + autonomous_life + "'");
  }
  for (const auto& name : missing_services) {
    if (name == "ServiceDirectory") errors.push_back("the ServiceDirectory cannot be left out");
  }
  return errors;
}

std::vector<std::string> MockServerOptions::validate() const {
  std::vector<std::string> errors;
  for (const auto& e : robot_state.validate()) errors.push_back(e);
  try {
    (void)parse_url(listen_url);
  } catch (const BridgeError& e) {
    errors.push_back(std::string("listen_url: ") + e.what());
  }
  if (tls_certificate_file.empty() != tls_private_key_file.empty()) {
    errors.push_back("tls_certificate_file and tls_private_key_file must be given together");
  }
  if (user.empty() && !password.empty()) errors.push_back("password given without a user");
  if (reply_latency.count() < 0 || reply_latency.count() > 60000) {
    errors.push_back("reply_latency must be in 0..60000 ms, got " +
                     std::to_string(reply_latency.count()));
  }
  if (drop_every_nth_frame < 0 || drop_every_nth_frame == 1) {
    errors.push_back("drop_every_nth_frame must be 0 (off) or >= 2, got " +
                     std::to_string(drop_every_nth_frame));
  }
  if (disconnect_after_messages < 0) errors.push_back("disconnect_after_messages must be >= 0");
  if (malformed_reply_every_nth < 0) errors.push_back("malformed_reply_every_nth must be >= 0");
  if (handshake_timeout.count() < 0) errors.push_back("handshake_timeout must be >= 0 (0 = off)");
  if (idle_timeout.count() < 0) errors.push_back("idle_timeout must be >= 0 (0 = off)");
  if (max_connections < 1 || max_connections > 100000) {
    errors.push_back("max_connections must be in 1..100000, got " +
                     std::to_string(max_connections));
  }
  for (const auto& e : limits.validate()) errors.push_back("limits." + e);
  return errors;
}

namespace {

/// Error raised by a simulated method: becomes an Error reply with this exact text.
struct MethodFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct ConnState;
using Handler = std::function<Value(ConnState&, const std::vector<Value>&)>;

struct MethodDef {
  MetaMethod meta;
  Type params;
  Type ret;
  Handler fn;
};

struct ServiceDef {
  std::string name;
  std::uint32_t id = 0;
  std::map<std::uint32_t, MethodDef> methods;
  std::map<std::uint32_t, MetaSignal> signals;

  void add(std::uint32_t uid, const std::string& name_, const std::string& params,
           const std::string& ret, Handler fn, std::vector<std::string> param_names = {}) {
    MethodDef d;
    d.meta.uid = uid;
    d.meta.name = name_;
    d.meta.parameters_signature = params;
    d.meta.return_signature = ret;
    for (auto& p : param_names) d.meta.parameters.push_back({p, ""});
    d.params = parse_signature(params);
    d.ret = parse_signature(ret);
    d.fn = std::move(fn);
    methods[uid] = std::move(d);
  }
  MetaObject meta() const {
    MetaObject mo;
    for (const auto& [uid, m] : methods) mo.methods[uid] = m.meta;
    mo.signals = signals;
    mo.description = name;
    return mo;
  }
};

struct ConnState {
  std::shared_ptr<detail::MessageConnection> conn;
  std::weak_ptr<ConnState> self;  ///< for replies sent later (a moveTo answers when it ends)
  bool authenticated = false;
  bool commanded_base = false;
  std::uint64_t received = 0;
  std::chrono::steady_clock::time_point accepted_at{};
  std::chrono::steady_clock::time_point last_message_at{};
};

std::vector<std::string> names_arg(const Value& v, const char* what) {
  const Value& u = v.unwrapped();
  if (u.kind() == TypeKind::kString) return {u.as_string()};
  std::vector<std::string> out;
  try {
    for (const auto& e : u.elements()) out.push_back(e.unwrapped().as_string());
  } catch (const ProtocolError&) {
    throw MethodFailure(std::string(what) + ": expected a name or a list of names, got '" +
                        u.signature() + "'");
  }
  return out;
}

std::vector<double> floats_arg(const Value& v, std::size_t n, const char* what) {
  const Value& u = v.unwrapped();
  std::vector<double> out;
  try {
    if (is_numeric(u.kind())) {
      out.assign(n, u.as_double());
    } else {
      for (const auto& e : u.elements()) out.push_back(e.unwrapped().as_double());
    }
  } catch (const ProtocolError&) {
    throw MethodFailure(std::string(what) + ": expected a number or a list of numbers, got '" +
                        u.signature() + "'");
  }
  if (out.size() != n) {
    throw MethodFailure(std::string(what) + ": " + std::to_string(n) + " names but " +
                        std::to_string(out.size()) + " values");
  }
  return out;
}

std::vector<std::string> expand_joint_group(const std::vector<std::string>& names) {
  std::vector<std::string> out;
  for (const auto& n : names) {
    if (n == "Head") {
      out.insert(out.end(), {"HeadYaw", "HeadPitch"});
    } else if (n == "Leg") {
      out.insert(out.end(), {"HipRoll", "HipPitch", "KneePitch"});
    } else if (n == "Body" || n == "JointActuators" || n == "Joints") {
      out.insert(out.end(), {"HeadYaw", "HeadPitch", "HipRoll", "HipPitch", "KneePitch"});
    } else {
      out.push_back(n);
    }
  }
  return out;
}

struct Subscription {
  int camera = 0;
  int resolution = 2;
  int color_space = 0;
  int fps = 30;
  std::chrono::steady_clock::time_point next_frame{};  ///< pace_frames: earliest next capture
};

std::pair<int, int> resolution_size(int code) {
  switch (code) {
    case 8:
      return {40, 30};
    case 7:
      return {80, 60};
    case 0:
      return {160, 120};
    case 1:
      return {320, 240};
    case 2:
      return {640, 480};
    case 3:
      return {1280, 960};
    default:
      throw MethodFailure("ALVideoDevice: unsupported resolution " + std::to_string(code));
  }
}

int layers_for(int color_space) {
  switch (color_space) {
    case 0:
      return 1;
    case 9:
      return 2;
    case 10:
    case 11:
    case 12:
    case 13:
      return 3;
    default:
      throw MethodFailure("ALVideoDevice: unsupported color space " + std::to_string(color_space));
  }
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw BridgeError("cannot read '" + path + "'");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}


void json_string(std::ostream& out, const std::string& text) {
  out << '"';
  for (const unsigned char ch : text) {
    switch (ch) {
      case '"':
        out << "\\\"";
        break;
      case '\\':
        out << "\\\\";
        break;
      case '\n':
        out << "\\n";
        break;
      default:
        if (ch < 0x20 || ch >= 0x7f) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", ch);
          out << buf;
        } else {
          out << static_cast<char>(ch);
        }
    }
  }
  out << '"';
}

/// A received argument as JSON: numbers, booleans, strings and lists as such; raw buffers by
/// size; anything else as its debug rendering.
void json_value(std::ostream& out, const Value& v, int depth = 0) {
  const Value& u = v.unwrapped();
  const TypeKind k = u.kind();
  if (k == TypeKind::kBool) {
    out << (u.as_bool() ? "true" : "false");
  } else if (is_numeric(k)) {
    const double d = u.as_double();
    if (std::isfinite(d)) {
      char buf[40];
      std::snprintf(buf, sizeof buf, "%.9g", d);
      out << buf;
    } else {
      json_string(out, std::isnan(d) ? "nan" : (d > 0 ? "inf" : "-inf"));
    }
  } else if (k == TypeKind::kString) {
    json_string(out, u.as_string());
  } else if (k == TypeKind::kRaw) {
    json_string(out, "<" + std::to_string(u.as_raw().size) + " bytes>");
  } else if ((k == TypeKind::kList || k == TypeKind::kTuple || k == TypeKind::kVarArgs) &&
             depth < 4) {
    out << '[';
    bool first = true;
    for (const auto& e : u.elements()) {
      if (!first) out << ',';
      first = false;
      json_value(out, e, depth + 1);
    }
    out << ']';
  } else {
    json_string(out, u.to_debug_string());
  }
}

double unix_time_s() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

struct MockNaoqiServer::Impl : std::enable_shared_from_this<MockNaoqiServer::Impl> {
  sim::SimRobot& robot;
  MockServerOptions options;
  asio::io_context io;
  std::optional<asio::executor_work_guard<asio::io_context::executor_type>> work;
  std::thread thread;
  std::unique_ptr<asio::ssl::context> ssl_ctx;
  std::unique_ptr<tcp::acceptor> acceptor;
  Url url;
  std::string fingerprint;
  bool running = false;

  // Everything below is touched on the I/O thread, plus the mutex for test accessors.
  mutable std::mutex mutex;
  std::map<std::uint32_t, ServiceDef> services;  // by id
  std::map<std::string, std::uint32_t> service_ids;
  std::set<std::shared_ptr<ConnState>> conns;
  /// TLS connections still in their handshake, with their accept time.
  std::map<std::shared_ptr<detail::MessageConnection>, std::chrono::steady_clock::time_point>
      handshaking;
  std::unique_ptr<asio::steady_timer> sweep_timer;
  std::map<std::string, Subscription> subscriptions;
  std::map<std::string, double> stiffness;
  std::string life_state = "solitary";
  bool awareness_enabled = true;
  bool awareness_paused = false;
  bool collision_protection = true;
  bool awake = true;
  bool charging = false;
  int battery_percent = 87;
  std::string naoqi_version;
  /// Robot-state hooks: a move failure in force (its cause), and Autonomous Life holding the
  /// head (the yaw it tracks; sticky: setState/setEnabled cannot turn it off).
  std::string move_failure_cause;
  std::optional<Value> move_failed_event;  ///< ALMemory "ALMotion/MoveFailed", once raised
  bool head_taken = false;
  bool head_taken_sticky = false;
  double tracked_head_yaw_rad = 0.0;
  std::string posture = "Stand";
  BaseVelocity last_velocity;  ///< what the base executes now (getRobotVelocity, moveIsActive)
  /// The time-constrained moveTo in progress: NAOqi answers the Call when the move ends (it
  /// reached its pose, or another motion command replaced it), and the base stops by itself at
  /// the end whether or not the client is still there.
  struct BoundedMove {
    std::shared_ptr<asio::steady_timer> timer;
    std::weak_ptr<ConnState> caller;
    MessageHeader call;
    bool post = false;
  };
  std::optional<BoundedMove> bounded_move;  // I/O thread only
  std::ofstream call_log;                    // --log: one JSON line per call (I/O thread only)
  std::chrono::milliseconds latency{0};
  bool stall_frames = false;
  std::uint64_t image_requests = 0;
  std::uint64_t replies = 0;
  std::map<std::string, ImageRemote> last_image;  // per handle, for frame drops
  Stats stats;

  Impl(sim::SimRobot& r, MockServerOptions o) : robot(r), options(std::move(o)) {
    latency = options.reply_latency;
    const MockRobotState& st = options.robot_state;
    life_state = st.autonomous_life;
    // Autonomous Life's abilities follow its state (BasicAwareness is on in solitary and
    // interactive, off in disabled: NAOqi's autonomous abilities table).
    awareness_enabled = st.autonomous_life == "solitary" || st.autonomous_life == "interactive";
    collision_protection = st.collision_protection;
    awake = st.awake;
    charging = st.charging;
    battery_percent = st.battery_percent;
    naoqi_version = st.naoqi_version;
    build_services();
    for (const auto& name : st.missing_services) {
      auto it = service_ids.find(name);
      if (it == service_ids.end()) continue;
      services.erase(it->second);
      service_ids.erase(it);
    }
  }

  /// Why the base cannot execute a move now ("" when it can), under the mutex: resting motors,
  /// the charger plugged (power hatch open) or an injected failure (an obstacle).
  std::string move_refusal_locked() const {
    if (!move_failure_cause.empty()) return move_failure_cause;
    if (!awake) return "robot is not awake (rest): motors off";
    if (charging) return "power hatch open: locomotion is prohibited while charging";
    return {};
  }

  /// A move NAOqi did not execute: the base stays still and ALMemory's ALMotion/MoveFailed holds
  /// [cause, status, position], as NAOqi raises it when a move is not launched or is stopped.
  void refuse_move(const std::string& cause) {
    end_bounded_move(false);
    robot.stop_move();
    const core::OdometryPose p = robot.odometry(sim::OdometrySource::kCommands);
    std::lock_guard lock(mutex);
    last_velocity = {};
    move_failed_event = Value::list(
        Type::of(TypeKind::kDynamic),
        {Value::dynamic(Value::string(cause)), Value::dynamic(Value::int32(1)),
         Value::dynamic(Value::floats({static_cast<float>(p.x_m), static_cast<float>(p.y_m),
                                       static_cast<float>(p.yaw_rad)}))});
    log_event("move failed: " + cause);
  }

  /// Autonomous Life holding the head: put it back on the tracked person.
  void hold_tracked_head_locked() {
    if (head_taken && awareness_enabled) {
      robot.set_joint_angles({"HeadYaw"}, {tracked_head_yaw_rad});
    }
  }

  // -------------------------------------------------------------------------------------------
  // Service tables (PROTOCOL.md 2, 4, 7)

  void add_generic(ServiceDef& s) {
    s.add(0, "registerEvent", "(IIL)", "L",
          [](ConnState&, const std::vector<Value>& a) {
            return Value::uint64((static_cast<std::uint64_t>(a[1].as_uint()) << 32) | 1u);
          },
          {"objectId", "signalId", "linkId"});
    s.add(1, "unregisterEvent", "(IIL)", "v",
          [](ConnState&, const std::vector<Value>&) { return Value(); });
    const std::uint32_t id = s.id;
    s.add(2, "metaObject", "(I)", MetaObject::signature(),
          [this, id](ConnState&, const std::vector<Value>&) {
            std::lock_guard lock(mutex);
            return services.at(id).meta().to_value();
          },
          {"objectId"});
    s.add(3, "terminate", "(I)", "v",
          [](ConnState&, const std::vector<Value>&) { return Value(); });
    s.add(5, "property", "(m)", "m", [](ConnState&, const std::vector<Value>& a) -> Value {
      throw MethodFailure("property: no such property " + a[0].to_debug_string());
    });
    s.add(6, "setProperty", "(mm)", "v", [](ConnState&, const std::vector<Value>& a) -> Value {
      throw MethodFailure("setProperty: no such property " + a[0].to_debug_string());
    });
    s.add(7, "properties", "()", "[s]",
          [](ConnState&, const std::vector<Value>&) { return Value::strings({}); });
    s.add(8, "registerEventWithSignature", "(IILs)", "L",
          [](ConnState&, const std::vector<Value>& a) {
            return Value::uint64((static_cast<std::uint64_t>(a[1].as_uint()) << 32) | 1u);
          });
  }

  ServiceDef& new_service(const std::string& name, std::uint32_t id) {
    ServiceDef& s = services[id];
    s.name = name;
    s.id = id;
    service_ids[name] = id;
    add_generic(s);
    return s;
  }

  ServiceInfo info_of(const ServiceDef& s) const {
    ServiceInfo info;
    info.name = s.name;
    info.service_id = s.id;
    info.machine_id = "5e1f0a7c-mock-pepper";
    info.process_id = 4242;
    info.endpoints = {url.to_string()};
    info.session_id = "a1b2c3d4-mock-session";
    if (!options.legacy_service_info) info.object_uid = std::string(20, '\x07');
    return info;
  }

  void build_services() {
    using A = const std::vector<Value>&;
    ServiceDef& dir = new_service("ServiceDirectory", 1);
    const std::string info_sig =
        options.legacy_service_info ? ServiceInfo::signature_v6() : ServiceInfo::signature_v7();
    dir.add(100, "service", "(s)", info_sig,
            [this](ConnState&, A a) {
              std::lock_guard lock(mutex);
              auto it = service_ids.find(a[0].as_string());
              if (it == service_ids.end()) {
                throw MethodFailure("Cannot find service '" + a[0].as_string() + "' in index");
              }
              return info_of(services.at(it->second)).to_value();
            },
            {"name"});
    dir.add(101, "services", "()", "[" + info_sig + "]", [this, info_sig](ConnState&, A) {
      std::lock_guard lock(mutex);
      std::vector<Value> all;
      for (const auto& [id, s] : services) all.push_back(info_of(s).to_value());
      if (all.empty()) return Value::list(parse_signature(info_sig), {});
      const Type t = all.front().type();
      return Value::list(t, std::move(all));
    });
    dir.add(108, "machineId", "()", "s",
            [](ConnState&, A) { return Value::string("5e1f0a7c-mock-pepper"); });
    dir.signals[106] = {106, "serviceAdded", "(Is)"};
    dir.signals[107] = {107, "serviceRemoved", "(Is)"};

    auto module_version = [this](ServiceDef& s) {
      // ALModule::version (uid 103 in NAOqi 2.5's ALModule methods): the NAOqi version.
      s.add(103, "version", "()", "s",
            [this](ConnState&, A) { return Value::string(naoqi_version); });
    };

    // ALMotion (7.1)
    ServiceDef& motion = new_service("ALMotion", 2);
    module_version(motion);
    motion.add(113, "wakeUp", "()", "v", [this](ConnState&, A) {
      std::lock_guard lock(mutex);
      awake = true;
      return Value();
    });
    // (real 2.5 robots: rest and wakeUp also stiffen/relax the body; the mock tracks awake only)
    motion.add(114, "rest", "()", "v", [this](ConnState&, A) {
      end_bounded_move(false);
      robot.stop_move();
      std::lock_guard lock(mutex);
      last_velocity = {};
      awake = false;
      return Value();
    });
    motion.add(122, "robotIsWakeUp", "()", "b", [this](ConnState&, A) {
      std::lock_guard lock(mutex);
      return Value::boolean(awake);
    });
    motion.add(124, "setStiffnesses", "(mm)", "v",
               [this](ConnState&, A a) {
                 const auto names = expand_joint_group(names_arg(a[0], "ALMotion::setStiffnesses"));
                 const Value& u = a[1].unwrapped();
                 std::vector<double> values =
                     is_numeric(u.kind()) ? std::vector<double>(names.size(), u.as_double())
                                          : floats_arg(a[1], u.elements().size(), "setStiffnesses");
                 if (values.size() != names.size()) {
                   // A list given for a group name: libqi broadcasts per joint only when sizes
                   // agree.
                   throw MethodFailure("ALMotion::setStiffnesses: " + std::to_string(names.size()) +
                                       " joints but " + std::to_string(values.size()) + " values");
                 }
                 std::lock_guard lock(mutex);
                 for (std::size_t i = 0; i < names.size(); ++i) stiffness[names[i]] = values[i];
                 return Value();
               },
               {"names", "stiffnesses"});
    motion.add(126, "getStiffnesses", "(m)", "[f]",
               [this](ConnState&, A a) {
                 const auto names = expand_joint_group(names_arg(a[0], "ALMotion::getStiffnesses"));
                 std::lock_guard lock(mutex);
                 std::vector<float> out;
                 for (const auto& n : names) out.push_back(static_cast<float>(stiffness[n]));
                 return Value::floats(out);
               },
               {"names"});
    motion.add(130, "setAngles", "(mmf)", "v",
               [this](ConnState&, A a) {
                 const auto names = expand_joint_group(names_arg(a[0], "ALMotion::setAngles"));
                 const auto angles = floats_arg(a[1], names.size(), "ALMotion::setAngles");
                 try {
                   robot.set_joint_angles(names, angles);
                 } catch (const sim::SimError& e) {
                   throw MethodFailure(std::string("ALMotion::setAngles: ") + e.what());
                 }
                 std::lock_guard lock(mutex);
                 hold_tracked_head_locked();  // awareness outranks the client while it is on
                 return Value();
               },
               {"names", "angles", "fractionMaxSpeed"});
    motion.add(132, "getAngles", "(mb)", "[f]",
               [this](ConnState&, A a) {
                 const auto names = expand_joint_group(names_arg(a[0], "ALMotion::getAngles"));
                 std::vector<double> angles;
                 try {
                   angles = robot.joint_angles(names);
                 } catch (const sim::SimError& e) {
                   throw MethodFailure(std::string("ALMotion::getAngles: ") + e.what());
                 }
                 std::vector<float> out(angles.begin(), angles.end());
                 return Value::floats(out);
               },
               {"names", "useSensors"});
    auto do_move = [this](ConnState& c, double x, double y, double theta) {
      if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(theta)) {
        // NAOqi refuses such a command; the base keeps what it was doing.
        throw MethodFailure("ALMotion::move: non-finite velocity (" + std::to_string(x) + ", " +
                            std::to_string(y) + ", " + std::to_string(theta) + ")");
      }
      c.commanded_base = true;
      std::string refusal;
      {
        std::lock_guard lock(mutex);
        refusal = move_refusal_locked();
      }
      if (!refusal.empty() && (x != 0.0 || y != 0.0 || theta != 0.0)) {
        refuse_move(refusal);  // answered like any move: the failure shows only on the robot
        return Value();
      }
      end_bounded_move(false);  // a new velocity replaces a moveTo in progress
      BaseVelocity v{x, y, theta};
      robot.command_velocity(v);
      std::lock_guard lock(mutex);
      last_velocity = v;
      return Value();
    };
    motion.add(135, "move", "(fff)", "v",
               [do_move](ConnState& c, A a) {
                 return do_move(c, a[0].as_double(), a[1].as_double(), a[2].as_double());
               },
               {"x", "y", "theta"});
    motion.add(136, "move", "(fffm)", "v",
               [do_move](ConnState& c, A a) {
                 return do_move(c, a[0].as_double(), a[1].as_double(), a[2].as_double());
               },
               {"x", "y", "theta", "moveConfig"});
    motion.add(137, "moveToward", "(fff)", "v",
               [do_move](ConnState& c, A a) {
                 return do_move(c, 0.35 * a[0].as_double(), 0.35 * a[1].as_double(),
                                1.0 * a[2].as_double());
               },
               {"x", "y", "theta"});
    // moveTo(x, y, theta, time) is answered by bounded_move() (the reply comes when it ends).
    motion.add(144, "moveTo", "(ffff)", "v",
               [](ConnState&, A) -> Value { throw MethodFailure("unreachable"); },
               {"x", "y", "theta", "time"});
    motion.add(175, "moveIsActive", "()", "b", [this](ConnState&, A) {
      std::lock_guard lock(mutex);
      return Value::boolean(last_velocity.v_x_m_s != 0.0 || last_velocity.v_y_m_s != 0.0 ||
                            last_velocity.omega_rad_s != 0.0);
    });
    motion.add(177, "stopMove", "()", "v", [this](ConnState&, A) {
      end_bounded_move(false);
      robot.stop_move();
      std::lock_guard lock(mutex);
      last_velocity = {};
      return Value();
    });
    // useSensors = true: the simulated wheel odometry (drifts); false: the commanded motion
    // integrated, as NAOqi answers (PROTOCOL.md 7.1). [x, y, theta] in the odometry frame.
    motion.add(180, "getRobotPosition", "(b)", "[f]",
               [this](ConnState&, A a) {
                 const core::OdometryPose p =
                     robot.odometry(a[0].as_bool() ? sim::OdometrySource::kWheels
                                                   : sim::OdometrySource::kCommands);
                 return Value::floats({static_cast<float>(p.x_m), static_cast<float>(p.y_m),
                                       static_cast<float>(p.yaw_rad)});
               },
               {"useSensors"});
    // getNextRobotPosition: where the base ends if stopMove is called now (NAOqi: the position
    // that can no longer be changed; equal to getRobotPosition(false) when not moving). The mock
    // brakes the executed velocity at ALMotion's default MaxAccXY 0.3 m/s^2 and MaxAccTheta
    // 0.75 rad/s^2 (../shared/design/PEPPER.md) from the commanded-motion pose.
    motion.add(181, "getNextRobotPosition", "()", "[f]", [this](ConnState&, A) {
      const core::OdometryPose p = robot.odometry(sim::OdometrySource::kCommands);
      BaseVelocity v;
      {
        std::lock_guard lock(mutex);
        v = last_velocity;
      }
      constexpr double kAccXy = 0.3, kAccTheta = 0.75;
      const double speed = std::hypot(v.v_x_m_s, v.v_y_m_s);
      const double brake_m = speed * speed / (2.0 * kAccXy);
      const double turn_rad =
          std::copysign(v.omega_rad_s * v.omega_rad_s / (2.0 * kAccTheta), v.omega_rad_s);
      double x = p.x_m, y = p.y_m;
      if (speed > 0.0) {
        // Direction of travel in the odometry frame, taken at mid-turn (a short arc).
        const double heading = p.yaw_rad + std::atan2(v.v_y_m_s, v.v_x_m_s) + 0.5 * turn_rad;
        x += brake_m * std::cos(heading);
        y += brake_m * std::sin(heading);
      }
      return Value::floats({static_cast<float>(x), static_cast<float>(y),
                            static_cast<float>(p.yaw_rad + turn_rad)});
    });
    motion.add(183, "getRobotVelocity", "()", "[f]", [this](ConnState&, A) {
      std::lock_guard lock(mutex);
      return Value::floats({static_cast<float>(last_velocity.v_x_m_s),
                            static_cast<float>(last_velocity.v_y_m_s),
                            static_cast<float>(last_velocity.omega_rad_s)});
    });
    motion.add(229, "setExternalCollisionProtectionEnabled", "(sb)", "v",
               [this](ConnState&, A a) {
                 std::lock_guard lock(mutex);
                 if (a[0].as_string() == "All" || a[0].as_string() == "Move")
                   collision_protection = a[1].as_bool();
                 return Value();
               },
               {"name", "enable"});
    motion.add(232, "getExternalCollisionProtectionEnabled", "(s)", "b",
               [this](ConnState&, A) {
                 std::lock_guard lock(mutex);
                 return Value::boolean(collision_protection);
               },
               {"name"});

    // ALVideoDevice (7.2)
    ServiceDef& video = new_service("ALVideoDevice", 3);
    auto subscribe = [this](const std::string& name, int cam, int res, int cs, int fps) {
      (void)resolution_size(res);
      (void)layers_for(cs);
      std::lock_guard lock(mutex);
      for (int n = 0; n < 6; ++n) {
        const std::string handle = name + "_" + std::to_string(n);
        if (!subscriptions.count(handle)) {
          Subscription sub;
          sub.camera = cam;
          sub.resolution = res;
          sub.color_space = cs;
          sub.fps = fps;
          subscriptions[handle] = sub;
          return Value::string(handle);
        }
      }
      throw MethodFailure("ALVideoDevice::subscribeCamera: too many instances of '" + name +
                          "' (6); unsubscribe the old ones");
    };
    video.add(113, "subscribeCamera", "(siiii)", "s",
              [subscribe](ConnState&, A a) {
                return subscribe(a[0].as_string(), static_cast<int>(a[1].as_int()),
                                 static_cast<int>(a[2].as_int()), static_cast<int>(a[3].as_int()),
                                 static_cast<int>(a[4].as_int()));
              },
              {"name", "cameraIndex", "resolution", "colorSpace", "fps"});
    video.add(191, "subscribe", "(siii)", "s",
              [subscribe](ConnState&, A a) {
                return subscribe(a[0].as_string(), 0, static_cast<int>(a[1].as_int()),
                                 static_cast<int>(a[2].as_int()), static_cast<int>(a[3].as_int()));
              },
              {"name", "resolution", "colorSpace", "fps"});
    video.add(115, "unsubscribe", "(s)", "b",
              [this](ConnState&, A a) {
                std::lock_guard lock(mutex);
                last_image.erase(a[0].as_string());
                return Value::boolean(subscriptions.erase(a[0].as_string()) > 0);
              },
              {"nameId"});
    video.add(119, "setActiveCamera", "(i)", "b",
              [](ConnState&, A) { return Value::boolean(true); });
    video.add(149, "setResolution", "(si)", "b", [this](ConnState&, A a) {
      (void)resolution_size(static_cast<int>(a[1].as_int()));
      std::lock_guard lock(mutex);
      auto it = subscriptions.find(a[0].as_string());
      if (it == subscriptions.end()) return Value::boolean(false);
      it->second.resolution = static_cast<int>(a[1].as_int());
      return Value::boolean(true);
    });
    video.add(151, "setColorSpace", "(si)", "b", [this](ConnState&, A a) {
      (void)layers_for(static_cast<int>(a[1].as_int()));
      std::lock_guard lock(mutex);
      auto it = subscriptions.find(a[0].as_string());
      if (it == subscriptions.end()) return Value::boolean(false);
      it->second.color_space = static_cast<int>(a[1].as_int());
      return Value::boolean(true);
    });
    // getImageRemote (162) is answered by serve_image() (encoded directly, no Value tree).
    video.add(162, "getImageRemote", "(s)", "m",
              [](ConnState&, A) -> Value { throw MethodFailure("unreachable"); }, {"name"});
    video.add(163, "releaseImage", "(s)", "b", [](ConnState&, A) { return Value::boolean(true); });

    // ALRobotPosture (7.3)
    ServiceDef& posture_svc = new_service("ALRobotPosture", 4);
    auto go = [this](ConnState&, A a) {
      const std::string p = a[0].as_string();
      if (p != "Stand" && p != "StandInit" && p != "StandZero" && p != "Crouch") {
        return Value::boolean(false);
      }
      std::lock_guard lock(mutex);
      posture = p;
      return Value::boolean(true);
    };
    posture_svc.add(114, "goToPosture", "(sf)", "b", go, {"postureName", "maxSpeedFraction"});
    posture_svc.add(115, "applyPosture", "(sf)", "b", go, {"postureName", "maxSpeedFraction"});
    posture_svc.add(116, "stopMove", "()", "v", [](ConnState&, A) { return Value(); });
    posture_svc.add(120, "getPosture", "()", "s", [this](ConnState&, A) {
      std::lock_guard lock(mutex);
      return Value::string(posture);
    });

    // ALAutonomousLife
    ServiceDef& life = new_service("ALAutonomousLife", 5);
    life.add(126, "setState", "(s)", "v",
             [this](ConnState&, A a) {
               const std::string s = a[0].as_string();
               if (s != "solitary" && s != "interactive" && s != "disabled" && s != "safeguard") {
                 throw MethodFailure("ALAutonomousLife::setState: invalid state '" + s + "'");
               }
               std::lock_guard lock(mutex);
               if (head_taken_sticky && s == "disabled") return Value();  // re-enabled at once
               // Entering a state resets the autonomous abilities (BasicAwareness on in
               // solitary and interactive, off in disabled).
               if (s != life_state) awareness_enabled = s == "solitary" || s == "interactive";
               life_state = s;
               if (s == "disabled") head_taken = false;
               return Value();
             },
             {"state"});
    life.add(127, "getState", "()", "s", [this](ConnState&, A) {
      std::lock_guard lock(mutex);
      return Value::string(life_state);
    });

    // ALBasicAwareness
    ServiceDef& aware = new_service("ALBasicAwareness", 6);
    aware.add(126, "setEnabled", "(b)", "v",
              [this](ConnState&, A a) {
                std::lock_guard lock(mutex);
                if (head_taken_sticky && !a[0].as_bool()) return Value();  // re-enabled at once
                awareness_enabled = a[0].as_bool();
                if (!awareness_enabled) head_taken = false;
                return Value();
              },
              {"enabled"});
    aware.add(127, "isEnabled", "()", "b", [this](ConnState&, A) {
      std::lock_guard lock(mutex);
      return Value::boolean(awareness_enabled);
    });
    aware.add(132, "pauseAwareness", "()", "v", [this](ConnState&, A) {
      std::lock_guard lock(mutex);
      awareness_paused = true;
      return Value();
    });
    aware.add(133, "resumeAwareness", "()", "v", [this](ConnState&, A) {
      std::lock_guard lock(mutex);
      awareness_paused = false;
      return Value();
    });
    aware.add(134, "isAwarenessPaused", "()", "b", [this](ConnState&, A) {
      std::lock_guard lock(mutex);
      return Value::boolean(awareness_paused);
    });
    aware.add(140, "setEngagementMode", "(s)", "v", [](ConnState&, A) { return Value(); });
    aware.add(143, "setTrackingMode", "(s)", "v", [](ConnState&, A) { return Value(); });

    // ALSystem (NAOqi 2.5 ALSystem API: systemVersion() -> string, uid 119)
    ServiceDef& system = new_service("ALSystem", 7);
    module_version(system);
    system.add(119, "systemVersion", "()", "s",
               [this](ConnState&, A) { return Value::string(naoqi_version); });

    // ALBattery (getBatteryCharge() -> int, percent)
    ServiceDef& battery = new_service("ALBattery", 8);
    module_version(battery);
    battery.add(114, "getBatteryCharge", "()", "i", [this](ConnState&, A) {
      std::lock_guard lock(mutex);
      return Value::int32(battery_percent);
    });

    // ALMemory.getData(key) -> any, for the keys doctor and the bridge read (docs/mock_robot.md)
    ServiceDef& memory = new_service("ALMemory", 9);
    module_version(memory);
    memory.add(
        124, "getData", "(s)", "m",
        [this](ConnState&, A a) -> Value {
          const std::string key = a[0].as_string();
          std::lock_guard lock(mutex);
          if (key == "Device/SubDeviceList/Battery/Charge/Sensor/Value") {
            return Value::float32(static_cast<float>(battery_percent / 100.0));
          }
          if (key == "Device/SubDeviceList/Battery/Current/Sensor/Value") {
            // Amperes into the battery: positive while charging, negative while discharging.
            return Value::float32(charging ? 1.6f : -0.9f);
          }
          if (key == "BatteryPowerPluggedChanged") return Value::boolean(charging);
          if (key == "ALMotion/MoveFailed" && move_failed_event) return *move_failed_event;
          throw MethodFailure("ALMemory::getData: key '" + key + "' not found");
        },
        {"key"});
  }

  // -------------------------------------------------------------------------------------------
  // Call log (MockServerOptions::call_log_file): one JSON object per line, flushed at once so a
  // test or an operator can follow it live.

  void log_line(const std::string& body) {
    if (!call_log.is_open()) return;
    char t[32];
    std::snprintf(t, sizeof t, "%.6f", unix_time_s());
    call_log << "{\"t_unix_s\":" << t << "," << body << "}\n" << std::flush;
  }

  void log_call(const std::string& service, const std::string& method,
                const std::vector<Value>& args) {
    if (!call_log.is_open()) return;
    std::ostringstream b;
    b << "\"service\":";
    json_string(b, service);
    b << ",\"method\":";
    json_string(b, method);
    b << ",\"args\":[";
    for (std::size_t i = 0; i < args.size(); ++i) {
      if (i) b << ',';
      json_value(b, args[i]);
    }
    b << ']';
    log_line(b.str());
  }

  void log_event(const std::string& what) {
    if (!call_log.is_open()) return;
    std::ostringstream b;
    b << "\"event\":";
    json_string(b, what);
    log_line(b.str());
  }

  // -------------------------------------------------------------------------------------------
  // Networking

  void start() {
    const auto errors = options.validate();
    if (!errors.empty()) throw BridgeError("MockServerOptions: " + errors.front());
    url = parse_url(options.listen_url);
    if (!options.call_log_file.empty()) {
      call_log.open(options.call_log_file, std::ios::out | std::ios::app);
      if (!call_log) {
        throw BridgeError("mock server: cannot write the call log '" + options.call_log_file + "'");
      }
    }
    if (url.tls) {
      ssl_ctx = std::make_unique<asio::ssl::context>(asio::ssl::context::tls_server);
      ssl_ctx->set_options(asio::ssl::context::default_workarounds | asio::ssl::context::no_sslv2 |
                           asio::ssl::context::no_sslv3 | asio::ssl::context::no_tlsv1 |
                           asio::ssl::context::no_tlsv1_1);
      // libqi servers speak TLS 1.2 only (PROTOCOL.md 9): do the same.
      SSL_CTX_set_max_proto_version(ssl_ctx->native_handle(), TLS1_2_VERSION);
      std::string cert_pem;
      std::string key_pem;
      if (options.tls_certificate_file.empty()) {
        auto ss = detail::make_self_signed_certificate("mock-pepper");
        cert_pem = std::move(ss.certificate_pem);
        key_pem = std::move(ss.private_key_pem);
      } else {
        cert_pem = read_file(options.tls_certificate_file);
        key_pem = read_file(options.tls_private_key_file);
      }
      try {
        ssl_ctx->use_certificate_chain(asio::buffer(cert_pem));
        ssl_ctx->use_private_key(asio::buffer(key_pem), asio::ssl::context::pem);
      } catch (const std::exception& e) {
        throw BridgeError(std::string("mock server: bad TLS certificate or key: ") + e.what());
      }
      fingerprint = detail::certificate_sha256_pem(cert_pem);
    }
    try {
      tcp::resolver resolver(io);
      auto results = resolver.resolve(url.host, std::to_string(url.port));
      const tcp::endpoint ep = *results.begin();
      acceptor = std::make_unique<tcp::acceptor>(io);
      acceptor->open(ep.protocol());
      acceptor->set_option(tcp::acceptor::reuse_address(true));
      acceptor->bind(ep);
      acceptor->listen();
      url.port = acceptor->local_endpoint().port();
    } catch (const boost::system::system_error& e) {
      throw BridgeError("mock server: cannot listen on " + options.listen_url + ": " + e.what());
    }
    work.emplace(asio::make_work_guard(io));
    accept_next();
    sweep_timer = std::make_unique<asio::steady_timer>(io);
    sweep_next();
    thread = std::thread([this] { io.run(); });
    running = true;
  }

  void stop() {
    if (!running) return;
    running = false;
    // Raw `this` in the I/O handlers is safe: the thread is joined here, before Impl dies.
    asio::post(io, [this] {
      boost::system::error_code ignored;
      if (acceptor) acceptor->close(ignored);
      if (sweep_timer) sweep_timer->cancel();
      if (bounded_move) bounded_move->timer->cancel();
      std::map<std::shared_ptr<detail::MessageConnection>, std::chrono::steady_clock::time_point>
          pending;
      {
        std::lock_guard lock(mutex);
        pending.swap(handshaking);
      }
      for (auto& [conn, at] : pending) conn->socket().close(ignored);
      std::set<std::shared_ptr<ConnState>> all;
      {
        std::lock_guard lock(mutex);
        all = conns;
      }
      for (const auto& c : all) c->conn->close("server stopping");
      work.reset();  // run() returns once the closes have completed
    });
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    while (!io.stopped() && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    io.stop();
    if (thread.joinable()) thread.join();
  }

  void accept_next() {
    auto conn = std::make_shared<detail::MessageConnection>(io, ssl_ctx.get(), options.limits);
    acceptor->async_accept(conn->socket(), [this, conn](const boost::system::error_code& ec) {
      Impl* const self = this;
      if (ec) {
        if (ec == asio::error::operation_aborted || !self->acceptor->is_open()) return;
        if (ec == asio::error::connection_aborted) {  // reset while queued: next one at once
          self->accept_next();
          return;
        }
        // Out of descriptors (EMFILE) or similar: try again a little later instead of spinning.
        auto retry = std::make_shared<asio::steady_timer>(io, std::chrono::milliseconds(100));
        retry->async_wait([self, retry](const boost::system::error_code& e) {
          if (!e && self->acceptor->is_open()) self->accept_next();
        });
        return;
      }
      boost::system::error_code ignored;
      bool full = false;
      {
        std::lock_guard lock(mutex);
        full = conns.size() + handshaking.size() >=
               static_cast<std::size_t>(options.max_connections);
        if (full) ++stats.connections_refused;
      }
      if (full) {
        conn->socket().close(ignored);  // at the limit: refuse at once, keep accepting
        self->accept_next();
        return;
      }
      conn->socket().set_option(tcp::no_delay(true), ignored);
      if (conn->tls()) {
        {
          std::lock_guard lock(mutex);
          handshaking[conn] = std::chrono::steady_clock::now();
        }
        conn->tls()->async_handshake(asio::ssl::stream_base::server,
                                     [self, conn](const boost::system::error_code& ec2) {
                                       bool timed_out = false;
                                       {
                                         std::lock_guard lock(self->mutex);
                                         timed_out = self->handshaking.erase(conn) == 0;
                                       }
                                       if (ec2 || timed_out) {
                                         boost::system::error_code ig;
                                         conn->socket().close(ig);
                                         return;
                                       }
                                       self->begin(conn);
                                     });
      } else {
        self->begin(conn);
      }
      self->accept_next();
    });
  }

  /// Closes connections that stay silent: no TLS handshake and login within handshake_timeout,
  /// or no message for idle_timeout. Runs on the I/O thread every sweep period.
  void sweep_next() {
    if (!sweep_timer) return;
    sweep_timer->expires_after(sweep_period());
    sweep_timer->async_wait([this](const boost::system::error_code& ec) {
      if (ec) return;
      const auto now = std::chrono::steady_clock::now();
      std::vector<std::shared_ptr<detail::MessageConnection>> late_handshakes;
      std::vector<std::pair<std::shared_ptr<ConnState>, std::string>> to_close;
      {
        std::lock_guard lock(mutex);
        for (auto it = handshaking.begin(); it != handshaking.end();) {
          if (options.handshake_timeout.count() > 0 &&
              now - it->second > options.handshake_timeout) {
            late_handshakes.push_back(it->first);
            it = handshaking.erase(it);
            ++stats.connections_timed_out;
          } else {
            ++it;
          }
        }
        for (const auto& c : conns) {
          if (!c->authenticated && options.handshake_timeout.count() > 0 &&
              now - c->accepted_at > options.handshake_timeout) {
            to_close.emplace_back(c, "no login within the handshake timeout");
          } else if (options.idle_timeout.count() > 0 &&
                     now - c->last_message_at > options.idle_timeout) {
            to_close.emplace_back(c, "idle timeout");
          }
        }
        stats.connections_timed_out += to_close.size();
      }
      boost::system::error_code ignored;
      for (auto& conn : late_handshakes) conn->socket().close(ignored);
      for (auto& [c, why] : to_close) c->conn->close(why);
      sweep_next();
    });
  }

  std::chrono::milliseconds sweep_period() const {
    std::chrono::milliseconds p{1000};
    for (const auto t : {options.handshake_timeout, options.idle_timeout}) {
      if (t.count() > 0) p = std::min(p, t / 4);
    }
    return std::max(p, std::chrono::milliseconds(10));
  }

  void begin(const std::shared_ptr<detail::MessageConnection>& conn) {
    auto state = std::make_shared<ConnState>();
    state->conn = conn;
    state->self = state;
    state->accepted_at = std::chrono::steady_clock::now();
    state->last_message_at = state->accepted_at;
    {
      std::lock_guard lock(mutex);
      conns.insert(state);
      ++stats.connections_accepted;
      stats.connections_open = conns.size();
    }
    std::weak_ptr<Impl> weak = shared_from_this();
    std::weak_ptr<ConnState> wstate = state;
    if (options.announce_capabilities) {
      CapabilityMap caps;
      caps["MessageFlags"] = Value::boolean(true);
      caps["MockAnnounced"] = Value::boolean(true);
      MessageHeader h;
      h.id = 1;
      h.type = MessageType::kCapability;
      conn->send(h, encode_capabilities(caps));
    }
    conn->start(
        [weak, wstate](Message m) {
          auto self = weak.lock();
          auto st = wstate.lock();
          if (self && st) self->on_message(*st, std::move(m));
        },
        [weak, state](const std::string&) {
          if (auto self = weak.lock()) self->on_close(state);
        });
  }

  void on_close(const std::shared_ptr<ConnState>& state) {
    const bool stop_base = options.stop_base_on_disconnect && state->commanded_base;
    {
      std::lock_guard lock(mutex);
      conns.erase(state);
      stats.connections_open = conns.size();
      if (stop_base) ++stats.base_stops_on_disconnect;
    }
    if (stop_base) {
      // Only with the option: a real NAOqi keeps the last velocity when its client goes away.
      end_bounded_move(false);
      robot.stop_move();
      std::lock_guard lock(mutex);
      last_velocity = {};
    }
  }

  /// Ends the moveTo in progress, if any: answers its Call (when the caller is still connected)
  /// and, when it ran to its end (`reached`), stops the base as NAOqi does at the target pose.
  void end_bounded_move(bool reached) {
    if (!bounded_move) return;
    BoundedMove m = std::move(*bounded_move);
    bounded_move.reset();
    m.timer->cancel();
    if (reached) {
      robot.stop_move();
      std::lock_guard lock(mutex);
      last_velocity = {};
      ++stats.bounded_moves_ended;
    }
    log_event(reached ? "moveTo reached its pose: base stopped" : "moveTo replaced");
    auto caller = m.caller.lock();
    if (caller && !m.post) {
      MessageHeader r = m.call;
      r.type = MessageType::kReply;
      r.flags = 0;
      std::vector<std::uint8_t> payload;
      if (options.dynamic_replies) {
        payload = encode(Value::dynamic(Value()));
        r.flags = flags::kDynamicPayload;
      }
      send_reply(*caller, r, std::move(payload), false);
    }
  }

  /// ALMotion.moveTo(x, y, theta, time): drives the constant twist that reaches the pose in
  /// `time` (bounded_move.hpp), then stops by itself; the Call is answered at the end.
  void bounded_move_call(ConnState& c, const MessageHeader& h, const std::vector<Value>& a,
                         bool post) {
    const double x = a.at(0).as_double();
    const double y = a.at(1).as_double();
    const double theta = a.at(2).as_double();
    const double time_s = a.at(3).as_double();
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(theta) ||
        !std::isfinite(time_s) || time_s <= 0.0) {
      if (!post) {
        send_error(c, h,
                   "ALMotion::moveTo: invalid target (" + std::to_string(x) + ", " +
                       std::to_string(y) + ", " + std::to_string(theta) + ") in " +
                       std::to_string(time_s) + " s");
      }
      return;
    }
    std::string refusal;
    {
      std::lock_guard lock(mutex);
      refusal = move_refusal_locked();
    }
    c.commanded_base = true;
    if (!refusal.empty() && (x != 0.0 || y != 0.0 || theta != 0.0)) {
      // Not launched: answered at once (a moveTo's Call ends with its move).
      refuse_move(refusal);
      if (!post) {
        MessageHeader r = h;
        r.type = MessageType::kReply;
        r.flags = 0;
        std::vector<std::uint8_t> payload;
        if (options.dynamic_replies) {
          payload = encode(Value::dynamic(Value()));
          r.flags = flags::kDynamicPayload;
        }
        send_reply(c, r, std::move(payload), false);
      }
      return;
    }
    end_bounded_move(false);
    const BaseVelocity v = velocity_reaching({x, y, theta}, time_s);
    robot.command_velocity(v);
    {
      std::lock_guard lock(mutex);
      last_velocity = v;
    }
    BoundedMove m;
    m.timer = std::make_shared<asio::steady_timer>(
        io, std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                std::chrono::duration<double>(time_s)));
    m.caller = c.self;
    m.call = h;
    m.post = post;
    std::weak_ptr<asio::steady_timer> timer_of_this_move = m.timer;
    m.timer->async_wait([this, timer_of_this_move](const boost::system::error_code& ec) {
      if (ec) return;  // cancelled: replaced or ended already
      auto t = timer_of_this_move.lock();
      if (t && bounded_move && bounded_move->timer == t) end_bounded_move(true);
    });
    bounded_move = std::move(m);
  }

  void send_reply(ConnState& c, MessageHeader h, std::vector<std::uint8_t> payload,
                  bool allow_corrupt = true) {
    bool corrupt = false;
    std::chrono::milliseconds delay{0};
    {
      std::lock_guard lock(mutex);
      if (h.type == MessageType::kReply && allow_corrupt && !payload.empty()) {
        ++replies;
        corrupt = options.malformed_reply_every_nth > 0 &&
                  replies % static_cast<std::uint64_t>(options.malformed_reply_every_nth) == 0;
      }
      delay = latency;
    }
    if (corrupt) {
      // A dynamic list claiming 0xFFFFFFFF elements: a strict decoder must refuse it.
      payload = {0x03, 0, 0, 0, '[', 'm', ']', 0xff, 0xff, 0xff, 0xff, 0x01, 0x00};
    }
    if (corrupt) h.flags = 0;
    auto conn = c.conn;
    if (delay.count() <= 0) {
      conn->send(h, std::move(payload));
      return;
    }
    auto timer = std::make_shared<asio::steady_timer>(io, delay);
    timer->async_wait(
        [timer, conn, h, payload = std::move(payload)](const boost::system::error_code&) mutable {
          conn->send(h, std::move(payload));
        });
  }

  void send_error(ConnState& c, const MessageHeader& call, const std::string& text) {
    MessageHeader h = call;
    h.type = MessageType::kError;
    h.flags = 0;
    send_reply(c, h, encode_error_text(text), false);
  }

  void on_message(ConnState& c, Message m) {
    {
      std::lock_guard lock(mutex);
      ++stats.messages_received;
    }
    ++c.received;
    c.last_message_at = std::chrono::steady_clock::now();
    if (options.disconnect_after_messages > 0 &&
        c.received > static_cast<std::uint64_t>(options.disconnect_after_messages)) {
      c.conn->close("fault injection: disconnect after " +
                    std::to_string(options.disconnect_after_messages) + " messages");
      return;
    }
    const MessageHeader& h = m.header;
    if (h.type == MessageType::kCapability) return;
    if (h.type != MessageType::kCall && h.type != MessageType::kPost) return;
    const bool post = h.type == MessageType::kPost;

    if (h.service == ids::kServerService) {
      if (h.action == ids::kAuthenticateAction && !post) {
        authenticate(c, m);
      } else if (!post) {
        send_error(c, h,
                   "Expected authentication (service #0, type #Call, action #8), received "
                   "service #0, type #Call, action #" +
                       std::to_string(h.action));
        if (!options.user.empty()) c.conn->close_after_flush("expected authentication");
      }
      return;
    }
    if (!c.authenticated) {
      if (!post) send_error(c, h, "The call request could not be handled.");
      if (!options.user.empty()) c.conn->close_after_flush("call before authentication");
      return;
    }
    ServiceDef* svc = nullptr;
    {
      std::lock_guard lock(mutex);
      auto it = services.find(h.service);
      if (it != services.end()) svc = &it->second;
    }
    if (!svc || h.object != ids::kMainObject) {
      if (!post) send_error(c, h, "The call request could not be handled.");
      return;
    }
    auto mit = svc->methods.find(h.action);
    if (mit == svc->methods.end()) {
      if (!post) {
        send_error(c, h,
                   "No such method {" + std::to_string(h.service) + "." + std::to_string(h.object) +
                       "." + std::to_string(h.action) + ", id:" + std::to_string(h.id) + "}");
      }
      return;
    }
    const MethodDef& md = mit->second;
    std::vector<Value> args;
    try {
      Value v;
      if (h.flags & flags::kDynamicPayload) {
        v = convert(decode(Type::of(TypeKind::kDynamic), m.bytes(), options.limits), md.params);
      } else {
        v = decode(md.params, m.bytes(), options.limits, m.payload);
      }
      args = v.elements();
    } catch (const ProtocolError&) {
      {
        std::lock_guard lock(mutex);
        ++stats.protocol_errors;
      }
      if (!post) send_error(c, h, "ISerialization error Status Read Past End");
      return;
    }
    log_call(svc->name, md.meta.name, args);
    if (svc->name == "ALMotion" && md.meta.name == "moveTo" &&
        md.meta.parameters_signature == "(ffff)") {
      bounded_move_call(c, h, args, post);
      return;
    }
    if (svc->name == "ALVideoDevice" && md.meta.name == "getImageRemote") {
      serve_image(c, h, args.at(0).as_string(), post);
      return;
    }
    try {
      Value result = md.fn(c, args);
      if (post) return;
      std::vector<std::uint8_t> payload;
      MessageHeader r = h;
      r.type = MessageType::kReply;
      r.flags = 0;
      r.flags = 0;
      if (options.dynamic_replies) {
        payload = encode(Value::dynamic(convert(result, md.ret)));
        r.flags = flags::kDynamicPayload;
      } else if (md.ret.kind != TypeKind::kVoid) {
        payload = encode(convert(result, md.ret));
      }
      send_reply(c, r, std::move(payload));
    } catch (const MethodFailure& e) {
      if (!post) send_error(c, h, e.what());
    } catch (const std::exception& e) {
      if (!post) send_error(c, h, svc->name + "::" + md.meta.name + ": " + e.what());
    }
  }

  void authenticate(ConnState& c, const Message& m) {
    CapabilityMap theirs;
    try {
      theirs = decode_capabilities(m.bytes(), options.limits);
    } catch (const ProtocolError& e) {
      {
        std::lock_guard lock(mutex);
        ++stats.protocol_errors;
      }
      send_error(c, m.header,
                 std::string("Authentication failed: malformed capability map: ") + e.what());
      c.conn->close_after_flush("malformed authenticate");
      return;
    }
    if (call_log.is_open()) {
      // The login keys are logged by presence (user name, token length), never the token.
      std::ostringstream b;
      b << "\"service\":\"Server\",\"method\":\"authenticate\",\"args\":[{";
      bool first = true;
      for (const auto& [key, value] : theirs) {
        if (!first) b << ',';
        first = false;
        json_string(b, key);
        b << ':';
        if (key == "auth_token") {
          std::size_t n = 0;
          try {
            n = value.unwrapped().as_string().size();
          } catch (const ProtocolError&) {
          }
          json_string(b, "<" + std::to_string(n) + " characters>");
        } else {
          json_value(b, value);
        }
      }
      b << "}]";
      log_line(b.str());
    }
    if (!options.user.empty()) {
      auto get = [&](const char* k) -> std::string {
        auto it = theirs.find(k);
        if (it == theirs.end()) return {};
        try {
          return it->second.as_string();
        } catch (const ProtocolError&) {
          return {};
        }
      };
      if (get("auth_user") != options.user || get("auth_token") != options.password) {
        {
          std::lock_guard lock(mutex);
          ++stats.auth_failures;
        }
        send_error(c, m.header, "Authentication failed: invalid user or token [1.0]");
        c.conn->close_after_flush("authentication failed");
        return;
      }
    }
    CapabilityMap mine;
    if (!c.authenticated) {
      mine["ClientServerSocket"] = Value::boolean(false);
      mine["MessageFlags"] = Value::boolean(true);
      mine["MetaObjectCache"] = Value::boolean(false);
      mine["RemoteCancelableCalls"] = Value::boolean(false);
    }
    mine["__qi_auth_state"] = Value::uint32(3);
    c.authenticated = true;
    MessageHeader r = m.header;
    r.type = MessageType::kReply;
    r.flags = 0;
    send_reply(c, r, encode_capabilities(mine), false);
  }

  /// Decides what to serve under the lock. Returns false when nothing is to be sent now
  /// (stalled, paced for later); sets `unknown` for a handle that is not subscribed.
  bool plan_image(ConnState& c, const MessageHeader& h, const std::string& handle, bool post,
                  bool paced, Subscription& sub, bool& unknown, bool& repeat,
                  ImageRemote& previous) {
    std::lock_guard lock(mutex);
    if (stall_frames) return false;  // never answered: the client sees frames stall
    auto it = subscriptions.find(handle);
    if (it == subscriptions.end()) {
      unknown = true;
      return true;
    }
    if (options.pace_frames && !paced) {
      const auto now = std::chrono::steady_clock::now();
      const auto period = std::chrono::microseconds(1'000'000 / std::max(1, it->second.fps));
      const auto at = std::max(now, it->second.next_frame);
      it->second.next_frame = at + period;
      if (at > now) {
        auto timer = std::make_shared<asio::steady_timer>(io, at);
        std::weak_ptr<ConnState> weak;
        for (const auto& s : conns) {
          if (s.get() == &c) weak = s;
        }
        timer->async_wait([this, timer, weak, h, handle, post](const boost::system::error_code&) {
          if (auto st = weak.lock()) serve_image(*st, h, handle, post, true);
        });
        return false;
      }
    }
    sub = it->second;
    ++image_requests;
    if (options.drop_every_nth_frame > 0 &&
        image_requests % static_cast<std::uint64_t>(options.drop_every_nth_frame) == 0 &&
        last_image.count(handle)) {
      repeat = true;
      previous = last_image[handle];
    }
    return true;
  }

  void serve_image(ConnState& c, const MessageHeader& h, const std::string& handle, bool post,
                   bool paced = false) {
    Subscription sub;
    bool repeat = false;
    bool unknown = false;
    ImageRemote previous;
    if (!plan_image(c, h, handle, post, paced, sub, unknown, repeat, previous)) return;
    if (unknown) {
      if (!post) {
        send_error(c, h, "ALVideoDevice::getImageRemote: unknown subscriber '" + handle + "'");
      }
      return;
    }
    if (post) return;
    ImageRemote img;
    if (repeat) {
      img = previous;
    } else {
      const auto [w, hgt] = resolution_size(sub.resolution);
      const core::Frame f = robot.capture(w, hgt);
      const int layers = layers_for(sub.color_space);
      auto pixels = std::make_shared<std::vector<std::uint8_t>>(static_cast<std::size_t>(w) *
                                                                static_cast<std::size_t>(hgt) *
                                                                static_cast<std::size_t>(layers));
      for (int v = 0; v < hgt; ++v) {
        const std::uint8_t* src = f.gray.ptr<std::uint8_t>(v);
        std::uint8_t* dst = pixels->data() + static_cast<std::size_t>(v) * w * layers;
        if (layers == 1) {
          std::memcpy(dst, src, static_cast<std::size_t>(w));
        } else {
          for (int u = 0; u < w; ++u) {
            for (int l = 0; l < layers; ++l)
              dst[u * layers + l] = (l == 0 || layers == 3) ? src[u] : 128;
          }
        }
      }
      img.width_px = w;
      img.height_px = hgt;
      img.layers = layers;
      img.color_space = sub.color_space;
      img.t_sec = static_cast<std::int32_t>(f.t_ns / 1'000'000'000);
      img.t_usec = static_cast<std::int32_t>((f.t_ns % 1'000'000'000) / 1000);
      img.pixels.data = pixels->data();
      img.pixels.size = pixels->size();
      img.pixels.owner = pixels;
      img.camera_index = sub.camera;
      img.angles_rad = {0.4992f, 0.3866f, -0.4992f, -0.3866f};
      std::lock_guard lock(mutex);
      last_image[handle] = img;
    }
    std::vector<std::uint8_t> payload;
    payload.reserve(img.pixels.size + 256);
    Writer w(payload);
    encode_image_remote(img, w);
    {
      std::lock_guard lock(mutex);
      ++stats.frames_served;
    }
    MessageHeader r = h;
    r.type = MessageType::kReply;
    r.flags = 0;
    send_reply(c, r, std::move(payload));
  }
};

// ---------------------------------------------------------------------------------------------

MockNaoqiServer::MockNaoqiServer(sim::SimRobot& robot, MockServerOptions options)
    : impl_(std::make_shared<Impl>(robot, std::move(options))) {}

MockNaoqiServer::~MockNaoqiServer() { stop(); }

void MockNaoqiServer::start() { impl_->start(); }
void MockNaoqiServer::stop() noexcept {
  try {
    impl_->stop();
  } catch (...) {
  }
}

std::string MockNaoqiServer::url() const { return impl_->url.to_string(); }
std::uint16_t MockNaoqiServer::port() const { return impl_->url.port; }
std::string MockNaoqiServer::certificate_sha256() const { return impl_->fingerprint; }

void MockNaoqiServer::disconnect_all() {
  auto self = impl_;
  asio::post(impl_->io, [self] {
    std::set<std::shared_ptr<ConnState>> all;
    {
      std::lock_guard lock(self->mutex);
      all = self->conns;
    }
    for (const auto& c : all) c->conn->close("fault injection: disconnect on demand");
  });
}

void MockNaoqiServer::set_stall_frames(bool stall) {
  std::lock_guard lock(impl_->mutex);
  impl_->stall_frames = stall;
}

void MockNaoqiServer::set_reply_latency(std::chrono::milliseconds latency) {
  std::lock_guard lock(impl_->mutex);
  impl_->latency = latency;
}

void MockNaoqiServer::set_move_failure(const std::string& cause) {
  std::lock_guard lock(impl_->mutex);
  impl_->move_failure_cause = cause;
}

void MockNaoqiServer::take_head_back(double head_yaw_rad, bool sticky) {
  std::lock_guard lock(impl_->mutex);
  impl_->life_state = "solitary";
  impl_->awareness_enabled = true;
  impl_->head_taken = true;
  impl_->head_taken_sticky = sticky;
  impl_->tracked_head_yaw_rad = head_yaw_rad;
  impl_->hold_tracked_head_locked();
}

void MockNaoqiServer::set_awake(bool awake) {
  std::lock_guard lock(impl_->mutex);
  impl_->awake = awake;
}

void MockNaoqiServer::set_charging(bool charging) {
  std::lock_guard lock(impl_->mutex);
  impl_->charging = charging;
}

void MockNaoqiServer::set_battery_percent(int percent) {
  std::lock_guard lock(impl_->mutex);
  impl_->battery_percent = std::clamp(percent, 0, 100);
}

bool MockNaoqiServer::awake() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->awake;
}

std::string MockNaoqiServer::autonomous_life_state() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->life_state;
}
bool MockNaoqiServer::basic_awareness_enabled() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->awareness_enabled;
}
bool MockNaoqiServer::external_collision_protection() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->collision_protection;
}
double MockNaoqiServer::stiffness(const std::string& joint) const {
  std::lock_guard lock(impl_->mutex);
  auto it = impl_->stiffness.find(joint);
  return it == impl_->stiffness.end() ? 0.0 : it->second;
}
std::vector<std::string> MockNaoqiServer::video_subscribers() const {
  std::lock_guard lock(impl_->mutex);
  std::vector<std::string> out;
  for (const auto& [k, v] : impl_->subscriptions) out.push_back(k);
  return out;
}
MockNaoqiServer::Stats MockNaoqiServer::stats() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->stats;
}

}  // namespace pepper::naoqi_bridge::qi
