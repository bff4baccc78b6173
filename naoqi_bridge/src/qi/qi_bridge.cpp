// QiBridge: RobotBridge over qi messaging, with the base watchdog (see the header).
#include "naoqi_bridge/qi/qi_bridge.hpp"

#include <cmath>
#include <cstring>

#include "naoqi_bridge/qi/bounded_move.hpp"
#include "naoqi_bridge/qi/image_remote.hpp"

namespace pepper::naoqi_bridge::qi {

namespace {

std::int64_t mono_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

const std::vector<std::string> kLockedJoints = {"HeadYaw", "HeadPitch", "HipRoll", "HipPitch",
                                                "KneePitch"};

int resolution_code(int width_px, int height_px) {
  if (width_px == 640 && height_px == 480) return 2;   // kVGA
  if (width_px == 320 && height_px == 240) return 1;   // kQVGA
  if (width_px == 160 && height_px == 120) return 0;   // kQQVGA
  if (width_px == 1280 && height_px == 960) return 3;  // k4VGA
  throw BridgeError("start_camera: unsupported size " + std::to_string(width_px) + "x" +
                    std::to_string(height_px) +
                    " (ALVideoDevice offers 160x120, 320x240, 640x480, 1280x960)");
}

std::string ms(std::chrono::milliseconds d) { return std::to_string(d.count()) + " ms"; }

}  // namespace

std::vector<std::string> QiBridgeOptions::validate() const {
  std::vector<std::string> errors;
  try {
    (void)parse_url(url);
  } catch (const BridgeError& e) {
    errors.push_back(std::string("url: ") + e.what());
  }
  auto range = [&](const char* name, std::chrono::milliseconds v, long lo, long hi) {
    if (v.count() < lo || v.count() > hi) {
      errors.push_back(std::string(name) + " must be in " + std::to_string(lo) + ".." +
                       std::to_string(hi) + " ms, got " + std::to_string(v.count()));
    }
  };
  range("connect_timeout", connect_timeout, 1, 600000);
  range("call_timeout", call_timeout, 1, 600000);
  range("stop_call_timeout", stop_call_timeout, 1, 10000);
  range("watchdog_timeout", watchdog_timeout, 50, 10000);
  range("frame_stall_timeout", frame_stall_timeout, 50, 60000);
  range("watchdog_period", watchdog_period, 1, 1000);
  if (deadman_horizon.count() != 0) range("deadman_horizon", deadman_horizon, 50, 2000);
  range("reconnect_initial_backoff", reconnect_initial_backoff, 0, 60000);
  range("reconnect_max_backoff", reconnect_max_backoff, 0, 600000);
  range("head_settle_timeout", head_settle_timeout, 0, 60000);
  range("head_resend_period", head_resend_period, 0, 60000);
  range("odometry_grace", odometry_grace, 0, 1000);
  range("supervise_period", supervise_period, 0, 60000);
  if (watchdog_period >= watchdog_timeout) {
    errors.push_back("watchdog_period must be shorter than watchdog_timeout");
  }
  if (reconnect_attempts < 1 || reconnect_attempts > 100) {
    errors.push_back("reconnect_attempts must be in 1..100, got " +
                     std::to_string(reconnect_attempts));
  }
  if (subscriber_name.empty() || subscriber_name.size() > 64) {
    errors.push_back("subscriber_name must have 1..64 characters");
  }
  if (!(head_max_speed_fraction > 0.0 && head_max_speed_fraction <= 1.0)) {
    errors.push_back("head_max_speed_fraction must be in (0, 1], got " +
                     std::to_string(head_max_speed_fraction));
  }
  if (user.empty() && !password.empty()) errors.push_back("password given without a user");
  SessionOptions session;
  session.tls_pin_sha256 = tls_pin_sha256;
  for (const auto& e : session.validate()) errors.push_back(e);  // the pin's format
  for (const auto& e : limits.validate()) errors.push_back("limits." + e);
  return errors;
}

QiBridge::QiBridge(QiBridgeOptions options)
    : options_(std::move(options)), supervisor_(options_.supervisor) {
  const auto errors = options_.validate();
  if (!errors.empty()) {
    std::string all;
    for (const auto& e : errors) all += (all.empty() ? "" : "; ") + e;
    throw BridgeError("QiBridgeOptions: " + all);
  }
  SessionOptions so;
  so.connect_timeout = options_.connect_timeout;
  so.call_timeout = options_.call_timeout;
  so.user = options_.user;
  so.password = options_.password;
  so.tls_pin_sha256 = options_.tls_pin_sha256;
  so.verify_certificate = options_.verify_certificate;
  so.limits = options_.limits;
  session_ = std::make_unique<QiSession>(so);
  session_->set_disconnect_handler([this](const std::string& why) {
    // I/O thread: only flag; never call the session from here.
    moving_ = false;
    if (state_.load() == ConnectionState::kConnected) state_ = ConnectionState::kLost;
    std::lock_guard lock(mutex_);
    needs_operator_ = true;
    if (fault_reason_.empty()) fault_reason_ = "connection lost: " + why;
  });
}

QiBridge::~QiBridge() {
  {
    std::lock_guard lock(wd_mutex_);
    wd_quit_ = true;
  }
  wd_cv_.notify_all();
  if (watchdog_.joinable()) watchdog_.join();
  release();
  session_->set_disconnect_handler(nullptr);
  // Joins the session's I/O thread now, while the members its handlers touch still exist.
  session_.reset();
}

ConnectionState QiBridge::state() const { return state_.load(); }

std::string QiBridge::describe() const {
  // Before connect() the session knows no URL yet; the console's "replay ... on ROBOT" line is
  // printed then, and "(not connected)" would hide which robot it is about to drive.
  if (!session_->is_connected()) {
    return options_.url + (options_.user.empty() ? "" : " (user " + options_.user + ")");
  }
  return session_->describe();
}

std::string QiBridge::tls_fingerprint() const { return session_->peer_certificate_sha256(); }

bool QiBridge::needs_operator() const {
  std::lock_guard lock(mutex_);
  return needs_operator_;
}

std::string QiBridge::fault_reason() const {
  std::lock_guard lock(mutex_);
  return fault_reason_;
}

QiBridge::Counters QiBridge::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

std::string QiBridge::last_move_error() const {
  std::lock_guard lock(mutex_);
  return last_move_error_;
}

bool QiBridge::robot_side_deadman() const {
  std::lock_guard lock(mutex_);
  return bounded_moves_;
}

std::string QiBridge::robot_side_deadman_summary() const {
  std::lock_guard lock(mutex_);
  if (bounded_moves_) {
    return "ALMotion.moveTo(x, y, theta, time): every velocity command ends by itself on the "
           "robot after " + ms(options_.deadman_horizon) + " without a fresh one";
  }
  if (options_.deadman_horizon.count() == 0) {
    return "off (deadman_horizon 0): plain ALMotion.move; a frozen or killed laptop leaves the "
           "base driving";
  }
  return "none: this ALMotion has no moveTo(x, y, theta, time); a frozen or killed laptop "
         "leaves the base driving (only the laptop-side watchdog stops it)";
}

std::string QiBridge::last_stop_reason() const {
  std::lock_guard lock(mutex_);
  return last_stop_reason_;
}

void QiBridge::latch_fault(const std::string& why) {
  std::lock_guard lock(mutex_);
  needs_operator_ = true;
  if (fault_reason_.empty()) fault_reason_ = why;
}

void QiBridge::clear_fault() {
  if (!connected() || !session_->is_connected()) {
    throw BridgeError("cannot clear the fault: not connected to " + describe() +
                      " (reconnect first)");
  }
  std::lock_guard lock(mutex_);
  needs_operator_ = false;
  fault_reason_.clear();
  head_lock_lost_ = false;
  head_lock_detail_.clear();
}

void QiBridge::open_session() {
  state_ = ConnectionState::kConnecting;
  try {
    session_->connect(options_.url);
    auto motion = session_->service("ALMotion");
    auto video = session_->service("ALVideoDevice");
    std::optional<ServiceHandle> life;
    std::optional<ServiceHandle> awareness;
    std::optional<ServiceHandle> memory;
    try {
      life = session_->service("ALAutonomousLife");
    } catch (const ServiceNotFound&) {
    }
    try {
      memory = session_->service("ALMemory");
    } catch (const ServiceNotFound&) {
    }
    try {
      awareness = session_->service("ALBasicAwareness");
    } catch (const ServiceNotFound&) {
    }
    const bool bounded =
        options_.deadman_horizon.count() > 0 && motion.meta.find("moveTo", "(ffff)") != nullptr;
    std::lock_guard lock(mutex_);
    bounded_moves_ = bounded;
    last_bounded_ = PendingCall();
    motion_ = std::move(motion);
    video_ = std::move(video);
    life_ = std::move(life);
    awareness_ = std::move(awareness);
    memory_ = std::move(memory);
    probe_ = Probe();
    move_failed_call_ = PendingCall();
    inflight_ = PendingCall();
    odometry_inflight_ = PendingCall();
    // Resolved by name and signature like every method; a robot without it gives frames
    // without odometry (reported), not a failed connection.
    odometry_available_ =
        options_.read_odometry && motion_->meta.find("getRobotPosition", "(b)") != nullptr;
    odometry_problem_.clear();
    if (options_.read_odometry && !odometry_available_) {
      odometry_problem_ = "ALMotion has no getRobotPosition(b): frames come without odometry";
    }
  } catch (...) {
    state_ = ConnectionState::kDisconnected;
    session_->close();
    throw;
  }
  state_ = ConnectionState::kConnected;
}

void QiBridge::connect() {
  open_session();
  std::lock_guard lock(wd_mutex_);
  if (!watchdog_.joinable()) {
    wd_quit_ = false;
    watchdog_ = std::thread([this] { watchdog_loop(); });
  }
}

void QiBridge::reconnect() {
  stop_base("reconnect requested");
  auto backoff = options_.reconnect_initial_backoff;
  std::string last_error;
  for (int attempt = 1; attempt <= options_.reconnect_attempts; ++attempt) {
    try {
      open_session();
      std::optional<CameraRequest> cam;
      std::optional<HeadLockRequest> head;
      {
        std::lock_guard lock(mutex_);
        cam = camera_;
        head = head_;
        camera_handle_.clear();
        last_t_ns_ = -1;
      }
      if (cam) start_camera(*cam);
      if (head) lock_head(*head);
      std::lock_guard lock(wd_mutex_);
      if (!watchdog_.joinable()) {
        wd_quit_ = false;
        watchdog_ = std::thread([this] { watchdog_loop(); });
      }
      return;
    } catch (const BridgeError& e) {
      last_error = e.what();
    }
    if (attempt < options_.reconnect_attempts) {
      std::this_thread::sleep_for(backoff);
      backoff = std::min(backoff * 2, options_.reconnect_max_backoff);
    }
  }
  throw ConnectError("reconnect to " + options_.url + " failed after " +
                     std::to_string(options_.reconnect_attempts) + " attempts: " + last_error);
}

void QiBridge::subscribe_camera_locked() {
  const CameraRequest& req = *camera_;
  const std::string prefix = options_.subscriber_name;
  // Clean up stale subscriptions of ours (a crashed earlier run keeps its instances alive).
  std::vector<std::string> stale;
  if (video_->meta.find("getSubscribers", "()")) {
    try {
      const Value subs = session_->call(*video_, "getSubscribers", "()", {});
      for (const auto& s : subs.elements()) {
        const std::string& name = s.unwrapped().as_string();
        if (name.rfind(prefix, 0) == 0) stale.push_back(name);
      }
    } catch (const RemoteCallError&) {
    }
  } else {
    for (int n = 0; n < 6; ++n) stale.push_back(prefix + "_" + std::to_string(n));
  }
  if (!camera_handle_.empty()) stale.push_back(camera_handle_);
  for (const auto& name : stale) {
    try {
      session_->call(*video_, "unsubscribe", "(s)", {Value::string(name)});
    } catch (const RemoteCallError&) {
    }
  }
  camera_handle_.clear();
  const Value handle = session_->call(
      *video_, "subscribeCamera", "(siiii)",
      {Value::string(prefix), Value::int32(req.camera_index), Value::int32(resolution_code_),
       Value::int32(0) /* kYuv: grey, 1 byte per pixel */, Value::int32(req.fps)});
  camera_handle_ = handle.as_string();
  last_t_ns_ = -1;
  inflight_ = PendingCall();
  odometry_inflight_ = PendingCall();
}

core::CameraIntrinsics QiBridge::start_camera(const CameraRequest& request) {
  if (request.fps < 1 || request.fps > 30) {
    throw BridgeError("start_camera: fps must be in 1..30, got " + std::to_string(request.fps));
  }
  const int code = resolution_code(request.width_px, request.height_px);
  try {
    std::lock_guard lock(mutex_);
    if (!video_ || !connected()) throw ConnectionLost("start_camera: not connected");
    camera_ = request;
    resolution_code_ = code;
    subscribe_camera_locked();
    request_frame_locked();
  } catch (...) {
    stop_base("exception in start_camera");
    throw;
  }
  last_frame_ns_ = mono_ns();
  return core::CameraIntrinsics::pepper_top_vga().scaled_to(request.width_px, request.height_px);
}

PendingCall QiBridge::request_image() {
  return session_->call_async(*video_, "getImageRemote", "(s)", {Value::string(camera_handle_)});
}

void QiBridge::request_frame_locked() {
  // The odometry first: a server that answers in order then answers it before the image, and
  // its reply is a few bytes where the image's is hundreds of kilobytes.
  odometry_inflight_ = odometry_available_ ? session_->call_async(*motion_, "getRobotPosition",
                                                                  "(b)", {Value::boolean(true)})
                                           : PendingCall();
  inflight_ = request_image();
  inflight_since_ = std::chrono::steady_clock::now();
}

std::optional<core::OdometryPose> QiBridge::take_odometry(PendingCall& call) {
  if (!call.valid()) return std::nullopt;  // not asked: odometry_problem_ says why
  std::string problem;
  try {
    const Value v = call.get(options_.odometry_grace);
    const auto& e = v.elements();
    if (e.size() == 3) {
      const core::OdometryPose p{e[0].as_double(), e[1].as_double(), e[2].as_double()};
      if (std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.yaw_rad)) {
        std::lock_guard lock(mutex_);
        odometry_problem_.clear();
        return p;
      }
    }
    problem = "ALMotion.getRobotPosition(true) returned " + v.to_debug_string() +
              ", not three finite numbers";
  } catch (const CallTimeout&) {
    problem = "ALMotion.getRobotPosition(true): no reply within " + ms(options_.odometry_grace) +
              " of the image";
  } catch (const RemoteCallError& e) {
    problem = e.what();
  } catch (const ProtocolError& e) {
    problem = std::string("ALMotion.getRobotPosition(true): ") + e.what();
  }
  std::lock_guard lock(mutex_);
  odometry_problem_ = problem;
  return std::nullopt;
}

std::string QiBridge::odometry_problem() const {
  std::lock_guard lock(mutex_);
  return odometry_problem_;
}

std::optional<core::Frame> QiBridge::next_frame(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  try {
    for (;;) {
      PendingCall call;
      PendingCall odometry_call;
      {
        std::lock_guard lock(mutex_);
        if (!camera_) throw BridgeError("next_frame called before start_camera");
        if (!connected()) {
          throw ConnectionLost("next_frame: not connected (" + fault_reason_ + ")");
        }
        if (!inflight_.valid() ||
            std::chrono::steady_clock::now() - inflight_since_ > options_.call_timeout) {
          // None in flight, or the robot dropped the request: ask again.
          request_frame_locked();
        }
        call = inflight_;
        odometry_call = odometry_inflight_;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (!call.wait(std::max(left, std::chrono::milliseconds(0)))) return std::nullopt;
      Message msg = call.get_message(std::chrono::milliseconds(0));
      {
        // Keep the next request in flight while this frame is decoded and processed.
        std::lock_guard lock(mutex_);
        request_frame_locked();
      }
      ImageRemote img;
      try {
        img = decode_image_remote(msg.bytes(), options_.limits, msg.payload);
      } catch (const ProtocolError& e) {
        const std::string why = std::string("malformed getImageRemote reply: ") + e.what();
        latch_fault(why);
        stop_base(why);
        session_->close();
        throw ProtocolViolation("ALVideoDevice.getImageRemote: " + why + " (connection closed)");
      }
      // Outside the lock: take_odometry may wait up to odometry_grace.
      std::optional<core::OdometryPose> odom = take_odometry(odometry_call);
      std::lock_guard lock(mutex_);
      if (img.t_ns() <= last_t_ns_) {
        ++counters_.stale_replies;
        if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
        continue;
      }
      last_t_ns_ = img.t_ns();
      core::Frame f;
      f.odom = odom;
      if (!odom) ++counters_.frames_without_odometry;
      f.gray.create(img.height_px, img.width_px, CV_8UC1);
      if (img.layers == 1) {
        std::memcpy(f.gray.data, img.pixels.data, img.pixels.size);
      } else {
        // Colour spaces with several layers: keep the first byte of each pixel (Y or R/B).
        for (std::size_t i = 0, n = f.gray.total(); i < n; ++i) {
          f.gray.data[i] = img.pixels.data[i * static_cast<std::size_t>(img.layers)];
        }
      }
      f.t_ns = img.t_ns();
      f.index = frame_index_++;
      ++counters_.frames;
      last_frame_ns_ = mono_ns();
      return f;
    }
  } catch (const ConnectionLost& e) {
    latch_fault(e.what());
    stop_base("exception in next_frame");
    throw;
  } catch (...) {
    stop_base("exception in next_frame");
    throw;
  }
}

HeadLockStatus QiBridge::lock_head(const HeadLockRequest& request) {
  try {
    std::optional<ServiceHandle> motion, life, awareness;
    {
      std::lock_guard lock(mutex_);
      if (!motion_ || !connected()) throw ConnectionLost("lock_head: not connected");
      motion = motion_;
      life = life_;
      awareness = awareness_;
    }
    if (life && options_.disable_autonomous_life) {
      const std::string prev = session_->call(*life, "getState", "()", {}).as_string();
      {
        std::lock_guard lock(mutex_);
        if (!previous_life_state_) previous_life_state_ = prev;
      }
      if (prev != "disabled") {
        session_->call(*life, "setState", "(s)", {Value::string("disabled")});
      }
    }
    if (awareness && options_.disable_basic_awareness) {
      const bool prev = session_->call(*awareness, "isEnabled", "()", {}).as_bool();
      {
        std::lock_guard lock(mutex_);
        if (!previous_awareness_) previous_awareness_ = prev;
      }
      if (prev) session_->call(*awareness, "setEnabled", "(b)", {Value::boolean(false)});
    }
    session_->call(*motion, "wakeUp", "()", {});
    std::vector<float> ones(kLockedJoints.size(), 1.0f);
    session_->call(*motion, "setStiffnesses", "(mm)",
                   {Value::strings(kLockedJoints), Value::floats(ones)});
    const std::vector<float> targets = {static_cast<float>(request.head_yaw_rad),
                                        static_cast<float>(request.head_pitch_rad), 0.f, 0.f, 0.f};
    session_->call(*motion, "setAngles", "(mmf)",
                   {Value::strings(kLockedJoints), Value::floats(targets),
                    Value::float32(static_cast<float>(options_.head_max_speed_fraction))});
    {
      std::lock_guard lock(mutex_);
      head_ = request;
      head_retaking_ = false;
    }
    last_head_resend_ns_ = mono_ns();
    HeadLockStatus status;
    const auto settle_deadline = std::chrono::steady_clock::now() + options_.head_settle_timeout;
    for (;;) {
      const Value angles = session_->call(*motion, "getAngles", "(mb)",
                                          {Value::strings(kLockedJoints), Value::boolean(true)});
      const auto& a = angles.elements();
      if (a.size() != kLockedJoints.size()) {
        throw BridgeError("ALMotion.getAngles returned " + std::to_string(a.size()) +
                          " angles for " + std::to_string(kLockedJoints.size()) + " joints");
      }
      status.head_yaw_rad = a[0].as_double();
      status.head_pitch_rad = a[1].as_double();
      status.max_error_rad = 0.0;
      for (std::size_t i = 0; i < a.size(); ++i) {
        status.max_error_rad =
            std::max(status.max_error_rad, std::fabs(a[i].as_double() - targets[i]));
      }
      status.holding = status.max_error_rad <= request.tolerance_rad;
      if (status.holding || std::chrono::steady_clock::now() >= settle_deadline) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return status;
  } catch (...) {
    stop_base("exception in lock_head");
    throw;
  }
}

void QiBridge::move(const BaseVelocity& velocity) {
  if (!std::isfinite(velocity.v_x_m_s) || !std::isfinite(velocity.v_y_m_s) ||
      !std::isfinite(velocity.omega_rad_s)) {
    stop_base("non-finite velocity");
    throw BridgeError("move: non-finite velocity");
  }
  std::optional<ServiceHandle> motion;
  {
    std::lock_guard lock(mutex_);
    if (needs_operator_) {
      throw BridgeError("move refused: " + fault_reason_ +
                        "; the base stays stopped until the operator clears the fault");
    }
    motion = motion_;
  }
  if (!motion || !connected()) throw ConnectionLost("move: not connected to " + describe());
  const bool zero =
      velocity.v_x_m_s == 0.0 && velocity.v_y_m_s == 0.0 && velocity.omega_rad_s == 0.0;
  bool bounded = false;
  {
    std::lock_guard lock(mutex_);
    bounded = bounded_moves_;
  }
  try {
    if (bounded && !zero) {
      send_bounded_move(*motion, velocity);
      return;
    }
    PendingCall call;
    {
      std::lock_guard send_lock(motion_send_mutex_);
      call = session_->call_async(*motion, "move", "(fff)",
                                  {Value::float32(static_cast<float>(velocity.v_x_m_s)),
                                   Value::float32(static_cast<float>(velocity.v_y_m_s)),
                                   Value::float32(static_cast<float>(velocity.omega_rad_s))});
      last_move_ns_ = mono_ns();
      moving_ = velocity.v_x_m_s != 0.0 || velocity.v_y_m_s != 0.0 || velocity.omega_rad_s != 0.0;
    }
    {
      std::lock_guard lock(mutex_);
      supervisor_.on_command(velocity, last_move_ns_.load());
    }
    call.get(options_.call_timeout);
    std::lock_guard lock(mutex_);
    ++counters_.moves;
  } catch (const ConnectionLost& e) {
    latch_fault(e.what());
    stop_base("exception in move");
    throw;
  } catch (...) {
    stop_base("exception in move");
    throw;
  }
}

void QiBridge::send_bounded_move(const ServiceHandle& motion, const BaseVelocity& velocity) {
  reap_bounded_move();
  const double horizon_s = std::chrono::duration<double>(options_.deadman_horizon).count();
  const RelativePose target = pose_after(velocity, horizon_s);
  {
    std::lock_guard send_lock(motion_send_mutex_);
    // Not awaited: NAOqi answers a moveTo when it ends (replaced by the next command, or at the
    // horizon), so waiting here would hold the control loop for the whole horizon.
    PendingCall call = session_->call_async(
        motion, "moveTo", "(ffff)",
        {Value::float32(static_cast<float>(target.x_m)),
         Value::float32(static_cast<float>(target.y_m)),
         Value::float32(static_cast<float>(target.theta_rad)),
         Value::float32(static_cast<float>(horizon_s))});
    last_move_ns_ = mono_ns();
    moving_ = true;
    std::lock_guard lock(mutex_);
    last_bounded_ = std::move(call);
    ++counters_.moves;
    supervisor_.on_command(velocity, last_move_ns_.load());
  }
}

void QiBridge::reap_bounded_move() {
  PendingCall previous;
  {
    std::lock_guard lock(mutex_);
    previous = last_bounded_;
  }
  if (!previous.valid() || !previous.ready()) return;
  try {
    (void)previous.get(std::chrono::milliseconds(0));
  } catch (const RemoteCallError& e) {
    // The robot refused or aborted a move. Kept for the operator rather than thrown: a moveTo
    // that a later command replaced may end this way on some NAOqi versions.
    std::lock_guard lock(mutex_);
    ++counters_.bounded_move_errors;
    last_move_error_ = e.what();
  }
}

void QiBridge::stop() noexcept { stop_base("stop requested"); }

void QiBridge::stop_base(const std::string& why) noexcept {
  try {
    moving_ = false;
    std::optional<ServiceHandle> motion;
    {
      std::lock_guard lock(mutex_);
      motion = motion_;
      last_stop_reason_ = why;
      supervisor_.on_command(BaseVelocity{}, mono_ns());
    }
    if (!motion || !session_->is_connected()) return;
    PendingCall zero;
    PendingCall halt;
    {
      std::lock_guard send_lock(motion_send_mutex_);
      zero = session_->call_async(*motion, "move", "(fff)",
                                  {Value::float32(0.f), Value::float32(0.f), Value::float32(0.f)});
      halt = session_->call_async(*motion, "stopMove", "()", {});
    }
    {
      std::lock_guard lock(mutex_);
      ++counters_.stops;
    }
    try {
      zero.get(options_.stop_call_timeout);
    } catch (const std::exception&) {
    }
    try {
      halt.get(options_.stop_call_timeout);
    } catch (const std::exception&) {
    }
  } catch (...) {
    // Best effort: stop() never throws.
  }
}

void QiBridge::release() noexcept {
  stop_base("release");
  try {
    std::optional<ServiceHandle> video, life, awareness;
    std::string handle;
    std::optional<std::string> prev_life;
    std::optional<bool> prev_awareness;
    {
      std::lock_guard lock(mutex_);
      video = video_;
      life = life_;
      awareness = awareness_;
      handle = camera_handle_;
      prev_life = previous_life_state_;
      prev_awareness = previous_awareness_;
      camera_.reset();
      camera_handle_.clear();
      inflight_ = PendingCall();
      head_.reset();
      previous_life_state_.reset();
      previous_awareness_.reset();
    }
    if (!session_->is_connected()) return;
    const auto t = options_.stop_call_timeout * 2;
    if (video && !handle.empty()) {
      try {
        session_->call(*video, "unsubscribe", "(s)", {Value::string(handle)}, t);
      } catch (const std::exception&) {
      }
    }
    if (awareness && prev_awareness && *prev_awareness) {
      try {
        session_->call(*awareness, "setEnabled", "(b)", {Value::boolean(true)}, t);
      } catch (const std::exception&) {
      }
    }
    if (life && prev_life && *prev_life != "disabled") {
      try {
        session_->call(*life, "setState", "(s)", {Value::string(*prev_life)}, t);
      } catch (const std::exception&) {
      }
    }
  } catch (...) {
  }
}

void QiBridge::send_probe_locked(std::int64_t now_ns) {
  Probe p;
  p.active = true;
  p.sent_ns = now_ns;
  p.command = supervisor_.snapshot(now_ns);
  p.head = head_;
  // Each read-back only where the robot has the method (a missing one is simply not judged).
  if (motion_->meta.find("getRobotVelocity", "()")) {
    p.velocity = session_->call_async(*motion_, "getRobotVelocity", "()", {});
  }
  if (motion_->meta.find("moveIsActive", "()")) {
    p.move_active = session_->call_async(*motion_, "moveIsActive", "()", {});
  }
  if (p.head) {
    if (life_ && options_.disable_autonomous_life && life_->meta.find("getState", "()")) {
      p.life = session_->call_async(*life_, "getState", "()", {});
    }
    if (awareness_ && options_.disable_basic_awareness &&
        awareness_->meta.find("isEnabled", "()")) {
      p.awareness = session_->call_async(*awareness_, "isEnabled", "()", {});
    }
    p.head_angles = session_->call_async(*motion_, "getAngles", "(mb)",
                                         {Value::strings({"HeadYaw", "HeadPitch"}),
                                          Value::boolean(true)});
  }
  probe_ = std::move(p);
  last_probe_ns_ = now_ns;
}

namespace {

/// A read-back's value, or nullopt when it was not asked or the robot answered an Error.
std::optional<Value> reply_of(PendingCall& call) {
  if (!call.valid()) return std::nullopt;
  try {
    return call.get(std::chrono::milliseconds(0));
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

}  // namespace

void QiBridge::judge_probe(Probe& p, RobotSupervision& out) {
  // Replies are all in (or the probe is judged with what came): read them outside the lock.
  std::optional<BaseVelocity> measured;
  if (auto v = reply_of(p.velocity)) {
    try {
      const auto& e = v->elements();
      if (e.size() == 3) {
        measured = BaseVelocity{e[0].as_double(), e[1].as_double(), e[2].as_double()};
      }
    } catch (const std::exception&) {
    }
  }
  std::optional<bool> active;
  if (auto v = reply_of(p.move_active)) {
    try {
      active = v->as_bool();
    } catch (const std::exception&) {
    }
  }
  MotionSupervisor::HeadReadback head;
  if (p.head) {
    if (auto v = reply_of(p.life)) {
      try {
        head.life_state = v->as_string();
      } catch (const std::exception&) {
      }
    }
    if (auto v = reply_of(p.awareness)) {
      try {
        head.awareness_enabled = v->as_bool();
      } catch (const std::exception&) {
      }
    }
    if (auto v = reply_of(p.head_angles)) {
      try {
        const auto& e = v->elements();
        if (e.size() == 2) {
          head.max_error_rad = std::max(std::fabs(e[0].as_double() - p.head->head_yaw_rad),
                                        std::fabs(e[1].as_double() - p.head->head_pitch_rad));
        }
      } catch (const std::exception&) {
      }
    }
  }
  std::optional<MotionSupervisor::HeadVerdict> verdict;
  std::string detail;
  bool ask_move_failed = false;
  {
    std::lock_guard lock(mutex_);
    ++counters_.supervision_probes;
    if (measured) {
      measured_velocity_ = measured;
      move_active_ = active;
      const bool was_failing = supervisor_.move_failing();
      if (auto w = supervisor_.on_motion_readback(p.command, *measured, active)) {
        out.warnings.push_back(*w);
      }
      if (!was_failing && supervisor_.move_failing()) {
        ++counters_.move_failures;
        ask_move_failed = memory_ && memory_->meta.find("getData", "(s)");
      }
    }
    if (p.head && head_ && !head_lock_lost_) {
      verdict = supervisor_.on_head_readback(
          head, life_.has_value() && options_.disable_autonomous_life,
          awareness_.has_value() && options_.disable_basic_awareness,
          p.head->tolerance_rad, detail);
    }
  }
  if (ask_move_failed) {
    std::lock_guard lock(mutex_);
    move_failed_call_ =
        session_->call_async(*memory_, "getData", "(s)", {Value::string("ALMotion/MoveFailed")});
  }
  if (!verdict) return;
  if (*verdict == MotionSupervisor::HeadVerdict::kHolding) {
    std::lock_guard lock(mutex_);
    if (head_retaking_) {
      head_retaking_ = false;
      out.warnings.push_back("head lock re-established: the head holds its locked angles again");
    }
    return;
  }
  if (*verdict == MotionSupervisor::HeadVerdict::kLost) {
    const std::string why = "head lock lost: " + detail + " on " +
                            std::to_string(options_.supervisor.lost_probes) +
                            " read-backs in a row, although Autonomous Life and awareness were "
                            "turned off again and the head angles re-sent";
    {
      std::lock_guard lock(mutex_);
      head_lock_lost_ = true;
      head_lock_detail_ = why;
    }
    latch_fault(why);
    stop_base(why);
    return;
  }
  // kRetake: the robot took the head (or it drifted): turn the autonomy off again and re-send
  // the angles, without waiting for the replies.
  std::lock_guard lock(mutex_);
  if (!head_retaking_) {
    head_retaking_ = true;
    ++counters_.head_retakes;
    out.warnings.push_back("the robot took the head back (" + detail +
                           "): turning Autonomous Life and awareness off again and re-sending "
                           "the head angles");
  }
  try {
    if (life_ && options_.disable_autonomous_life && head.life_state &&
        *head.life_state != "disabled") {
      (void)session_->call_async(*life_, "setState", "(s)", {Value::string("disabled")});
    }
    if (awareness_ && options_.disable_basic_awareness && head.awareness_enabled &&
        *head.awareness_enabled) {
      (void)session_->call_async(*awareness_, "setEnabled", "(b)", {Value::boolean(false)});
    }
    const std::vector<float> targets = {static_cast<float>(p.head->head_yaw_rad),
                                        static_cast<float>(p.head->head_pitch_rad), 0.f, 0.f, 0.f};
    const auto speed = static_cast<float>(options_.head_max_speed_fraction);
    (void)session_->call_async(*motion_, "setAngles", "(mmf)",
                               {Value::strings(kLockedJoints), Value::floats(targets),
                                Value::float32(speed)});
  } catch (const std::exception&) {
    // A lost connection shows in state(); the next read-back judges again.
  }
}

RobotSupervision QiBridge::supervise() {
  RobotSupervision out;
  if (options_.supervise_period.count() > 0 && connected() && session_->is_connected()) {
    const std::int64_t now = mono_ns();
    Probe ready;
    PendingCall move_failed;
    {
      std::lock_guard lock(mutex_);
      if (probe_.active) {
        const bool all_in = (!probe_.velocity.valid() || probe_.velocity.ready()) &&
                            (!probe_.move_active.valid() || probe_.move_active.ready()) &&
                            (!probe_.life.valid() || probe_.life.ready()) &&
                            (!probe_.awareness.valid() || probe_.awareness.ready()) &&
                            (!probe_.head_angles.valid() || probe_.head_angles.ready());
        const bool overdue =
            now - probe_.sent_ns > std::chrono::nanoseconds(options_.call_timeout).count();
        if (all_in || overdue) {
          ready = std::move(probe_);
          probe_ = Probe();
        }
      }
      if (move_failed_call_.valid() && move_failed_call_.ready()) {
        move_failed = std::move(move_failed_call_);
        move_failed_call_ = PendingCall();
      }
    }
    try {
      if (ready.active) judge_probe(ready, out);
      if (auto v = reply_of(move_failed)) {
        // NAOqi's ALMotion/MoveFailed value: [cause, status, position].
        const Value& u = v->unwrapped();
        if ((u.kind() == TypeKind::kList || u.kind() == TypeKind::kTuple) &&
            !u.elements().empty() && u.elements()[0].unwrapped().kind() == TypeKind::kString) {
          out.warnings.push_back("ALMotion/MoveFailed on the robot: " +
                                 u.elements()[0].unwrapped().as_string());
        }
      }
      std::lock_guard lock(mutex_);
      if (!probe_.active && motion_ &&
          now - last_probe_ns_ >=
              std::chrono::nanoseconds(options_.supervise_period).count()) {
        send_probe_locked(now);
      }
    } catch (const std::exception&) {
      // A lost connection shows in state(); supervision resumes after a reconnect.
    }
  }
  std::lock_guard lock(mutex_);
  out.head_lock_lost = head_lock_lost_;
  out.head_lock_detail = head_lock_detail_;
  out.measured_velocity = measured_velocity_;
  out.move_active = move_active_;
  out.move_failing = supervisor_.move_failing();
  return out;
}

void QiBridge::watchdog_loop() {
  std::unique_lock lock(wd_mutex_);
  while (!wd_quit_) {
    wd_cv_.wait_for(lock, options_.watchdog_period);
    if (wd_quit_) break;
    lock.unlock();
    const std::int64_t now = mono_ns();
    if (moving_) {
      const std::int64_t since_move_ms = (now - last_move_ns_.load()) / 1'000'000;
      const std::int64_t since_frame_ms = (now - last_frame_ns_.load()) / 1'000'000;
      bool camera_on = false;
      {
        std::lock_guard g(mutex_);
        camera_on = camera_.has_value();
      }
      std::string why;
      if (since_move_ms > options_.watchdog_timeout.count()) {
        why = "watchdog: no move command for " + std::to_string(since_move_ms) + " ms (limit " +
              ms(options_.watchdog_timeout) + ")";
      } else if (camera_on && since_frame_ms > options_.frame_stall_timeout.count()) {
        why = "watchdog: frames stalled for " + std::to_string(since_frame_ms) + " ms (limit " +
              ms(options_.frame_stall_timeout) + ")";
      }
      if (!why.empty()) {
        stop_base(why);
        std::lock_guard g(mutex_);
        ++counters_.watchdog_stops;
      }
    }
    if (options_.head_resend_period.count() > 0 && connected() &&
        (now - last_head_resend_ns_.load()) / 1'000'000 > options_.head_resend_period.count()) {
      last_head_resend_ns_ = now;
      std::optional<HeadLockRequest> head;
      std::optional<ServiceHandle> motion;
      {
        std::lock_guard g(mutex_);
        head = head_;
        motion = motion_;
      }
      if (head && motion) {
        // Re-send the head angles (NAOqi's autonomous abilities may have moved the head);
        // the reply is not awaited.
        try {
          (void)session_->call_async(
              *motion, "setAngles", "(mmf)",
              {Value::strings({"HeadYaw", "HeadPitch"}),
               Value::floats({static_cast<float>(head->head_yaw_rad),
                              static_cast<float>(head->head_pitch_rad)}),
               Value::float32(static_cast<float>(options_.head_max_speed_fraction))});
        } catch (const std::exception&) {
        }
      }
    }
    lock.lock();
  }
}

}  // namespace pepper::naoqi_bridge::qi
