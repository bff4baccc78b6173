#pragma once
// Loopback test clients for the teach UI server: a one-shot HTTP GET and a WebSocket client whose
// reads time out (Beast async reads driven by io_context::run_for), so a server bug fails a test
// instead of hanging it.
#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <functional>
#include <optional>
#include <string>

namespace pepper::teach_ui::testing {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

struct HttpReply {
  int status = 0;
  std::string content_type;
  std::string body;
};

/// Sends one request with a raw target (no normalisation by the client) and reads the reply.
inline HttpReply http_request(std::uint16_t port, const std::string& target,
                              http::verb verb = http::verb::get) {
  net::io_context ioc;
  beast::tcp_stream stream(ioc);
  stream.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
  http::request<http::string_body> req(verb, target, 11);
  req.set(http::field::host, "127.0.0.1");
  req.keep_alive(false);
  http::write(stream, req);
  beast::flat_buffer buffer;
  http::response_parser<http::string_body> parser;
  if (verb == http::verb::head) parser.skip(true);
  http::read(stream, buffer, parser);
  HttpReply reply;
  reply.status = static_cast<int>(parser.get().result_int());
  reply.content_type = std::string(parser.get()[http::field::content_type]);
  reply.body = parser.get().body();
  beast::error_code ec;
  stream.socket().shutdown(tcp::socket::shutdown_both, ec);
  return reply;
}

struct WsMessage {
  bool binary = false;
  std::string data;
};

class WsClient {
 public:
  /// Connects and performs the upgrade on "/ws". Throws beast::system_error when refused.
  /// `receive_buffer_bytes` > 0 shrinks the socket's receive buffer (slow-client tests).
  explicit WsClient(std::uint16_t port, const std::string& origin = "",
                    int receive_buffer_bytes = 0)
      : ws_(ioc_) {
    auto& socket = beast::get_lowest_layer(ws_).socket();
    socket.open(tcp::v4());
    if (receive_buffer_bytes > 0) {
      socket.set_option(net::socket_base::receive_buffer_size(receive_buffer_bytes));
    }
    beast::get_lowest_layer(ws_).connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    if (!origin.empty()) {
      ws_.set_option(websocket::stream_base::decorator(
          [origin](websocket::request_type& req) { req.set(http::field::origin, origin); }));
    }
    ws_.handshake("127.0.0.1:" + std::to_string(port), "/ws");
  }

  void send_text(const std::string& text) {
    ws_.text(true);
    ws_.write(net::buffer(text));
  }
  /// Like send_text, but reports a failed write (peer already closed) instead of throwing.
  bool try_send_text(const std::string& text) {
    beast::error_code ec;
    ws_.text(true);
    ws_.write(net::buffer(text), ec);
    return !ec;
  }
  void send_binary(const std::string& bytes) {
    ws_.binary(true);
    ws_.write(net::buffer(bytes));
  }

  /// Next message, or std::nullopt on timeout or when the connection ended (see closed()).
  std::optional<WsMessage> read(std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
    if (closed_) return std::nullopt;
    std::optional<WsMessage> out;
    bool done = false;
    buffer_.consume(buffer_.size());
    ws_.async_read(buffer_, [&](beast::error_code ec, std::size_t) {
      done = true;
      if (ec) {
        closed_ = true;
        return;
      }
      out = WsMessage{!ws_.got_text(), beast::buffers_to_string(buffer_.data())};
    });
    ioc_.restart();
    ioc_.run_for(timeout);
    if (!done) {
      beast::get_lowest_layer(ws_).cancel();
      ioc_.restart();
      ioc_.run();
      closed_ = true;  // a cancelled websocket read leaves the stream unusable
    }
    return out;
  }

  /// Reads until `pred` accepts a message (returned) or `timeout` passes in total.
  std::optional<WsMessage> read_until(
      const std::function<bool(const WsMessage&)>& pred,
      std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      auto m = read(left);
      if (!m) return std::nullopt;
      if (pred(*m)) return m;
    }
    return std::nullopt;
  }

  bool closed() const { return closed_; }

  /// Abrupt disconnect (no close frame), like a crashed or killed browser tab.
  void drop() {
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ec);
    beast::get_lowest_layer(ws_).close();
    closed_ = true;
  }
  /// Polite close handshake.
  void close() {
    beast::error_code ec;
    ws_.close(websocket::close_code::normal, ec);
    closed_ = true;
  }

 private:
  net::io_context ioc_;
  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer buffer_;
  bool closed_ = false;
};

}  // namespace pepper::teach_ui::testing
