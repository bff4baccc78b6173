#pragma once
// ALVideoDevice.getImageRemote reply (PROTOCOL.md 7.2): a dynamic holding a list of 12 dynamics
// (width, height, layers, colour space, seconds, microseconds, pixels `r`, camera index, four
// angles). The decoder walks the elements and reads each one's signature (no fixed offsets), and
// returns the pixels as a view into the received payload: no copy.
//
// Plain C++ (no Asio, no OpenCV).

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "naoqi_bridge/qi/codec.hpp"

namespace pepper::naoqi_bridge::qi {

struct ImageRemote {
  std::int32_t width_px = 0;
  std::int32_t height_px = 0;
  std::int32_t layers = 0;       ///< bytes per pixel
  std::int32_t color_space = 0;  ///< 0 = kYuv (grey)
  std::int32_t t_sec = 0;        ///< robot timestamp, seconds
  std::int32_t t_usec = 0;       ///< robot timestamp, microseconds
  RawBytes pixels;               ///< width x height x layers bytes, row-major
  std::int32_t camera_index = 0;
  std::array<float, 4> angles_rad{};  ///< left, top, right, bottom

  /// Capture time in ns: seconds * 1e9 + microseconds * 1e3.
  std::int64_t t_ns() const {
    return static_cast<std::int64_t>(t_sec) * 1'000'000'000 +
           static_cast<std::int64_t>(t_usec) * 1'000;
  }
};

/// Decodes a reply payload (return signature `m`). Throws ProtocolError when the structure or
/// the pixel byte count (width x height x layers) is wrong. An empty dynamic (no image
/// available) throws kBadValue "no image".
ImageRemote decode_image_remote(std::span<const std::uint8_t> payload, const CodecLimits& limits,
                                std::shared_ptr<const std::vector<std::uint8_t>> owner = {});

/// Encodes the reply payload (the mock server uses it; pixels copied once into `w`).
void encode_image_remote(const ImageRemote& image, Writer& w);

}  // namespace pepper::naoqi_bridge::qi
