#pragma once
// Binary WebSocket message framing of the teach UI (server -> page), see docs/teach_ui.md.
//
// Layout: byte 0 = kind (kBinaryFrame or kBinaryImage), bytes 1..4 = header length N as an
// unsigned 32-bit little-endian integer, bytes 5..5+N = UTF-8 JSON header, the rest = the encoded
// image (JPEG or PNG) exactly as the app passed it. Pure functions, never throw except
// encode_binary_message on a header over 4 GiB (std::length_error).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace pepper::teach_ui {

inline constexpr std::uint8_t kBinaryFrame = 1;  ///< camera frame; header {seq, server_ms, overlay}
inline constexpr std::uint8_t kBinaryImage = 2;  ///< named thumbnail; header {name}

std::string encode_binary_message(std::uint8_t kind, std::string_view header_json,
                                  std::string_view payload);

struct BinaryMessageView {
  std::uint8_t kind = 0;
  std::string_view header_json;
  std::string_view payload;
};

/// Splits a binary message; std::nullopt when it is too short or the length is inconsistent.
/// The views point into `message`.
std::optional<BinaryMessageView> decode_binary_message(std::string_view message);

}  // namespace pepper::teach_ui
