#pragma once
// Binary encoding of qi values (PROTOCOL.md section 6): little-endian, no padding, uint32 counts.
//
// Decoding is strict. Every length and count is checked against the bytes that remain and the
// limits below before anything is allocated; nesting depth and the number of decoded values are
// bounded. A violation throws ProtocolError naming the field, the value and the byte offset.
// Raw buffers decode as views into `owner` when one is given (no copy).
//
// Plain C++ (no Asio, no OpenCV): the fuzz target builds this file alone.

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "naoqi_bridge/qi/protocol_error.hpp"
#include "naoqi_bridge/qi/signature.hpp"
#include "naoqi_bridge/qi/value.hpp"

namespace pepper::naoqi_bridge::qi {

/// Bounds applied to everything received. Defaults fit a 1280x960 BGR frame (3.7 MB) with room.
struct CodecLimits {
  std::size_t max_payload_bytes = 64u << 20;  ///< largest accepted message payload, bytes
  std::size_t max_depth = 32;                 ///< deepest nesting of containers and dynamics
  std::size_t max_values = 1u << 18;          ///< most values materialised from one payload

  /// Messages naming each invalid field and its allowed range; empty when valid.
  std::vector<std::string> validate() const;
};

/// Appends encoded data to a byte vector.
class Writer {
 public:
  explicit Writer(std::vector<std::uint8_t>& out) : out_(out) {}
  void u8(std::uint8_t v) { out_.push_back(v); }
  void u16(std::uint16_t v);
  void u32(std::uint32_t v);
  void u64(std::uint64_t v);
  void f32(float v);
  void f64(double v);
  /// uint32 length then bytes (`s` and `r`). Throws kPayloadTooLarge beyond 4 GiB.
  void string(std::string_view s);
  void bytes_with_length(std::span<const std::uint8_t> b);
  void bytes(std::span<const std::uint8_t> b) { out_.insert(out_.end(), b.begin(), b.end()); }
  std::size_t size() const { return out_.size(); }
  std::vector<std::uint8_t>& buffer() { return out_; }

 private:
  std::vector<std::uint8_t>& out_;
};

/// Bounds-checked reader over a byte span. Offsets in errors are relative to the span start.
class Reader {
 public:
  Reader(std::span<const std::uint8_t> data, const CodecLimits& limits,
         std::shared_ptr<const std::vector<std::uint8_t>> owner = {})
      : data_(data), limits_(limits), owner_(std::move(owner)) {}

  std::size_t offset() const { return pos_; }
  std::size_t remaining() const { return data_.size() - pos_; }
  const CodecLimits& limits() const { return limits_; }

  std::uint8_t u8(const char* what);
  std::uint16_t u16(const char* what);
  std::uint32_t u32(const char* what);
  std::uint64_t u64(const char* what);
  float f32(const char* what);
  double f64(const char* what);
  /// uint32 length then bytes; the length is checked against the remaining bytes.
  std::string string(const char* what);
  std::span<const std::uint8_t> bytes_with_length(const char* what);
  /// Raw view (shares `owner` if the reader has one, else copies).
  RawBytes raw(const char* what);
  /// A count of elements each taking at least `min_element_bytes`; checked against what remains.
  std::uint32_t count(const char* what, std::size_t min_element_bytes);
  /// Counts materialised values against max_values.
  void account_value();

  /// Throws kTrailingBytes if anything is left.
  void expect_end(const char* what) const;

 private:
  void need(std::size_t n, const char* what) const;

  std::span<const std::uint8_t> data_;
  const CodecLimits& limits_;
  std::shared_ptr<const std::vector<std::uint8_t>> owner_;
  std::size_t pos_ = 0;
  std::size_t values_ = 0;
};

/// Encodes `v` with its own type (for a dynamic: signature string, then the value).
void encode_value(const Value& v, Writer& w);
std::vector<std::uint8_t> encode(const Value& v);

/// Decodes one value of type `t`. `depth` counts enclosing containers.
Value decode_value(const Type& t, Reader& r, std::size_t depth = 0);
/// Decodes a whole payload holding exactly one value of type `t` (kTrailingBytes otherwise).
Value decode(const Type& t, std::span<const std::uint8_t> payload, const CodecLimits& limits,
             std::shared_ptr<const std::vector<std::uint8_t>> owner = {});

/// Capability map `{sm}` (PROTOCOL.md 3.3): keys to the values inside the dynamics.
using CapabilityMap = std::map<std::string, Value>;
std::vector<std::uint8_t> encode_capabilities(const CapabilityMap& caps);
CapabilityMap decode_capabilities(std::span<const std::uint8_t> payload, const CodecLimits& limits);

/// Text of an Error message payload (a dynamic, normally holding a string). Non-string contents
/// are rendered with to_debug_string(). Throws ProtocolError when the payload is malformed.
std::string decode_error_text(std::span<const std::uint8_t> payload, const CodecLimits& limits);
std::vector<std::uint8_t> encode_error_text(std::string_view text);

}  // namespace pepper::naoqi_bridge::qi
