#pragma once
// UiServer: the teach UI's local HTTP + WebSocket server (Boost.Beast) on 127.0.0.1.
//
// It serves the static page under UiOptions::web_root and one WebSocket endpoint ("/ws"). The app
// pushes data in (publish_frame, publish_state, publish_image, publish_samples); every connected
// page receives it. Operator intents flow back out through next_intent() or an intent handler.
// teach_ui never calls the core or the robot. Message schema: docs/teach_ui.md.
//
// Delivery policy (a slow page never slows the app):
//  - frames: latest wins per client; a client still sending the previous frame skips to the newest.
//  - state: top-level keys of the published object replace that key's previous value; a client
//    that is behind gets one merged message with the newest value of every changed key.
//  - images (thumbnails, by name): latest wins per name and client.
//  - samples (plot points): appended; at most UiOptions::sample_history are kept per client and
//    in the snapshot, older ones are dropped.
//  A page that connects late first receives a snapshot: the merged state, every image, the sample
//  history and the latest frame.
//
// Safety: when a client that was driving (a drive intent not followed by a release or stop)
// disconnects, or stops refreshing its drive intent for UiOptions::drive_timeout_s, the server
// itself queues a kDriveReleased intent (source kServer).
//
// Security: binds 127.0.0.1 by default; serves only regular files under web_root (no "..", no
// escape through symbolic links); refuses WebSocket upgrades whose Origin is not this server's
// own (so a foreign web page in the operator's browser cannot drive the robot); closes a
// WebSocket that sends a message larger than UiOptions::max_message_bytes; ignores (and logs)
// malformed intents.
//
// Threading: the server runs one I/O thread between start() and stop(). Every public method is
// thread-safe and never blocks on the network; publish_* only copy and post. The intent handler,
// if set, runs on the I/O thread and must return quickly. Not copyable, not movable. The destructor
// stops and joins.
//
// Failure: start() throws UiServerError when the options are invalid, the web root is missing or
// the address cannot be bound. Network errors of one client only end that client's connection.
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "teach_ui/intent.hpp"

namespace pepper::teach_ui {

namespace detail {
struct UiServerImpl;
}  // namespace detail

/// Setup or environment failure of the UI server (bad options, missing web root, bind failure).
class UiServerError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class UiLogLevel { kDebug, kInfo, kWarning, kError };
/// Log sink; the app plugs its logger in. Called from the I/O thread and from start()/stop().
using UiLogSink = std::function<void(UiLogLevel, std::string_view)>;

struct UiOptions {
  std::string bind_address = "127.0.0.1";     ///< IPv4/IPv6 literal; keep loopback unless you must
  std::uint16_t port = 0;                     ///< 0 = ephemeral (read the real one with port())
  std::string web_root;                       ///< folder of index.html; empty = default_web_root()
  DriveLimits limits;                         ///< clamp for drive intents; sent to the page
  std::size_t max_message_bytes = 16 * 1024;  ///< larger client messages close the WebSocket
  std::size_t max_clients = 8;                ///< further WebSocket upgrades get 503
  std::size_t max_queued_intents = 1024;      ///< beyond it new intents are dropped (stops never)
  std::size_t sample_history = 600;           ///< plot samples kept for late/slow clients
  /// A drive intent expires after this long without a refresh (the page refreshes every 0.1 s);
  /// the server then queues kDriveReleased with reason "drive_timeout". 0 disables the watchdog;
  /// otherwise at least 0.25 s (four page refresh periods).
  double drive_timeout_s = 0.5;
  /// Extra Origin values accepted for WebSocket upgrades besides http://127.0.0.1:<port>,
  /// http://localhost:<port> and http://[::1]:<port>. Requests without Origin (non-browser
  /// clients) are always accepted.
  std::vector<std::string> extra_allowed_origins;
  UiLogSink log;  ///< empty = silent

  /// Human-readable problems, one per bad field ("max_message_bytes must be in [256, 16777216]");
  /// empty when valid. Does not check the file system.
  std::vector<std::string> validate() const;
};

/// Counters for tests and the status line. Monotonic except `clients`.
struct UiServerStats {
  std::size_t clients = 0;               ///< open WebSocket connections now
  std::uint64_t frames_published = 0;    ///< publish_frame() calls
  std::uint64_t frames_sent = 0;         ///< frame messages written, all clients together
  std::uint64_t frames_dropped = 0;      ///< frames replaced before a client could take them
  std::uint64_t intents_received = 0;    ///< valid intents queued (client and server)
  std::uint64_t malformed_messages = 0;  ///< client messages ignored as malformed
  std::uint64_t http_requests = 0;
};

class UiServer {
 public:
  explicit UiServer(UiOptions options);
  ~UiServer();  ///< stop()s and joins
  UiServer(const UiServer&) = delete;
  UiServer& operator=(const UiServer&) = delete;
  UiServer(UiServer&&) = delete;
  UiServer& operator=(UiServer&&) = delete;

  /// Validates the options, binds, listens and starts the I/O thread. Throws UiServerError.
  /// Calling start() on a running server throws too.
  void start();
  /// Sends what is queued for the open pages (state, images, samples: not frames) for at most
  /// 0.5 s, so that an app's last publish_state reaches them, then
  /// closes every connection (a driving client's connection first queues its kDriveReleased) and
  /// joins the I/O thread. Idempotent; never throws. Intents already queued stay readable with
  /// next_intent(). Do not call it from the intent handler (it would join its own thread).
  void stop();
  bool running() const;

  /// Bound port (the ephemeral one when UiOptions::port was 0); 0 before start().
  std::uint16_t port() const;
  /// "http://127.0.0.1:<port>/" (IPv6 addresses in brackets); empty before start().
  std::string url() const;

  /// Camera frame, already encoded (JPEG or PNG bytes; the page sniffs the format), with its
  /// overlay (see docs/teach_ui.md: size, line segments, points, colours, optional t_ns; build it
  /// with teach_ui/ui_messages.hpp). Latest wins per client. Empty bytes are ignored.
  void publish_frame(std::string encoded_image, nlohmann::json overlay);
  /// Same, for the byte vector that cv::imencode fills.
  void publish_frame(const std::vector<std::uint8_t>& encoded_image, nlohmann::json overlay);
  /// State update: a JSON object whose top-level keys replace the previous value of the same key
  /// (documented keys: docs/teach_ui.md). Throws std::invalid_argument if not an object.
  void publish_state(const nlohmann::json& patch);
  /// Named thumbnail ("key/12", "ip", "in", "inn"): JPEG/PNG bytes; empty bytes remove the image.
  void publish_image(const std::string& name, std::string encoded_image);
  void publish_image(const std::string& name, const std::vector<std::uint8_t>& encoded_image);
  /// Plot samples appended to the history: one object or an array of objects.
  /// Throws std::invalid_argument if neither.
  void publish_samples(const nlohmann::json& samples);
  /// Forgets the sample history (new session) and tells the pages to clear their plots.
  void clear_samples();

  /// Next operator intent in arrival order (from any thread but the intent handler's), waiting at
  /// most `timeout`. std::nullopt on timeout.
  std::optional<Intent> next_intent(std::chrono::milliseconds timeout);
  /// Alternative to polling: when set, every intent goes to `handler` (called on the I/O thread,
  /// in arrival order) instead of the queue. Set it before start().
  void set_intent_handler(std::function<void(const Intent&)> handler);

  UiServerStats stats() const;

 private:
  std::unique_ptr<detail::UiServerImpl> impl_;
};

}  // namespace pepper::teach_ui
