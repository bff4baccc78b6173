#pragma once
// QiSession: a qi-messaging client connection to a NAOqi service directory (PROTOCOL.md 3-5).
//
// connect() opens tcp:// or tcps:// (TLS 1.2+, the robot's self-signed certificate accepted,
// its SHA-256 fingerprint available and optionally pinned), sends the authenticate Call first
// (capability map with MessageFlags and, when a user is set, auth_user/auth_token), and checks
// __qi_auth_state. service(name) asks the directory (both ServiceInfo forms accepted) and fetches
// the service's MetaObject; calls resolve methods by name AND parameter signature. Several calls
// may be in flight; replies are matched by id. Unsolicited Capability messages are merged.
// Services are reached over the directory's connection (every NAOqi service of a Pepper lives in
// the process that hosts the directory); other endpoints are not dialled.
//
// Errors: typed BridgeError subclasses from errors.hpp whose text names the URL or
// service.method. A malformed message from the robot closes the connection (ProtocolViolation
// to the waiting calls). Losing the connection fails every pending call with ConnectionLost and
// runs the disconnect handler once (on the I/O thread: keep it short, never call back into
// the session from it synchronously).
//
// Threading: one internal I/O thread; every public method is thread-safe. The password is kept
// only in memory, never logged or returned by describe().

#include <chrono>
#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "naoqi_bridge/qi/codec.hpp"
#include "naoqi_bridge/qi/errors.hpp"
#include "naoqi_bridge/qi/message.hpp"
#include "naoqi_bridge/qi/meta.hpp"
#include "naoqi_bridge/qi/url.hpp"

namespace pepper::naoqi_bridge::qi {

struct SessionOptions {
  std::chrono::milliseconds connect_timeout{5000};  ///< TCP connect + TLS handshake + login
  std::chrono::milliseconds call_timeout{5000};     ///< default per-call reply timeout
  std::string user;                                 ///< empty: no login keys sent (NAOqi 2.5)
  std::string password;                             ///< auth_token; never logged
  std::string tls_pin_sha256;  ///< empty: accept any certificate; else required fingerprint
  /// tcps only: called with the URL and the certificate's SHA-256 fingerprint after the TLS
  /// handshake (and the pin check) and before anything is sent, the login included. Throwing
  /// (a TlsError naming what to do) closes the connection and fails connect() with it. Used for
  /// trust on first use (pepper_app's known-robots file).
  std::function<void(const std::string& url, const std::string& sha256)> verify_certificate;
  CodecLimits limits;          ///< applied to every received message

  std::vector<std::string> validate() const;
};

/// A service found in the directory, with its method table.
struct ServiceHandle {
  std::string name;
  std::uint32_t id = 0;
  MetaObject meta;
};

class QiSession;

/// A call in flight. get() waits for the reply; get_message() returns the raw Reply message
/// (used for image replies, decoded without copies). Both throw the typed errors.
class PendingCall {
 public:
  PendingCall() = default;
  Value get(std::optional<std::chrono::milliseconds> timeout = std::nullopt);
  Message get_message(std::optional<std::chrono::milliseconds> timeout = std::nullopt);
  bool ready() const;
  /// Waits up to `t` for the answer (reply, error or loss); true when it is there. Never throws.
  bool wait(std::chrono::milliseconds t) const;
  bool valid() const { return future_.valid(); }
  const std::string& what() const { return description_; }

 private:
  friend class QiSession;
  std::shared_future<Message> future_;
  std::string description_;  ///< "ALMotion.move"
  std::string return_signature_;
  std::uint32_t id_ = 0;
  std::chrono::milliseconds default_timeout_{5000};
  std::function<void(std::uint32_t)> forget_;  ///< drops the pending entry on timeout
  std::function<void(const std::string&)> on_protocol_error_;
};

class QiSession {
 public:
  explicit QiSession(SessionOptions options = {});
  ~QiSession();
  QiSession(const QiSession&) = delete;
  QiSession& operator=(const QiSession&) = delete;

  /// Connects and authenticates. Throws ConnectError, TlsError, AuthenticationError,
  /// ProtocolViolation. Calling it again reconnects (closing any previous connection).
  void connect(const std::string& url);
  /// Closes the connection (pending calls fail with ConnectionLost). Never throws.
  void close() noexcept;
  bool is_connected() const;

  /// "tcps://10.0.0.5:9503 (user nao)"; never contains the password.
  std::string describe() const;
  /// SHA-256 fingerprint of the robot's TLS certificate ("AB:CD:..."), empty on tcp.
  std::string peer_certificate_sha256() const;
  /// Capabilities the server advertised (authenticate reply plus Capability messages).
  CapabilityMap server_capabilities() const;

  /// Directory lookup + MetaObject. Throws ServiceNotFound naming the service.
  ServiceHandle service(const std::string& name);

  /// Sends a Call of `method(parameters_signature)`; `args` are converted to the parameter
  /// types (numbers widened/narrowed, values wrapped into `m` where declared). Throws
  /// MethodNotFound (listing the overloads that exist) or ConnectionLost.
  PendingCall call_async(const ServiceHandle& service, std::string_view method,
                         std::string_view parameters_signature, std::vector<Value> args);
  Value call(const ServiceHandle& service, std::string_view method,
             std::string_view parameters_signature, std::vector<Value> args,
             std::optional<std::chrono::milliseconds> timeout = std::nullopt);
  /// Low level: a Call with an already-encoded payload.
  PendingCall call_raw(std::uint32_t service, std::uint32_t object, std::uint32_t action,
                       std::vector<std::uint8_t> payload, std::string description,
                       std::string return_signature);

  /// Runs once per lost connection with the reason (I/O thread).
  void set_disconnect_handler(std::function<void(const std::string& reason)> handler);
  /// Why the last connection ended ("" while connected or never connected).
  std::string disconnect_reason() const;

  const SessionOptions& options() const { return options_; }

 private:
  struct Impl;
  SessionOptions options_;
  std::shared_ptr<Impl> impl_;
};

/// Reads a password from a file (first line, trailing newline removed). Throws BridgeError.
std::string read_password_file(const std::string& path);
/// Reads a password from the environment variable `name`; nullopt when unset.
std::optional<std::string> read_password_env(const std::string& name);
/// Prompts on the terminal with echo off; throws BridgeError when stdin is not a terminal.
std::string prompt_password(const std::string& prompt);

}  // namespace pepper::naoqi_bridge::qi
