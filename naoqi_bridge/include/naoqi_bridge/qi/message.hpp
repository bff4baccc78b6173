#pragma once
// qi message framing (PROTOCOL.md sections 1 and 2): the 28-byte header and a whole message.
//
// Header fields are little-endian; the magic is the bytes 42 DE AD 42. decode_header() checks the
// magic, the message type and the payload size against CodecLimits::max_payload_bytes before
// any payload is read, so a hostile size never causes an allocation. MessageSplitter turns an
// arbitrary byte stream (TCP segments) into messages with the same checks; the fuzz target
// drives it.
//
// Plain C++ (no Asio, no OpenCV).

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "naoqi_bridge/qi/codec.hpp"

namespace pepper::naoqi_bridge::qi {

inline constexpr std::size_t kHeaderSize = 28;
inline constexpr std::uint32_t kMagic = 0x42ADDE42;  ///< read as a little-endian uint32

enum class MessageType : std::uint8_t {
  kNone = 0,
  kCall = 1,
  kReply = 2,
  kError = 3,
  kPost = 4,
  kEvent = 5,
  kCapability = 6,
  kCancel = 7,
  kCanceled = 8,
};
const char* to_string(MessageType type);

namespace flags {
inline constexpr std::uint8_t kDynamicPayload = 0x01;  ///< payload is one `m`
inline constexpr std::uint8_t kReturnType = 0x02;      ///< call carries the wanted return signature
}  // namespace flags

/// Fixed ids (PROTOCOL.md section 2).
namespace ids {
inline constexpr std::uint32_t kServerService = 0;
inline constexpr std::uint32_t kAuthenticateAction = 8;
inline constexpr std::uint32_t kDirectoryService = 1;
inline constexpr std::uint32_t kMainObject = 1;
inline constexpr std::uint32_t kRegisterEvent = 0;
inline constexpr std::uint32_t kUnregisterEvent = 1;
inline constexpr std::uint32_t kMetaObject = 2;
inline constexpr std::uint32_t kDirectoryServiceAction = 100;   ///< service(s) -> ServiceInfo
inline constexpr std::uint32_t kDirectoryServicesAction = 101;  ///< services() -> [ServiceInfo]
inline constexpr std::uint32_t kDirectoryMachineId = 108;
}  // namespace ids

struct MessageHeader {
  std::uint32_t id = 0;
  std::uint32_t size = 0;  ///< payload bytes
  std::uint16_t version = 0;
  MessageType type = MessageType::kNone;
  std::uint8_t flags = 0;
  std::uint32_t service = 0;
  std::uint32_t object = 0;
  std::uint32_t action = 0;

  /// "Call id=7 1.1.100 size=17"
  std::string to_string() const;
};

std::array<std::uint8_t, kHeaderSize> encode_header(const MessageHeader& h);
/// Throws ProtocolError: kTruncated (fewer than 28 bytes), kBadMagic, kUnknownType,
/// kPayloadTooLarge.
MessageHeader decode_header(std::span<const std::uint8_t> bytes, const CodecLimits& limits);

/// A received message: header plus its payload (shared: raw values decoded from it point into it).
struct Message {
  MessageHeader header;
  std::shared_ptr<const std::vector<std::uint8_t>> payload;

  std::span<const std::uint8_t> bytes() const {
    return payload ? std::span<const std::uint8_t>(*payload) : std::span<const std::uint8_t>();
  }
};

/// Header + payload in one buffer; sets header.size from the payload.
std::vector<std::uint8_t> serialize(MessageHeader header, std::span<const std::uint8_t> payload);

/// Splits a byte stream into messages. feed() returns the messages completed by these bytes;
/// a framing violation throws ProtocolError and leaves the splitter unusable (close the link).
class MessageSplitter {
 public:
  explicit MessageSplitter(CodecLimits limits = {}) : limits_(limits) {}
  std::vector<Message> feed(std::span<const std::uint8_t> bytes);
  std::size_t buffered() const { return pending_.size(); }

 private:
  CodecLimits limits_;
  std::vector<std::uint8_t> pending_;
};

}  // namespace pepper::naoqi_bridge::qi
