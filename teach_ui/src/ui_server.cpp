// UiServer implementation: one Asio I/O thread, Beast HTTP sessions that serve static files and
// upgrade "/ws" to WebSocket sessions. See teach_ui/ui_server.hpp for the contract and
// docs/teach_ui.md for the wire format.
//
// Everything below the public methods runs on the I/O thread, so sessions, the snapshot and the
// per-client pending data need no locks; public methods post work to that thread. Only the intent
// queue (read by the app) and the counters are shared, behind a mutex and atomics.
#include "teach_ui/ui_server.hpp"

#include <atomic>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <condition_variable>
#include <deque>
#include <fstream>
#include <future>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "teach_ui/static_files.hpp"
#include "teach_ui/web_root.hpp"
#include "teach_ui/wire.hpp"

namespace pepper::teach_ui {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using Message = std::shared_ptr<const std::string>;

constexpr std::size_t kMaxRequestHeaderBytes = 8 * 1024;
constexpr std::size_t kMaxRequestBodyBytes = 1024;         // we serve GET/HEAD only
constexpr std::uintmax_t kMaxServedFileBytes = 16u << 20;  // static assets are small
constexpr auto kHttpTimeout = std::chrono::seconds(30);
constexpr auto kWsHandshakeTimeout = std::chrono::seconds(10);
constexpr std::size_t kMaxQueuedTextMessages = 64;         // hello + pongs waiting to be written
constexpr auto kStopDrainTime = std::chrono::milliseconds(500);  // stop(): send what is queued
constexpr auto kWsIdleTimeout = std::chrono::seconds(10);  // pings at half of it keep it alive

}  // namespace

namespace detail {

class WsSession;

struct UiServerImpl {
  explicit UiServerImpl(UiOptions o) : options(std::move(o)) {}

  void log(UiLogLevel level, const std::string& text) const {
    if (options.log) options.log(level, text);
  }
  void push_intent(Intent intent);
  void remove_session(const std::shared_ptr<WsSession>& s);

  UiOptions options;
  net::io_context ioc{1};
  std::optional<tcp::acceptor> acceptor;
  std::thread thread;
  std::atomic<bool> running{false};
  bool started_once = false;
  std::atomic<std::uint16_t> bound_port{0};
  std::string base_url;
  std::filesystem::path root;
  std::set<std::string> allowed_origins;

  // I/O thread only.
  std::set<std::shared_ptr<WsSession>> sessions;
  std::uint64_t next_client_id = 1;
  nlohmann::json snapshot_state = nlohmann::json::object();
  std::map<std::string, Message> snapshot_images;
  std::deque<nlohmann::json> sample_history;
  Message latest_frame;

  // Shared with the app's threads.
  std::mutex intent_mutex;
  std::condition_variable intent_cv;
  std::deque<Intent> intents;
  std::function<void(const Intent&)> handler;
  std::atomic<std::uint64_t> frame_seq{0};

  std::atomic<std::size_t> clients{0};
  std::atomic<std::uint64_t> frames_published{0};
  std::atomic<std::uint64_t> frames_sent{0};
  std::atomic<std::uint64_t> frames_dropped{0};
  std::atomic<std::uint64_t> intents_received{0};
  std::atomic<std::uint64_t> malformed_messages{0};
  std::atomic<std::uint64_t> http_requests{0};
};

using Impl = UiServerImpl;

bool is_stop_like(IntentKind k) {
  return k == IntentKind::kDriveReleased || k == IntentKind::kEmergencyStop;
}

// ---------------------------------------------------------------- WebSocket session
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(tcp::socket socket, Impl& impl, std::uint64_t id)
      : ws_(std::move(socket)), impl_(impl), id_(id), drive_timer_(impl.ioc) {}

  void run(http::request<http::string_body> req) {
    websocket::stream_base::timeout t{};
    t.handshake_timeout = kWsHandshakeTimeout;
    t.idle_timeout = kWsIdleTimeout;
    t.keep_alive_pings = true;
    ws_.set_option(t);
    ws_.read_message_max(impl_.options.max_message_bytes);
    ws_.auto_fragment(false);
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& res) { res.set(http::field::server, "pepper-teach-ui"); }));
    ws_.async_accept(req,
                     [self = shared_from_this()](beast::error_code ec) { self->on_accept(ec); });
  }

  std::uint64_t id() const { return id_; }

  void queue_text(Message m) {
    text_out_.push_back(std::move(m));
    maybe_write();
  }
  void queue_state(const nlohmann::json& patch) {
    for (const auto& [key, value] : patch.items()) pending_state_[key] = value;
    maybe_write();
  }
  void queue_image(const std::string& name, Message m) {
    pending_images_[name] = std::move(m);
    maybe_write();
  }
  void queue_samples(const nlohmann::json& samples) {
    for (const auto& s : samples) {
      pending_samples_.push_back(s);
      if (pending_samples_.size() > impl_.options.sample_history) pending_samples_.pop_front();
    }
    maybe_write();
  }
  void queue_samples_reset() {
    pending_samples_.clear();
    samples_reset_ = true;
    maybe_write();
  }
  void queue_frame(Message m) {
    if (pending_frame_) ++impl_.frames_dropped;
    pending_frame_ = std::move(m);
    maybe_write();
  }

  /// Nothing but a camera frame is waiting to be sent (frames may be dropped; state may not).
  bool drained() const {
    return gone_ || !accepted_ ||
           (!writing_ && text_out_.empty() && pending_state_.empty() && pending_images_.empty() &&
            pending_samples_.empty() && !samples_reset_);
  }

  /// Hard close (server stop): cancels every pending operation.
  void shutdown() {
    beast::error_code ec;
    drive_timer_.cancel();
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ec);
    beast::get_lowest_layer(ws_).close();
    on_gone("server stopping");
  }

 private:
  void on_accept(beast::error_code ec) {
    if (ec) {
      impl_.log(UiLogLevel::kInfo, "ui: websocket handshake failed: " + ec.message());
      on_gone("handshake failed");
      return;
    }
    accepted_ = true;
    impl_.log(UiLogLevel::kInfo, "ui: client " + std::to_string(id_) + " connected");
    // Snapshot for a late joiner: hello, state, samples, images, latest frame.
    nlohmann::json hello = {{"type", "hello"},
                            {"client_id", id_},
                            {"limits",
                             {{"max_v_m_s", impl_.options.limits.max_v_m_s},
                              {"max_omega_rad_s", impl_.options.limits.max_omega_rad_s}}},
                            {"drive_timeout_s", impl_.options.drive_timeout_s},
                            {"max_message_bytes", impl_.options.max_message_bytes}};
    text_out_.push_back(std::make_shared<const std::string>(hello.dump()));
    if (!impl_.snapshot_state.empty()) pending_state_ = impl_.snapshot_state;
    pending_samples_.assign(impl_.sample_history.begin(), impl_.sample_history.end());
    samples_reset_ = true;
    pending_images_ = impl_.snapshot_images;
    pending_frame_ = impl_.latest_frame;
    do_read();
    maybe_write();
  }

  void do_read() {
    ws_.async_read(read_buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      self->on_read(ec);
    });
  }

  void on_read(beast::error_code ec) {
    if (ec) {
      if (ec == websocket::error::message_too_big) {
        impl_.log(UiLogLevel::kWarning, "ui: client " + std::to_string(id_) +
                                            " sent a message over the size limit; closing it");
        ++impl_.malformed_messages;
      }
      on_gone(ec == websocket::error::closed ? "closed by client" : ec.message());
      return;
    }
    const std::string text = beast::buffers_to_string(read_buffer_.data());
    read_buffer_.consume(read_buffer_.size());
    if (!ws_.got_text()) {
      ++impl_.malformed_messages;
      impl_.log(UiLogLevel::kWarning,
                "ui: ignored a binary message from client " + std::to_string(id_));
    } else {
      handle_text(text);
    }
    do_read();
  }

  void handle_text(const std::string& text) {
    // Ping is not an intent: answer at once so the page can show its round-trip time.
    const nlohmann::json msg = nlohmann::json::parse(text, nullptr, false);
    if (msg.is_object() && msg.value("type", "") == "ping") {
      nlohmann::json pong = {{"type", "pong"}};
      if (const auto t = msg.find("t_ms"); t != msg.end() && t->is_number()) pong["t_ms"] = *t;
      // A client that pings but never reads must not grow our queue without bound.
      if (text_out_.size() < kMaxQueuedTextMessages) {
        queue_text(std::make_shared<const std::string>(pong.dump()));
      }
      return;
    }
    IntentParse parsed = parse_intent(text, impl_.options.limits, id_);
    if (!parsed.intent) {
      ++impl_.malformed_messages;
      impl_.log(UiLogLevel::kWarning, "ui: ignored malformed message from client " +
                                          std::to_string(id_) + ": " + parsed.error);
      return;
    }
    Intent& intent = *parsed.intent;
    if (intent.kind == IntentKind::kDrive) {
      driving_ = intent.v_m_s != 0.0 || intent.omega_rad_s != 0.0;
      arm_drive_watchdog();
    } else if (is_stop_like(intent.kind)) {
      driving_ = false;
      drive_timer_.cancel();
    }
    impl_.push_intent(std::move(intent));
  }

  void arm_drive_watchdog() {
    if (!driving_ || impl_.options.drive_timeout_s <= 0.0) {
      drive_timer_.cancel();
      return;
    }
    drive_timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(impl_.options.drive_timeout_s)));
    drive_timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (ec || !self->driving_ || self->gone_) return;
      self->driving_ = false;
      self->impl_.log(UiLogLevel::kWarning, "ui: client " + std::to_string(self->id_) +
                                                " stopped refreshing its drive intent");
      self->emit_server_release("drive_timeout");
    });
  }

  void emit_server_release(const char* reason) {
    Intent stop;
    stop.kind = IntentKind::kDriveReleased;
    stop.source = IntentSource::kServer;
    stop.client_id = id_;
    stop.reason = reason;
    impl_.push_intent(std::move(stop));
  }

  void maybe_write() {
    if (writing_ || gone_ || !accepted_) return;
    Message next;
    bool binary = false;
    bool is_frame = false;
    if (!text_out_.empty()) {
      next = std::move(text_out_.front());
      text_out_.pop_front();
    } else if (!pending_state_.empty()) {
      nlohmann::json m = {{"type", "state"}, {"state", std::move(pending_state_)}};
      pending_state_ = nlohmann::json::object();
      next = std::make_shared<const std::string>(
          m.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    } else if (samples_reset_ || !pending_samples_.empty()) {
      nlohmann::json m = {
          {"type", "samples"}, {"reset", samples_reset_}, {"samples", nlohmann::json::array()}};
      for (auto& s : pending_samples_) m["samples"].push_back(std::move(s));
      pending_samples_.clear();
      samples_reset_ = false;
      next = std::make_shared<const std::string>(
          m.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    } else if (!pending_images_.empty()) {
      next = std::move(pending_images_.begin()->second);
      pending_images_.erase(pending_images_.begin());
      binary = true;
    } else if (pending_frame_) {
      next = std::move(pending_frame_);
      pending_frame_.reset();
      binary = true;
      is_frame = true;
    } else {
      return;
    }
    writing_ = true;
    ws_.binary(binary);
    // `next` keeps the bytes alive until the write completes.
    ws_.async_write(net::buffer(*next),
                    [self = shared_from_this(), next, is_frame](beast::error_code ec, std::size_t) {
                      self->writing_ = false;
                      if (ec) {
                        self->on_gone(ec.message());
                        return;
                      }
                      if (is_frame) ++self->impl_.frames_sent;
                      self->maybe_write();
                    });
  }

  void on_gone(const std::string& why) {
    if (gone_) return;
    gone_ = true;
    drive_timer_.cancel();
    if (accepted_) {
      impl_.log(UiLogLevel::kInfo,
                "ui: client " + std::to_string(id_) + " disconnected (" + why + ")");
    }
    if (driving_) {
      driving_ = false;
      emit_server_release("client_disconnected");
    }
    impl_.remove_session(shared_from_this());
  }

  websocket::stream<beast::tcp_stream> ws_;
  Impl& impl_;
  std::uint64_t id_;
  net::steady_timer drive_timer_;
  beast::flat_buffer read_buffer_;
  bool accepted_ = false;
  bool writing_ = false;
  bool gone_ = false;
  bool driving_ = false;
  std::deque<Message> text_out_;
  nlohmann::json pending_state_ = nlohmann::json::object();
  std::deque<nlohmann::json> pending_samples_;
  bool samples_reset_ = false;
  std::map<std::string, Message> pending_images_;
  Message pending_frame_;
};

// ---------------------------------------------------------------- HTTP session
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, Impl& impl) : stream_(std::move(socket)), impl_(impl) {}

  void run() { do_read(); }

 private:
  void do_read() {
    parser_.emplace();
    parser_->header_limit(kMaxRequestHeaderBytes);
    parser_->body_limit(kMaxRequestBodyBytes);
    stream_.expires_after(kHttpTimeout);
    http::async_read(
        stream_, buffer_, *parser_,
        [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

  void on_read(beast::error_code ec) {
    if (ec) {
      if (ec != http::error::end_of_stream && ec != net::error::operation_aborted &&
          ec != beast::error::timeout) {
        // Over-long header or body, bad syntax: answer 400 once, then close.
        send(error_response(http::status::bad_request, "bad request\n", 11, false));
        close_after_write_ = true;
        return;
      }
      close();
      return;
    }
    ++impl_.http_requests;
    http::request<http::string_body> req = parser_->release();
    if (websocket::is_upgrade(req)) {
      upgrade(std::move(req));
      return;
    }
    send(handle(req));
  }

  void upgrade(http::request<http::string_body> req) {
    const unsigned version = req.version();
    const bool keep = req.keep_alive();
    if (req.target() != "/ws") {
      send(error_response(http::status::not_found, "no such endpoint\n", version, keep));
      return;
    }
    if (const auto origin = req.find(http::field::origin); origin != req.end()) {
      if (impl_.allowed_origins.count(std::string(origin->value())) == 0) {
        impl_.log(UiLogLevel::kWarning,
                  "ui: refused a websocket from origin " + std::string(origin->value()));
        send(error_response(http::status::forbidden, "origin not allowed\n", version, false));
        close_after_write_ = true;
        return;
      }
    }
    if (impl_.sessions.size() >= impl_.options.max_clients) {
      send(error_response(http::status::service_unavailable, "too many clients\n", version, false));
      close_after_write_ = true;
      return;
    }
    stream_.expires_never();
    auto session =
        std::make_shared<WsSession>(stream_.release_socket(), impl_, impl_.next_client_id++);
    impl_.sessions.insert(session);
    impl_.clients = impl_.sessions.size();
    session->run(std::move(req));
  }

  using Response = http::response<http::string_body>;

  static std::shared_ptr<Response> error_response(http::status status, std::string body,
                                                  unsigned version, bool keep_alive) {
    auto res = std::make_shared<Response>(status, version);
    res->set(http::field::server, "pepper-teach-ui");
    res->set(http::field::content_type, "text/plain; charset=utf-8");
    res->set(http::field::cache_control, "no-store");
    res->keep_alive(keep_alive);
    res->body() = std::move(body);
    res->prepare_payload();
    return res;
  }

  std::shared_ptr<Response> handle(const http::request<http::string_body>& req) {
    const unsigned version = req.version();
    const bool keep = req.keep_alive();
    if (req.method() != http::verb::get && req.method() != http::verb::head) {
      auto res =
          error_response(http::status::method_not_allowed, "GET or HEAD only\n", version, keep);
      res->set(http::field::allow, "GET, HEAD");
      return res;
    }
    const std::string target(req.target());
    const WebPath where = resolve_web_path(impl_.root, target);
    if (where.status == WebPathStatus::kBadTarget) {
      impl_.log(UiLogLevel::kWarning, "ui: refused request target " + target);
      return error_response(http::status::bad_request, "bad path\n", version, keep);
    }
    std::error_code fs_ec;
    if (where.status == WebPathStatus::kNotFound ||
        std::filesystem::file_size(where.path, fs_ec) > kMaxServedFileBytes || fs_ec) {
      return error_response(http::status::not_found, "not found\n", version, keep);
    }
    std::ifstream in(where.path, std::ios::binary);
    std::ostringstream content;
    content << in.rdbuf();
    if (!in) return error_response(http::status::not_found, "not found\n", version, keep);
    auto res = std::make_shared<Response>(http::status::ok, version);
    res->set(http::field::server, "pepper-teach-ui");
    res->set(http::field::content_type, std::string(mime_type_for(where.path)));
    res->set(http::field::cache_control, "no-store");
    res->set("X-Content-Type-Options", "nosniff");
    res->set("Content-Security-Policy",
             "default-src 'self'; img-src 'self' blob: data:; connect-src 'self'; "
             "frame-ancestors 'none'");
    res->keep_alive(keep);
    res->body() = content.str();
    res->prepare_payload();
    if (req.method() == http::verb::head) {
      const auto length = res->body().size();
      res->body().clear();
      res->content_length(length);
    }
    return res;
  }

  void send(std::shared_ptr<Response> res) {
    http::async_write(stream_, *res,
                      [self = shared_from_this(), res](beast::error_code ec, std::size_t) {
                        self->after_write(ec, res->keep_alive());
                      });
  }

  void after_write(beast::error_code ec, bool keep_alive) {
    if (ec || !keep_alive || close_after_write_) {
      close();
      return;
    }
    do_read();
  }

  void close() {
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
    stream_.close();
  }

  beast::tcp_stream stream_;
  Impl& impl_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  bool close_after_write_ = false;
};

}  // namespace detail

namespace {

using detail::HttpSession;
using detail::Impl;
using detail::is_stop_like;
using detail::WsSession;

void accept_loop(Impl& impl) {
  impl.acceptor->async_accept([&impl](beast::error_code ec, tcp::socket socket) {
    if (ec) {
      if (ec != net::error::operation_aborted) {
        impl.log(UiLogLevel::kWarning, "ui: accept failed: " + ec.message());
      }
      if (!impl.acceptor->is_open()) return;
    } else {
      std::make_shared<HttpSession>(std::move(socket), impl)->run();
    }
    if (impl.acceptor->is_open()) accept_loop(impl);
  });
}

Message encode_binary(std::uint8_t kind, const nlohmann::json& header, std::string_view bytes) {
  return std::make_shared<const std::string>(encode_binary_message(
      kind, header.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), bytes));
}

}  // namespace

void detail::UiServerImpl::push_intent(Intent intent) {
  ++intents_received;
  if (handler) {
    try {
      handler(intent);
    } catch (const std::exception& e) {
      log(UiLogLevel::kError, std::string("ui: intent handler threw: ") + e.what());
    }
    return;
  }
  {
    std::lock_guard<std::mutex> lock(intent_mutex);
    if (intents.size() >= options.max_queued_intents && !is_stop_like(intent.kind)) {
      log(UiLogLevel::kWarning,
          "ui: intent queue full; dropped a " + std::string(to_string(intent.kind)) + " intent");
      return;
    }
    intents.push_back(std::move(intent));
  }
  intent_cv.notify_one();
}

void detail::UiServerImpl::remove_session(const std::shared_ptr<WsSession>& s) {
  sessions.erase(s);
  clients = sessions.size();
}

// ---------------------------------------------------------------- options
std::vector<std::string> UiOptions::validate() const {
  std::vector<std::string> errors;
  boost::system::error_code ec;
  net::ip::make_address(bind_address, ec);
  if (ec) errors.push_back("bind_address '" + bind_address + "' is not an IP address literal");
  if (!(limits.max_v_m_s > 0.0 && limits.max_v_m_s <= 1.0)) {
    errors.push_back("limits.max_v_m_s must be in (0, 1] m/s");
  }
  if (!(limits.max_omega_rad_s > 0.0 && limits.max_omega_rad_s <= 3.0)) {
    errors.push_back("limits.max_omega_rad_s must be in (0, 3] rad/s");
  }
  if (max_message_bytes < 256 || max_message_bytes > (16u << 20)) {
    errors.push_back("max_message_bytes must be in [256, 16777216]");
  }
  if (max_clients < 1 || max_clients > 64) errors.push_back("max_clients must be in [1, 64]");
  if (max_queued_intents < 16) errors.push_back("max_queued_intents must be >= 16");
  if (sample_history < 1 || sample_history > 100000) {
    errors.push_back("sample_history must be in [1, 100000]");
  }
  // The page refreshes a held drive every 0.1 s: a shorter timeout would stop a held key.
  if (!(drive_timeout_s == 0.0 || (drive_timeout_s >= 0.25 && drive_timeout_s <= 10.0))) {
    errors.push_back("drive_timeout_s must be 0 (watchdog off) or in [0.25, 10] s");
  }
  return errors;
}

// ---------------------------------------------------------------- UiServer
UiServer::UiServer(UiOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}

UiServer::~UiServer() { stop(); }

void UiServer::start() {
  Impl& impl = *impl_;
  if (impl.started_once) throw UiServerError("UiServer::start: a server can be started only once");
  if (const auto errors = impl.options.validate(); !errors.empty()) {
    std::string text = "UiServer: invalid options:";
    for (const auto& e : errors) text += "\n  " + e;
    throw UiServerError(text);
  }
  const std::string root =
      impl.options.web_root.empty() ? default_web_root() : impl.options.web_root;
  std::error_code fs_ec;
  impl.root = std::filesystem::canonical(root, fs_ec);
  if (fs_ec || !std::filesystem::is_directory(impl.root)) {
    throw UiServerError("UiServer: web_root '" + root + "' is not a folder");
  }
  const auto address = net::ip::make_address(impl.options.bind_address);
  try {
    impl.acceptor.emplace(impl.ioc);
    const tcp::endpoint endpoint(address, impl.options.port);
    impl.acceptor->open(endpoint.protocol());
    impl.acceptor->set_option(net::socket_base::reuse_address(true));
    impl.acceptor->bind(endpoint);
    impl.acceptor->listen(net::socket_base::max_listen_connections);
  } catch (const boost::system::system_error& e) {
    impl.acceptor.reset();
    throw UiServerError("UiServer: cannot listen on " + impl.options.bind_address + ":" +
                        std::to_string(impl.options.port) + ": " + e.what());
  }
  impl.started_once = true;
  const std::uint16_t port = impl.acceptor->local_endpoint().port();
  impl.bound_port = port;
  const std::string host = address.is_v6() ? "[" + address.to_string() + "]" : address.to_string();
  impl.base_url = "http://" + host + ":" + std::to_string(port) + "/";
  const std::string p = ":" + std::to_string(port);
  impl.allowed_origins = {"http://127.0.0.1" + p, "http://localhost" + p, "http://[::1]" + p,
                          "http://" + host + p};
  for (const auto& o : impl.options.extra_allowed_origins) impl.allowed_origins.insert(o);
  accept_loop(impl);
  impl.running = true;
  impl.thread = std::thread([&impl] {
    for (;;) {
      try {
        impl.ioc.run();
        return;
      } catch (const std::exception& e) {
        // A handler threw (a bug): log and keep serving rather than take the UI down.
        impl.log(UiLogLevel::kError, std::string("ui: I/O handler threw: ") + e.what());
      }
    }
  });
  impl.log(UiLogLevel::kInfo, "ui: serving " + impl.root.string() + " at " + impl.base_url);
}

void UiServer::stop() {
  Impl& impl = *impl_;
  if (!impl.running.exchange(false)) return;
  // The last state an app publishes before stopping (the final figures, "disconnected") must
  // reach the open pages: let the sessions send what is queued, for at most kStopDrainTime.
  const auto drain_until = std::chrono::steady_clock::now() + kStopDrainTime;
  while (impl.thread.joinable() && std::chrono::steady_clock::now() < drain_until) {
    auto drained = std::make_shared<std::promise<bool>>();
    auto answer = drained->get_future();
    net::post(impl.ioc, [&impl, drained] {
      bool all = true;
      for (const auto& s : impl.sessions) all = all && s->drained();
      drained->set_value(all);
    });
    if (answer.wait_until(drain_until) != std::future_status::ready || answer.get()) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  net::post(impl.ioc, [&impl] {
    beast::error_code ec;
    if (impl.acceptor) impl.acceptor->close(ec);
    const auto sessions = impl.sessions;  // shutdown() removes from the set
    for (const auto& s : sessions) s->shutdown();
    // Idle HTTP keep-alive connections are not tracked: their handlers are dropped with the
    // io_context (sessions touch nothing of the server in their destructors).
    impl.ioc.stop();
  });
  if (impl.thread.joinable()) impl.thread.join();
  impl.log(UiLogLevel::kInfo, "ui: stopped");
}

bool UiServer::running() const { return impl_->running; }

std::uint16_t UiServer::port() const { return impl_->bound_port; }

std::string UiServer::url() const { return impl_->base_url; }

void UiServer::publish_frame(std::string encoded_image, nlohmann::json overlay) {
  Impl& impl = *impl_;
  if (encoded_image.empty()) return;
  ++impl.frames_published;
  if (!impl.running) return;
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  nlohmann::json header = {{"seq", ++impl.frame_seq},
                           {"server_ms", std::chrono::duration<double, std::milli>(now).count()},
                           {"overlay", std::move(overlay)}};
  Message m = encode_binary(kBinaryFrame, header, encoded_image);
  net::post(impl.ioc, [&impl, m = std::move(m)] {
    impl.latest_frame = m;
    for (const auto& s : impl.sessions) s->queue_frame(m);
  });
}

void UiServer::publish_frame(const std::vector<std::uint8_t>& encoded_image,
                             nlohmann::json overlay) {
  publish_frame(std::string(encoded_image.begin(), encoded_image.end()), std::move(overlay));
}

void UiServer::publish_image(const std::string& name,
                             const std::vector<std::uint8_t>& encoded_image) {
  publish_image(name, std::string(encoded_image.begin(), encoded_image.end()));
}

void UiServer::publish_state(const nlohmann::json& patch) {
  if (!patch.is_object()) {
    throw std::invalid_argument("UiServer::publish_state: the state patch must be a JSON object");
  }
  Impl& impl = *impl_;
  if (!impl.running) return;
  net::post(impl.ioc, [&impl, patch] {
    for (const auto& [key, value] : patch.items()) impl.snapshot_state[key] = value;
    for (const auto& s : impl.sessions) s->queue_state(patch);
  });
}

void UiServer::publish_image(const std::string& name, std::string encoded_image) {
  Impl& impl = *impl_;
  if (!impl.running) return;
  Message m = encode_binary(kBinaryImage, {{"name", name}}, encoded_image);
  const bool removal = encoded_image.empty();
  net::post(impl.ioc, [&impl, name, removal, m = std::move(m)] {
    if (removal) {
      impl.snapshot_images.erase(name);
    } else {
      impl.snapshot_images[name] = m;
    }
    for (const auto& s : impl.sessions) s->queue_image(name, m);
  });
}

void UiServer::publish_samples(const nlohmann::json& samples) {
  nlohmann::json list;
  if (samples.is_object()) {
    list = nlohmann::json::array({samples});
  } else if (samples.is_array()) {
    for (const auto& s : samples) {
      if (!s.is_object()) {
        throw std::invalid_argument("UiServer::publish_samples: every sample must be an object");
      }
    }
    list = samples;
  } else {
    throw std::invalid_argument("UiServer::publish_samples: expected an object or an array");
  }
  Impl& impl = *impl_;
  if (!impl.running || list.empty()) return;
  net::post(impl.ioc, [&impl, list = std::move(list)] {
    for (const auto& s : list) {
      impl.sample_history.push_back(s);
      if (impl.sample_history.size() > impl.options.sample_history) impl.sample_history.pop_front();
    }
    for (const auto& s : impl.sessions) s->queue_samples(list);
  });
}

void UiServer::clear_samples() {
  Impl& impl = *impl_;
  if (!impl.running) return;
  net::post(impl.ioc, [&impl] {
    impl.sample_history.clear();
    for (const auto& s : impl.sessions) s->queue_samples_reset();
  });
}

std::optional<Intent> UiServer::next_intent(std::chrono::milliseconds timeout) {
  Impl& impl = *impl_;
  std::unique_lock<std::mutex> lock(impl.intent_mutex);
  if (!impl.intent_cv.wait_for(lock, timeout, [&impl] { return !impl.intents.empty(); })) {
    return std::nullopt;
  }
  Intent out = std::move(impl.intents.front());
  impl.intents.pop_front();
  return out;
}

void UiServer::set_intent_handler(std::function<void(const Intent&)> handler) {
  Impl& impl = *impl_;
  if (impl.running) {
    throw std::logic_error("UiServer::set_intent_handler: set the handler before start()");
  }
  impl.handler = std::move(handler);
}

UiServerStats UiServer::stats() const {
  const Impl& impl = *impl_;
  UiServerStats s;
  s.clients = impl.clients;
  s.frames_published = impl.frames_published;
  s.frames_sent = impl.frames_sent;
  s.frames_dropped = impl.frames_dropped;
  s.intents_received = impl.intents_received;
  s.malformed_messages = impl.malformed_messages;
  s.http_requests = impl.http_requests;
  return s;
}

}  // namespace pepper::teach_ui
