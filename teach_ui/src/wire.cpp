// Binary message framing (see teach_ui/wire.hpp).
#include "teach_ui/wire.hpp"

#include <limits>
#include <stdexcept>

namespace pepper::teach_ui {

std::string encode_binary_message(std::uint8_t kind, std::string_view header_json,
                                  std::string_view payload) {
  if (header_json.size() > std::numeric_limits<std::uint32_t>::max()) {
    throw std::length_error("encode_binary_message: header over 4 GiB");
  }
  const auto n = static_cast<std::uint32_t>(header_json.size());
  std::string out;
  out.reserve(5 + header_json.size() + payload.size());
  out.push_back(static_cast<char>(kind));
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((n >> (8 * i)) & 0xFFu));
  out.append(header_json);
  out.append(payload);
  return out;
}

std::optional<BinaryMessageView> decode_binary_message(std::string_view message) {
  if (message.size() < 5) return std::nullopt;
  std::uint32_t n = 0;
  for (int i = 0; i < 4; ++i) {
    n |= static_cast<std::uint32_t>(static_cast<unsigned char>(message[1 + i])) << (8 * i);
  }
  if (n > message.size() - 5) return std::nullopt;
  BinaryMessageView view;
  view.kind = static_cast<std::uint8_t>(message[0]);
  view.header_json = message.substr(5, n);
  view.payload = message.substr(5 + n);
  return view;
}

}  // namespace pepper::teach_ui
