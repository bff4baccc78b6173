#pragma once
// ProtocolError: a malformed or unsupported qi message, as found by the codec.
//
// The codec (signature parser, value encoder/decoder, header decoder) throws only this type.
// `code()` says what kind of violation it was; `what()` names the field, the offending value and
// the byte offset, e.g. "list count 4294967295 at offset 12 exceeds remaining 30 bytes".
// The client and the mock server react to it by closing that one connection; nothing aborts.
//
// Plain C++ (no Asio, no OpenCV) so that the fuzz target can build the codec alone.

#include <stdexcept>
#include <string>

namespace pepper::naoqi_bridge::qi {

enum class ProtocolErrc {
  kBadMagic,         ///< header magic is not 42 DE AD 42
  kUnknownType,      ///< header message type outside 0..8
  kPayloadTooLarge,  ///< header size above CodecLimits::max_payload_bytes
  kTruncated,        ///< a field runs past the end of the buffer
  kCountTooLarge,    ///< a list/map count or string length cannot fit in what remains
  kTooDeep,          ///< nesting deeper than CodecLimits::max_depth
  kTooManyValues,    ///< more decoded values than CodecLimits::max_values
  kBadSignature,     ///< unparsable signature string
  kBadValue,         ///< a value outside its domain (bool not 0/1, optional flag not 0/1...)
  kTrailingBytes,    ///< bytes left over after the expected value
  kTypeMismatch,     ///< a value does not have (and cannot be converted to) the expected type
  kUnsupported,      ///< a type that cannot cross the wire (X, void in a list...)
};

const char* to_string(ProtocolErrc code);

class ProtocolError : public std::runtime_error {
 public:
  ProtocolError(ProtocolErrc code, const std::string& message)
      : std::runtime_error(message), code_(code) {}
  ProtocolErrc code() const noexcept { return code_; }

 private:
  ProtocolErrc code_;
};

}  // namespace pepper::naoqi_bridge::qi
