// QiSession: qi-messaging client over Boost.Asio (tcp and tcps), see the header.
#include "naoqi_bridge/qi/session.hpp"

#include <termios.h>
#include <unistd.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/asio/steady_timer.hpp>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <thread>

#include "connection.hpp"

namespace pepper::naoqi_bridge::qi {

namespace asio = boost::asio;
using tcp = asio::ip::tcp;

std::vector<std::string> SessionOptions::validate() const {
  std::vector<std::string> errors;
  if (connect_timeout.count() < 1 || connect_timeout.count() > 600000) {
    errors.push_back("connect_timeout must be in 1..600000 ms, got " +
                     std::to_string(connect_timeout.count()));
  }
  if (call_timeout.count() < 1 || call_timeout.count() > 600000) {
    errors.push_back("call_timeout must be in 1..600000 ms, got " +
                     std::to_string(call_timeout.count()));
  }
  if (user.empty() && !password.empty()) errors.push_back("password given without a user");
  if (!tls_pin_sha256.empty() && detail::normalize_fingerprint(tls_pin_sha256).size() != 64) {
    errors.push_back("tls_pin_sha256 must be 64 hex digits (colons allowed), got '" +
                     tls_pin_sha256 + "'");
  }
  for (const auto& e : limits.validate()) errors.push_back("limits." + e);
  return errors;
}

// ---------------------------------------------------------------------------------------------

struct QiSession::Impl : std::enable_shared_from_this<QiSession::Impl> {
  asio::io_context io;
  std::optional<asio::executor_work_guard<asio::io_context::executor_type>> work;
  std::thread thread;

  mutable std::mutex mutex;
  std::unique_ptr<asio::ssl::context> ssl_ctx;
  std::shared_ptr<detail::MessageConnection> conn;
  std::uint64_t generation = 0;
  std::map<std::uint32_t, std::shared_ptr<std::promise<Message>>> pending;
  std::atomic<std::uint32_t> next_id{1};
  std::atomic<bool> connected{false};
  CapabilityMap caps;
  std::string reason;
  std::string fingerprint;
  Url url;
  std::string user;
  std::function<void(const std::string&)> on_disconnect;
  std::map<std::string, ServiceHandle> services;
  CodecLimits limits;
  std::chrono::milliseconds call_timeout{5000};

  Impl() {
    work.emplace(asio::make_work_guard(io));
    thread = std::thread([this] { io.run(); });
  }
  ~Impl() { shutdown(); }

  /// Stops and joins the I/O thread. Called by the owner (~QiSession) so that the thread is
  /// never joined from itself, whoever drops the last reference.
  void shutdown() {
    work.reset();
    io.stop();
    if (thread.joinable() && thread.get_id() != std::this_thread::get_id()) thread.join();
    if (thread.joinable()) thread.detach();
  }

  void handle_message(std::uint64_t gen, Message msg) {
    switch (msg.header.type) {
      case MessageType::kReply:
      case MessageType::kError:
      case MessageType::kCanceled: {
        std::shared_ptr<std::promise<Message>> p;
        {
          std::lock_guard lock(mutex);
          if (gen != generation) return;
          auto it = pending.find(msg.header.id);
          if (it == pending.end()) return;  // timed out earlier: drop
          p = it->second;
          pending.erase(it);
        }
        p->set_value(std::move(msg));
        return;
      }
      case MessageType::kCapability: {
        try {
          auto more = decode_capabilities(msg.bytes(), limits);
          std::lock_guard lock(mutex);
          for (auto& [k, v] : more) caps[k] = v;
        } catch (const ProtocolError& e) {
          protocol_error(gen, std::string("malformed Capability message: ") + e.what());
        }
        return;
      }
      case MessageType::kCall: {
        // We expose no objects: answer so the robot does not wait.
        std::shared_ptr<detail::MessageConnection> c;
        {
          std::lock_guard lock(mutex);
          if (gen == generation) c = conn;
        }
        if (c) {
          MessageHeader h = msg.header;
          h.type = MessageType::kError;
          h.flags = 0;
          c->send(h, encode_error_text("this client serves no objects"));
        }
        return;
      }
      default:
        return;  // Post, Event, Cancel: nothing to do for this client
    }
  }

  void handle_close(std::uint64_t gen, const std::string& why) {
    std::map<std::uint32_t, std::shared_ptr<std::promise<Message>>> failed;
    std::function<void(const std::string&)> handler;
    std::string where;
    {
      std::lock_guard lock(mutex);
      if (gen != generation) return;
      connected = false;
      reason = why;
      failed.swap(pending);
      handler = on_disconnect;
      where = url.to_string();
      services.clear();
    }
    for (auto& [id, p] : failed) {
      p->set_exception(
          std::make_exception_ptr(ConnectionLost("connection to " + where + " lost: " + why)));
    }
    if (handler) handler(why);
  }

  void protocol_error(std::uint64_t gen, const std::string& why) {
    std::shared_ptr<detail::MessageConnection> c;
    {
      std::lock_guard lock(mutex);
      if (gen == generation) c = conn;
    }
    if (c) c->close(why);
  }

  PendingCall send_call(std::uint32_t service, std::uint32_t object, std::uint32_t action,
                        std::vector<std::uint8_t> payload, std::string description,
                        std::string return_signature) {
    auto p = std::make_shared<std::promise<Message>>();
    PendingCall call;
    call.future_ = p->get_future().share();
    call.description_ = std::move(description);
    call.return_signature_ = std::move(return_signature);
    call.default_timeout_ = call_timeout;
    std::shared_ptr<detail::MessageConnection> c;
    std::uint64_t gen = 0;
    {
      std::lock_guard lock(mutex);
      if (!connected || !conn) {
        throw ConnectionLost(call.description_ + ": not connected to " + url.to_string() +
                             (reason.empty() ? "" : " (" + reason + ")"));
      }
      call.id_ = next_id.fetch_add(1);
      pending[call.id_] = p;
      c = conn;
      gen = generation;
    }
    std::weak_ptr<Impl> weak = shared_from_this();
    call.forget_ = [weak](std::uint32_t id) {
      if (auto self = weak.lock()) {
        std::lock_guard lock(self->mutex);
        self->pending.erase(id);
      }
    };
    call.on_protocol_error_ = [weak, gen](const std::string& why) {
      if (auto self = weak.lock()) self->protocol_error(gen, why);
    };
    MessageHeader h;
    h.id = call.id_;
    h.type = MessageType::kCall;
    h.service = service;
    h.object = object;
    h.action = action;
    c->send(h, std::move(payload));
    return call;
  }
};

// ---------------------------------------------------------------------------------------------
// PendingCall

bool PendingCall::ready() const {
  return future_.valid() && future_.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
}

bool PendingCall::wait(std::chrono::milliseconds t) const {
  return future_.valid() && future_.wait_for(t) == std::future_status::ready;
}

Message PendingCall::get_message(std::optional<std::chrono::milliseconds> timeout) {
  if (!future_.valid()) throw BridgeError(description_ + ": no call in flight");
  const auto t = timeout.value_or(default_timeout_);
  if (future_.wait_for(t) != std::future_status::ready) {
    if (forget_) forget_(id_);
    throw CallTimeout(description_ + ": no reply within " + std::to_string(t.count()) + " ms");
  }
  Message msg = future_.get();  // rethrows ConnectionLost
  if (msg.header.type == MessageType::kError) {
    std::string text;
    try {
      text = decode_error_text(msg.bytes(), CodecLimits{});
    } catch (const ProtocolError& e) {
      if (on_protocol_error_) on_protocol_error_(std::string("malformed Error reply: ") + e.what());
      throw ProtocolViolation(description_ + ": malformed error reply: " + e.what());
    }
    throw RemoteCallError(description_ + " failed on the robot: " + text);
  }
  if (msg.header.type == MessageType::kCanceled) {
    throw RemoteCallError(description_ + ": call canceled by the robot");
  }
  return msg;
}

Value PendingCall::get(std::optional<std::chrono::milliseconds> timeout) {
  Message msg = get_message(timeout);
  try {
    const Type rt = parse_signature(return_signature_.empty() ? "v" : return_signature_);
    if (msg.header.flags & flags::kDynamicPayload) {
      Value v = decode(Type::of(TypeKind::kDynamic), msg.bytes(), CodecLimits{}, msg.payload);
      return rt.kind == TypeKind::kDynamic ? v : convert(v, rt);
    }
    if (rt.kind == TypeKind::kVoid) {
      // Some servers send a value for void methods; ignore whatever came.
      return Value();
    }
    return decode(rt, msg.bytes(), CodecLimits{}, msg.payload);
  } catch (const ProtocolError& e) {
    if (on_protocol_error_) on_protocol_error_(std::string("malformed reply: ") + e.what());
    throw ProtocolViolation(description_ + ": malformed reply (connection closed): " + e.what());
  }
}

// ---------------------------------------------------------------------------------------------
// QiSession

QiSession::QiSession(SessionOptions options)
    : options_(std::move(options)), impl_(std::make_shared<Impl>()) {
  const auto errors = options_.validate();
  if (!errors.empty()) throw BridgeError("SessionOptions: " + errors.front());
  impl_->limits = options_.limits;
  impl_->call_timeout = options_.call_timeout;
  impl_->user = options_.user;
}

QiSession::~QiSession() {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->on_disconnect = nullptr;
  }
  close();
  impl_->shutdown();
}

void QiSession::close() noexcept {
  std::shared_ptr<detail::MessageConnection> c;
  {
    std::lock_guard lock(impl_->mutex);
    c = impl_->conn;
  }
  if (c) {
    c->close("closed by the client");
    // Wait briefly until the close has run so pending calls fail promptly.
    for (int i = 0; i < 200 && impl_->connected; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
}

bool QiSession::is_connected() const { return impl_->connected; }

std::string QiSession::describe() const {
  std::lock_guard lock(impl_->mutex);
  std::string s = impl_->url.host.empty() ? "(not connected)" : impl_->url.to_string();
  if (!impl_->user.empty()) s += " (user " + impl_->user + ")";
  return s;
}

std::string QiSession::peer_certificate_sha256() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->fingerprint;
}

CapabilityMap QiSession::server_capabilities() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->caps;
}

void QiSession::set_disconnect_handler(std::function<void(const std::string&)> handler) {
  std::lock_guard lock(impl_->mutex);
  impl_->on_disconnect = std::move(handler);
}

std::string QiSession::disconnect_reason() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->reason;
}

void QiSession::connect(const std::string& url_text) {
  const Url url = parse_url(url_text);
  close();
  const std::string where = url.to_string();

  std::unique_ptr<asio::ssl::context> ctx;
  if (url.tls) {
    ctx = std::make_unique<asio::ssl::context>(asio::ssl::context::tls_client);
    ctx->set_options(asio::ssl::context::default_workarounds | asio::ssl::context::no_sslv2 |
                     asio::ssl::context::no_sslv3 | asio::ssl::context::no_tlsv1 |
                     asio::ssl::context::no_tlsv1_1);
    // Robots use self-signed certificates (libqi does not verify either): accept, report the
    // fingerprint, and let the user pin it.
    ctx->set_verify_mode(asio::ssl::verify_none);
  }
  auto conn = std::make_shared<detail::MessageConnection>(impl_->io, ctx.get(), options_.limits);

  // Resolve, connect and handshake on the I/O thread, bounded by connect_timeout.
  auto done = std::make_shared<std::promise<std::string>>();  // "" = success, else the error
  auto fut = done->get_future();
  auto resolver = std::make_shared<tcp::resolver>(impl_->io);
  auto timer = std::make_shared<asio::steady_timer>(impl_->io, options_.connect_timeout);
  auto finished = std::make_shared<std::atomic<bool>>(false);
  auto finish = [done, finished, timer](const std::string& err) {
    if (finished->exchange(true)) return;
    timer->cancel();
    done->set_value(err);
  };
  const auto timeout_ms = options_.connect_timeout.count();
  timer->async_wait([finish, conn, resolver, timeout_ms](const boost::system::error_code& ec) {
    if (ec) return;
    resolver->cancel();
    boost::system::error_code ignored;
    conn->socket().close(ignored);
    finish("timed out after " + std::to_string(timeout_ms) + " ms");
  });
  asio::post(impl_->io, [=]() {
    resolver->async_resolve(
        url.host, std::to_string(url.port),
        [=](const boost::system::error_code& ec, tcp::resolver::results_type results) {
          if (ec) {
            finish("cannot resolve host '" + url.host + "': " + ec.message());
            return;
          }
          asio::async_connect(
              conn->socket(), results,
              [=](const boost::system::error_code& ec2, const tcp::endpoint&) {
                if (ec2) {
                  finish(ec2.message());
                  return;
                }
                boost::system::error_code ignored;
                conn->socket().set_option(tcp::no_delay(true), ignored);
                if (!conn->tls()) {
                  finish("");
                  return;
                }
                SSL_set_tlsext_host_name(conn->tls()->native_handle(), url.host.c_str());
                conn->tls()->async_handshake(asio::ssl::stream_base::client,
                                             [=](const boost::system::error_code& ec3) {
                                               finish(ec3 ? "TLS: " + ec3.message() : "");
                                             });
              });
        });
  });
  if (fut.wait_for(options_.connect_timeout + std::chrono::seconds(2)) !=
      std::future_status::ready) {
    conn->close("connect timed out");
    throw ConnectError("cannot reach " + where + ": timed out");
  }
  const std::string err = fut.get();
  if (!err.empty()) {
    conn->close("connect failed");
    if (err.rfind("TLS: ", 0) == 0) {
      throw TlsError("TLS handshake with " + where + " failed: " + err.substr(5) +
                     " (is it a tcps:// port? NAOqi 2.9 listens on tcps://ROBOT:9503)");
    }
    throw ConnectError("cannot reach " + where + ": " + err);
  }

  std::string fingerprint;
  if (conn->tls()) {
    fingerprint = detail::peer_certificate_sha256(*conn->tls());
    if (!options_.tls_pin_sha256.empty() &&
        detail::normalize_fingerprint(fingerprint) !=
            detail::normalize_fingerprint(options_.tls_pin_sha256)) {
      conn->close("certificate pin mismatch");
      throw TlsError("TLS certificate of " + where + " has SHA-256 fingerprint " + fingerprint +
                     ", which does not match the pinned " + options_.tls_pin_sha256);
    }
    if (options_.verify_certificate) {
      try {
        options_.verify_certificate(url.to_string(), fingerprint);
      } catch (...) {
        conn->close("certificate not trusted");  // nothing, no login, was sent
        throw;
      }
    }
  }

  std::uint64_t gen = 0;
  {
    std::lock_guard lock(impl_->mutex);
    gen = ++impl_->generation;
    impl_->conn = conn;
    impl_->ssl_ctx = std::move(ctx);
    impl_->url = url;
    impl_->fingerprint = fingerprint;
    impl_->caps.clear();
    impl_->services.clear();
    impl_->reason.clear();
    impl_->connected = true;
  }
  std::weak_ptr<Impl> weak = impl_;
  asio::post(impl_->io, [weak, conn, gen] {
    conn->start(
        [weak, gen](Message m) {
          if (auto self = weak.lock()) self->handle_message(gen, std::move(m));
        },
        [weak, gen](const std::string& why) {
          if (auto self = weak.lock()) self->handle_close(gen, why);
        });
  });

  // Authenticate first (PROTOCOL.md 3.1, 8).
  CapabilityMap mine;
  mine["MessageFlags"] = Value::boolean(true);
  std::string token = options_.password;
  for (int round = 0; round < 4; ++round) {
    if (!options_.user.empty()) {
      mine["auth_user"] = Value::string(options_.user);
      mine["auth_token"] = Value::string(token);
    }
    Message reply;
    try {
      auto call = impl_->send_call(ids::kServerService, 0, ids::kAuthenticateAction,
                                   encode_capabilities(mine), "authenticate", "{sm}");
      reply = call.get_message(options_.connect_timeout);
    } catch (const RemoteCallError& e) {
      close();
      const std::string text = e.what();
      const auto pos = text.find("failed on the robot: ");
      const std::string server_text = pos == std::string::npos ? text : text.substr(pos + 21);
      if (options_.user.empty()) {
        throw AuthenticationError("login required by " + where +
                                  " (give a user and a password): " + server_text);
      }
      throw AuthenticationError("wrong user or password for " + where + " (user '" + options_.user +
                                "'): " + server_text);
    } catch (const ConnectionLost& e) {
      close();
      throw AuthenticationError(
          "the robot closed the connection during login to " + where +
          (url.tls ? "" : " (is it a tcps:// port? NAOqi 2.9 listens on tcps://ROBOT:9503)") +
          ": " + e.what());
    } catch (const BridgeError& e) {
      close();
      throw AuthenticationError("authentication with " + where + " failed: " + e.what());
    }
    CapabilityMap theirs;
    try {
      theirs = decode_capabilities(reply.bytes(), options_.limits);
    } catch (const ProtocolError& e) {
      close();
      throw ProtocolViolation("authenticate reply from " + where + " is malformed: " + e.what());
    }
    std::int64_t state = 3;  // a server that sends no state accepted us (older NAOqi)
    if (auto it = theirs.find("__qi_auth_state"); it != theirs.end()) {
      try {
        state = it->second.as_int();
      } catch (const ProtocolError&) {
        state = 1;
      }
    }
    {
      std::lock_guard lock(impl_->mutex);
      for (auto& [k, v] : theirs) {
        if (k.rfind("__qi_auth", 0) != 0 && k.rfind("auth_", 0) != 0) impl_->caps[k] = v;
      }
    }
    if (state == 3) return;
    if (state == 2) {
      if (auto it = theirs.find("auth_newToken"); it != theirs.end()) {
        try {
          token = it->second.as_string();
        } catch (const ProtocolError&) {
        }
      }
      continue;
    }
    close();
    throw AuthenticationError("wrong user or password for " + where +
                              ": the robot answered "
                              "authentication state " +
                              std::to_string(state));
  }
  close();
  throw AuthenticationError("authentication with " + where + " did not complete after 4 rounds");
}

PendingCall QiSession::call_raw(std::uint32_t service, std::uint32_t object, std::uint32_t action,
                                std::vector<std::uint8_t> payload, std::string description,
                                std::string return_signature) {
  return impl_->send_call(service, object, action, std::move(payload), std::move(description),
                          std::move(return_signature));
}

ServiceHandle QiSession::service(const std::string& name) {
  {
    std::lock_guard lock(impl_->mutex);
    if (auto it = impl_->services.find(name); it != impl_->services.end()) return it->second;
  }
  std::vector<std::uint8_t> payload;
  Writer w(payload);
  w.string(name);
  Message reply;
  try {
    reply = call_raw(ids::kDirectoryService, ids::kMainObject, ids::kDirectoryServiceAction,
                     std::move(payload), "ServiceDirectory.service(\"" + name + "\")",
                     ServiceInfo::signature_v7())
                .get_message();
  } catch (const RemoteCallError& e) {
    throw ServiceNotFound("service '" + name + "' not found on " + describe() + ": " + e.what());
  }
  ServiceInfo info;
  try {
    if (reply.header.flags & flags::kDynamicPayload) {
      // One `m` holding the ServiceInfo tuple: re-encode the inner value and decode it plainly.
      const Value v = decode(Type::of(TypeKind::kDynamic), reply.bytes(), options_.limits);
      info = ServiceInfo::decode(encode(v.unwrapped()), options_.limits);
    } else {
      info = ServiceInfo::decode(reply.bytes(), options_.limits);
    }
  } catch (const ProtocolError& e) {
    close();
    throw ProtocolViolation("ServiceInfo of '" + name + "' is malformed: " + e.what());
  }
  std::vector<std::uint8_t> arg;
  Writer wa(arg);
  wa.u32(0);
  const Value mo_value = call_raw(info.service_id, ids::kMainObject, ids::kMetaObject,
                                  std::move(arg), name + ".metaObject", MetaObject::signature())
                             .get();
  ServiceHandle handle;
  handle.name = name;
  handle.id = info.service_id;
  try {
    handle.meta = MetaObject::from_value(mo_value);
  } catch (const ProtocolError& e) {
    throw ProtocolViolation(name + ".metaObject: unexpected layout: " + e.what());
  }
  std::lock_guard lock(impl_->mutex);
  impl_->services[name] = handle;
  return handle;
}

PendingCall QiSession::call_async(const ServiceHandle& service, std::string_view method,
                                  std::string_view parameters_signature, std::vector<Value> args) {
  const std::string desc = service.name + "." + std::string(method);
  const MetaMethod* m = service.meta.find(method, parameters_signature);
  if (!m) {
    std::string have;
    for (const auto* o : service.meta.overloads(method)) {
      have += (have.empty() ? "" : ", ") + o->name + o->parameters_signature;
    }
    throw MethodNotFound(service.name + " has no method " + std::string(method) +
                         std::string(parameters_signature) +
                         (have.empty() ? " (no method of that name)" : " (it has: " + have + ")"));
  }
  std::vector<std::uint8_t> payload;
  try {
    const Type params = parse_signature(m->parameters_signature);
    if (params.children.size() != args.size()) {
      throw BridgeError(desc + m->parameters_signature + ": " + std::to_string(args.size()) +
                        " arguments given for " + std::to_string(params.children.size()));
    }
    Writer w(payload);
    for (std::size_t i = 0; i < args.size(); ++i) {
      encode_value(convert(args[i], params.children[i]), w);
    }
  } catch (const ProtocolError& e) {
    throw BridgeError(desc + m->parameters_signature + ": bad argument: " + e.what());
  }
  return call_raw(service.id, ids::kMainObject, m->uid, std::move(payload), desc,
                  m->return_signature);
}

Value QiSession::call(const ServiceHandle& service, std::string_view method,
                      std::string_view parameters_signature, std::vector<Value> args,
                      std::optional<std::chrono::milliseconds> timeout) {
  return call_async(service, method, parameters_signature, std::move(args)).get(timeout);
}

// ---------------------------------------------------------------------------------------------
// Passwords

std::string read_password_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw BridgeError("cannot read the password file '" + path + "'");
  std::string line;
  std::getline(in, line);
  while (!line.empty() && (line.back() == '\r' || line.back() == '\n')) line.pop_back();
  if (line.empty()) throw BridgeError("the password file '" + path + "' is empty");
  return line;
}

std::optional<std::string> read_password_env(const std::string& name) {
  const char* v = std::getenv(name.c_str());
  if (!v) return std::nullopt;
  return std::string(v);
}

std::string prompt_password(const std::string& prompt) {
  if (!isatty(STDIN_FILENO)) {
    throw BridgeError(
        "a password is needed but stdin is not a terminal: use --password-file "
        "or the PEPPER_PASSWORD environment variable");
  }
  std::cerr << prompt << std::flush;
  termios old_attr{};
  tcgetattr(STDIN_FILENO, &old_attr);
  termios no_echo = old_attr;
  no_echo.c_lflag &= ~static_cast<tcflag_t>(ECHO);
  tcsetattr(STDIN_FILENO, TCSANOW, &no_echo);
  std::string line;
  std::getline(std::cin, line);
  tcsetattr(STDIN_FILENO, TCSANOW, &old_attr);
  std::cerr << "\n";
  return line;
}

}  // namespace pepper::naoqi_bridge::qi
