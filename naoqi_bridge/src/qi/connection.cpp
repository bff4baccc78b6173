// MessageConnection: framing over TCP/TLS with Boost.Asio; TLS helpers with OpenSSL.
#include "connection.hpp"

#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include <algorithm>
#include <boost/asio/post.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>
#include <cctype>
#include <cstdio>

#include "naoqi_bridge/robot_bridge.hpp"

namespace pepper::naoqi_bridge::qi::detail {

MessageConnection::MessageConnection(asio::io_context& io, asio::ssl::context* tls_context,
                                     CodecLimits limits)
    : io_(io), limits_(limits) {
  if (tls_context) {
    tls_.emplace(io, *tls_context);
  } else {
    plain_.emplace(io);
  }
}

tcp::socket& MessageConnection::socket() { return tls_ ? tls_->next_layer() : *plain_; }

void MessageConnection::start(MessageHandler on_message, CloseHandler on_close) {
  on_message_ = std::move(on_message);
  on_close_ = std::move(on_close);
  read_header();
}

void MessageConnection::read_header() {
  auto self = shared_from_this();
  auto handler = [this, self](const boost::system::error_code& ec, std::size_t) {
    if (ec) {
      do_close(ec == asio::error::eof ? "connection closed by peer"
                                      : "read failed: " + ec.message());
      return;
    }
    try {
      header_ = decode_header(header_buf_, limits_);
    } catch (const ProtocolError& e) {
      do_close(std::string("malformed message header: ") + e.what());
      return;
    }
    payload_ = std::make_shared<std::vector<std::uint8_t>>();
    read_payload(0);
  };
  if (tls_) {
    asio::async_read(*tls_, asio::buffer(header_buf_), std::move(handler));
  } else {
    asio::async_read(*plain_, asio::buffer(header_buf_), std::move(handler));
  }
}

void MessageConnection::read_payload(std::size_t filled) {
  const std::size_t total = header_.size;
  if (filled == total) {
    Message m;
    m.header = header_;
    m.payload = std::move(payload_);
    if (open_ && on_message_) on_message_(std::move(m));
    if (open_) read_header();
    return;
  }
  // Grow in chunks: never allocate much more than what the peer actually sent.
  constexpr std::size_t kChunk = 1u << 20;
  const std::size_t target = std::min(total, std::max(kChunk, filled * 2));
  payload_->resize(target);
  auto self = shared_from_this();
  // The handler holds the buffer too: a close drops the member while this read may be pending.
  auto handler = [this, self, target, buffer = payload_](const boost::system::error_code& ec,
                                                          std::size_t) {
    if (ec || !open_) {
      do_close("read failed in a " + std::to_string(header_.size) +
               "-byte payload: " + ec.message());
      return;
    }
    read_payload(target);
  };
  auto buf = asio::buffer(payload_->data() + filled, target - filled);
  if (tls_) {
    asio::async_read(*tls_, buf, std::move(handler));
  } else {
    asio::async_read(*plain_, buf, std::move(handler));
  }
}

void MessageConnection::send(MessageHeader header, std::vector<std::uint8_t> payload) {
  header.size = static_cast<std::uint32_t>(payload.size());
  Outgoing out;
  out.header = encode_header(header);
  out.payload = std::move(payload);
  auto self = shared_from_this();
  asio::post(io_, [this, self, out = std::move(out)]() mutable {
    if (!open_) return;
    queue_.push_back(std::move(out));
    if (!writing_) write_next();
  });
}

void MessageConnection::send_raw(std::vector<std::uint8_t> bytes) {
  Outgoing out;
  out.has_header = false;
  out.payload = std::move(bytes);
  auto self = shared_from_this();
  asio::post(io_, [this, self, out = std::move(out)]() mutable {
    if (!open_) return;
    queue_.push_back(std::move(out));
    if (!writing_) write_next();
  });
}

void MessageConnection::close_after_flush(const std::string& reason) {
  Outgoing out;
  out.close_reason = reason;
  auto self = shared_from_this();
  asio::post(io_, [this, self, out = std::move(out)]() mutable {
    if (!open_) return;
    queue_.push_back(std::move(out));
    if (!writing_) write_next();
  });
}

void MessageConnection::write_next() {
  if (queue_.empty() || !open_) {
    writing_ = false;
    return;
  }
  writing_ = true;
  Outgoing& out = queue_.front();
  if (out.close_reason) {
    const std::string reason = *out.close_reason;
    queue_.clear();
    writing_ = false;
    do_close(reason);
    return;
  }
  std::array<asio::const_buffer, 2> bufs{
      asio::buffer(out.header.data(), out.has_header ? out.header.size() : 0),
      asio::buffer(out.payload)};
  auto self = shared_from_this();
  auto handler = [this, self](const boost::system::error_code& ec, std::size_t) {
    if (!queue_.empty()) queue_.pop_front();
    if (!open_) {
      writing_ = false;
      queue_.clear();
      return;
    }
    if (ec) {
      writing_ = false;
      do_close("write failed: " + ec.message());
      return;
    }
    write_next();
  };
  if (tls_) {
    asio::async_write(*tls_, bufs, std::move(handler));
  } else {
    asio::async_write(*plain_, bufs, std::move(handler));
  }
}

void MessageConnection::close(const std::string& reason) {
  auto self = shared_from_this();
  asio::post(io_, [this, self, reason] { do_close(reason); });
}

void MessageConnection::do_close(const std::string& reason) {
  open_ = false;
  boost::system::error_code ignored;
  socket().shutdown(tcp::socket::shutdown_both, ignored);
  socket().close(ignored);
  // Drop everything the connection holds: the handlers (the server's close handler owns the
  // connection's state, which owns this connection: keeping it would leak both), the payload
  // being read (up to the announced size, 64 MiB by default) and what was queued to send.
  CloseHandler on_close = std::move(on_close_);
  on_close_ = nullptr;
  on_message_ = nullptr;
  payload_.reset();
  if (!writing_) queue_.clear();  // a write in flight still reads its buffers; it pops itself
  if (!closed_notified_) {
    closed_notified_ = true;
    if (on_close) on_close(reason);
  }
}

// ---------------------------------------------------------------------------------------------
// TLS helpers

namespace {

std::string hex_colon(const unsigned char* md, unsigned int n) {
  std::string out;
  char buf[4];
  for (unsigned int i = 0; i < n; ++i) {
    std::snprintf(buf, sizeof buf, "%02X", md[i]);
    if (i) out += ':';
    out += buf;
  }
  return out;
}

std::string x509_sha256(X509* cert) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  if (!cert || X509_digest(cert, EVP_sha256(), md, &n) != 1) return {};
  return hex_colon(md, n);
}

}  // namespace

std::string peer_certificate_sha256(asio::ssl::stream<tcp::socket>& stream) {
  X509* cert = SSL_get1_peer_certificate(stream.native_handle());
  std::string fp = x509_sha256(cert);
  X509_free(cert);
  return fp;
}

std::string certificate_sha256_pem(const std::string& pem) {
  BIO* bio = BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size()));
  X509* cert = PEM_read_bio_X509(bio, nullptr, nullptr, nullptr);
  BIO_free(bio);
  std::string fp = x509_sha256(cert);
  X509_free(cert);
  return fp;
}

std::string normalize_fingerprint(const std::string& fp) {
  std::string s = fp;
  if (s.size() > 7) {
    std::string prefix = s.substr(0, 7);
    std::transform(prefix.begin(), prefix.end(), prefix.begin(),
                   [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
    if (prefix == "SHA256:") s = s.substr(7);
  }
  std::string out;
  for (unsigned char c : s) {
    if (std::isxdigit(c)) out += static_cast<char>(std::toupper(c));
  }
  return out;
}

SelfSigned make_self_signed_certificate(const std::string& common_name) {
  EVP_PKEY* key = EVP_EC_gen("P-256");
  if (!key) throw BridgeError("TLS: cannot generate an EC key");
  X509* cert = X509_new();
  X509_set_version(cert, 2);
  ASN1_INTEGER_set(X509_get_serialNumber(cert), 1);
  X509_gmtime_adj(X509_getm_notBefore(cert), -3600);
  X509_gmtime_adj(X509_getm_notAfter(cert), 365L * 24 * 3600);
  X509_set_pubkey(cert, key);
  X509_NAME* name = X509_get_subject_name(cert);
  X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_ASC,
                             reinterpret_cast<const unsigned char*>(common_name.c_str()), -1, -1,
                             0);
  X509_set_issuer_name(cert, name);
  if (X509_sign(cert, key, EVP_sha256()) == 0) {
    X509_free(cert);
    EVP_PKEY_free(key);
    throw BridgeError("TLS: cannot sign the self-signed certificate");
  }
  SelfSigned out;
  BIO* b1 = BIO_new(BIO_s_mem());
  PEM_write_bio_X509(b1, cert);
  BUF_MEM* mem = nullptr;
  BIO_get_mem_ptr(b1, &mem);
  out.certificate_pem.assign(mem->data, mem->length);
  BIO_free(b1);
  BIO* b2 = BIO_new(BIO_s_mem());
  PEM_write_bio_PrivateKey(b2, key, nullptr, nullptr, 0, nullptr, nullptr);
  BIO_get_mem_ptr(b2, &mem);
  out.private_key_pem.assign(mem->data, mem->length);
  BIO_free(b2);
  X509_free(cert);
  EVP_PKEY_free(key);
  return out;
}

}  // namespace pepper::naoqi_bridge::qi::detail
