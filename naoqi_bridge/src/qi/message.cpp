// qi message header encoding/decoding and stream splitting (PROTOCOL.md section 1).
#include "naoqi_bridge/qi/message.hpp"

#include <cstdio>
#include <cstring>

namespace pepper::naoqi_bridge::qi {

const char* to_string(MessageType type) {
  switch (type) {
    case MessageType::kNone:
      return "None";
    case MessageType::kCall:
      return "Call";
    case MessageType::kReply:
      return "Reply";
    case MessageType::kError:
      return "Error";
    case MessageType::kPost:
      return "Post";
    case MessageType::kEvent:
      return "Event";
    case MessageType::kCapability:
      return "Capability";
    case MessageType::kCancel:
      return "Cancel";
    case MessageType::kCanceled:
      return "Canceled";
  }
  return "?";
}

std::string MessageHeader::to_string() const {
  return std::string(qi::to_string(type)) + " id=" + std::to_string(id) + " " +
         std::to_string(service) + "." + std::to_string(object) + "." + std::to_string(action) +
         " size=" + std::to_string(size) + " flags=" + std::to_string(flags);
}

namespace {
void put32(std::uint8_t* p, std::uint32_t v) { std::memcpy(p, &v, 4); }
std::uint32_t get32(const std::uint8_t* p) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}
}  // namespace

std::array<std::uint8_t, kHeaderSize> encode_header(const MessageHeader& h) {
  std::array<std::uint8_t, kHeaderSize> b{};
  put32(b.data(), kMagic);
  put32(b.data() + 4, h.id);
  put32(b.data() + 8, h.size);
  std::memcpy(b.data() + 12, &h.version, 2);
  b[14] = static_cast<std::uint8_t>(h.type);
  b[15] = h.flags;
  put32(b.data() + 16, h.service);
  put32(b.data() + 20, h.object);
  put32(b.data() + 24, h.action);
  return b;
}

MessageHeader decode_header(std::span<const std::uint8_t> bytes, const CodecLimits& limits) {
  if (bytes.size() < kHeaderSize) {
    throw ProtocolError(ProtocolErrc::kTruncated,
                        "message header needs 28 bytes, got " + std::to_string(bytes.size()));
  }
  const std::uint32_t magic = get32(bytes.data());
  if (magic != kMagic) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "bad magic %02x %02x %02x %02x at offset 0", bytes[0], bytes[1],
                  bytes[2], bytes[3]);
    throw ProtocolError(ProtocolErrc::kBadMagic, buf);
  }
  MessageHeader h;
  h.id = get32(bytes.data() + 4);
  h.size = get32(bytes.data() + 8);
  std::memcpy(&h.version, bytes.data() + 12, 2);
  if (bytes[14] > static_cast<std::uint8_t>(MessageType::kCanceled)) {
    throw ProtocolError(ProtocolErrc::kUnknownType,
                        "unknown message type " + std::to_string(bytes[14]) + " at offset 14");
  }
  h.type = static_cast<MessageType>(bytes[14]);
  h.flags = bytes[15];
  h.service = get32(bytes.data() + 16);
  h.object = get32(bytes.data() + 20);
  h.action = get32(bytes.data() + 24);
  if (h.size > limits.max_payload_bytes) {
    throw ProtocolError(ProtocolErrc::kPayloadTooLarge,
                        "payload size " + std::to_string(h.size) + " at offset 8 exceeds limit " +
                            std::to_string(limits.max_payload_bytes) + " bytes");
  }
  return h;
}

std::vector<std::uint8_t> serialize(MessageHeader header, std::span<const std::uint8_t> payload) {
  if (payload.size() > 0xFFFFFFFFu) {
    throw ProtocolError(ProtocolErrc::kPayloadTooLarge, "payload exceeds 4 GiB");
  }
  header.size = static_cast<std::uint32_t>(payload.size());
  const auto h = encode_header(header);
  std::vector<std::uint8_t> out;
  out.reserve(kHeaderSize + payload.size());
  out.insert(out.end(), h.begin(), h.end());
  out.insert(out.end(), payload.begin(), payload.end());
  return out;
}

std::vector<Message> MessageSplitter::feed(std::span<const std::uint8_t> bytes) {
  pending_.insert(pending_.end(), bytes.begin(), bytes.end());
  std::vector<Message> out;
  std::size_t pos = 0;
  while (pending_.size() - pos >= kHeaderSize) {
    const MessageHeader h =
        decode_header(std::span<const std::uint8_t>(pending_).subspan(pos, kHeaderSize), limits_);
    if (pending_.size() - pos - kHeaderSize < h.size) break;
    const auto* start = pending_.data() + pos + kHeaderSize;
    Message m;
    m.header = h;
    m.payload = std::make_shared<const std::vector<std::uint8_t>>(start, start + h.size);
    out.push_back(std::move(m));
    pos += kHeaderSize + h.size;
  }
  pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(pos));
  return out;
}

}  // namespace pepper::naoqi_bridge::qi
