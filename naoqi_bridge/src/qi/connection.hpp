#pragma once
// MessageConnection (private): one qi message stream over TCP or TLS, shared by the client
// (QiSession) and the mock server.
//
// Threading: all I/O and both handlers run on the io_context's single thread. send() and close()
// may be called from any thread (they post). The read loop decodes each header with the codec's
// limits before reading the payload (read in growing chunks, so a hostile size never allocates
// more than what actually arrived plus 1 MiB); a framing error closes the connection with a
// reason naming the violation. The close handler runs exactly once.

#include <array>
#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl/context.hpp>
#include <boost/asio/ssl/stream.hpp>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "naoqi_bridge/qi/message.hpp"

namespace pepper::naoqi_bridge::qi::detail {

namespace asio = boost::asio;
using tcp = asio::ip::tcp;

class MessageConnection : public std::enable_shared_from_this<MessageConnection> {
 public:
  using MessageHandler = std::function<void(Message)>;
  using CloseHandler = std::function<void(const std::string& reason)>;

  /// Plain TCP when `tls_context` is null.
  MessageConnection(asio::io_context& io, asio::ssl::context* tls_context, CodecLimits limits);

  tcp::socket& socket();
  asio::ssl::stream<tcp::socket>* tls() { return tls_ ? &*tls_ : nullptr; }

  /// Starts the read loop (call on the io thread).
  void start(MessageHandler on_message, CloseHandler on_close);
  /// Queues a message; `payload` is moved into the queue. Thread-safe.
  void send(MessageHeader header, std::vector<std::uint8_t> payload);
  /// Queues bytes as they are (fault injection). Thread-safe.
  void send_raw(std::vector<std::uint8_t> bytes);
  /// Closes once everything queued so far has been written (e.g. after an Error). Thread-safe.
  void close_after_flush(const std::string& reason);
  /// Closes the socket; the close handler receives `reason`. Thread-safe, idempotent.
  void close(const std::string& reason);
  bool is_open() const { return open_; }

 private:
  struct Outgoing {
    std::array<std::uint8_t, kHeaderSize> header{};
    bool has_header = true;
    std::vector<std::uint8_t> payload;
    std::optional<std::string> close_reason;  ///< a close marker instead of data
  };
  void read_header();
  void read_payload(std::size_t filled);
  void write_next();
  void do_close(const std::string& reason);

  asio::io_context& io_;
  std::optional<tcp::socket> plain_;
  std::optional<asio::ssl::stream<tcp::socket>> tls_;
  CodecLimits limits_;
  MessageHandler on_message_;
  CloseHandler on_close_;
  std::array<std::uint8_t, kHeaderSize> header_buf_{};
  MessageHeader header_;
  std::shared_ptr<std::vector<std::uint8_t>> payload_;
  std::deque<Outgoing> queue_;
  bool writing_ = false;
  std::atomic<bool> open_{true};
  bool closed_notified_ = false;
};

/// SHA-256 of the peer certificate (DER), "AB:CD:..." upper-case hex; empty if none.
std::string peer_certificate_sha256(asio::ssl::stream<tcp::socket>& stream);
/// SHA-256 of a PEM certificate file's first certificate, same format.
std::string certificate_sha256_pem(const std::string& pem);
/// Normalises a fingerprint for comparison: hex digits only, upper case, "SHA256:" prefix removed.
std::string normalize_fingerprint(const std::string& fp);
/// A fresh self-signed certificate and key (EC P-256), PEM encoded.
struct SelfSigned {
  std::string certificate_pem;
  std::string private_key_pem;
};
SelfSigned make_self_signed_certificate(const std::string& common_name);

}  // namespace pepper::naoqi_bridge::qi::detail
