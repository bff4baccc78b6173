// getImageRemote reply: walk the [m] elements, pixels as a view (PROTOCOL.md 7.2).
#include "naoqi_bridge/qi/image_remote.hpp"

namespace pepper::naoqi_bridge::qi {

namespace {

std::int32_t int_field(const Value& v, int index) {
  const Value& u = v.unwrapped();
  if (!is_integer(u.kind())) {
    throw ProtocolError(ProtocolErrc::kTypeMismatch,
                        "getImageRemote element " + std::to_string(index) +
                            ": expected an integer, got '" + u.signature() + "'");
  }
  const std::int64_t i = u.as_int();
  if (i < INT32_MIN || i > INT32_MAX) {
    throw ProtocolError(ProtocolErrc::kBadValue,
                        "getImageRemote element " + std::to_string(index) + " out of range");
  }
  return static_cast<std::int32_t>(i);
}

}  // namespace

ImageRemote decode_image_remote(std::span<const std::uint8_t> payload, const CodecLimits& limits,
                                std::shared_ptr<const std::vector<std::uint8_t>> owner) {
  Reader r(payload, limits, std::move(owner));
  const std::string sig = r.string("getImageRemote signature");
  if (sig.empty()) throw ProtocolError(ProtocolErrc::kBadValue, "getImageRemote: no image");
  if (sig != "[m]" && sig != "(mmmmmmmmmmmm)") {
    throw ProtocolError(ProtocolErrc::kTypeMismatch,
                        "getImageRemote: expected a dynamic holding '[m]', got '" + sig + "'");
  }
  std::uint32_t n = 12;
  if (sig == "[m]") n = r.count("getImageRemote element list", 4);
  if (n < 7) {
    throw ProtocolError(ProtocolErrc::kBadValue,
                        "getImageRemote: " + std::to_string(n) + " elements, at least 7 expected");
  }
  static const Type dyn = Type::of(TypeKind::kDynamic);
  ImageRemote img;
  for (std::uint32_t i = 0; i < n; ++i) {
    const Value e = decode_value(dyn, r, 1);
    const int idx = static_cast<int>(i);
    switch (i) {
      case 0:
        img.width_px = int_field(e, idx);
        break;
      case 1:
        img.height_px = int_field(e, idx);
        break;
      case 2:
        img.layers = int_field(e, idx);
        break;
      case 3:
        img.color_space = int_field(e, idx);
        break;
      case 4:
        img.t_sec = int_field(e, idx);
        break;
      case 5:
        img.t_usec = int_field(e, idx);
        break;
      case 6: {
        const Value& u = e.unwrapped();
        if (u.kind() != TypeKind::kRaw) {
          throw ProtocolError(
              ProtocolErrc::kTypeMismatch,
              "getImageRemote element 6: expected raw pixels 'r', got '" + u.signature() + "'");
        }
        img.pixels = u.as_raw();
        break;
      }
      case 7:
        img.camera_index = int_field(e, idx);
        break;
      case 8:
      case 9:
      case 10:
      case 11: {
        const Value& u = e.unwrapped();
        if (!is_numeric(u.kind())) {
          throw ProtocolError(ProtocolErrc::kTypeMismatch,
                              "getImageRemote element " + std::to_string(i) +
                                  ": expected an angle, got '" + u.signature() + "'");
        }
        img.angles_rad[i - 8] = static_cast<float>(u.as_double());
        break;
      }
      default:
        break;  // later NAOqi versions may append fields
    }
  }
  r.expect_end("getImageRemote reply");
  if (img.width_px <= 0 || img.height_px <= 0 || img.layers <= 0 || img.width_px > 8192 ||
      img.height_px > 8192 || img.layers > 4) {
    throw ProtocolError(ProtocolErrc::kBadValue,
                        "getImageRemote: implausible size " + std::to_string(img.width_px) + "x" +
                            std::to_string(img.height_px) + "x" + std::to_string(img.layers));
  }
  const std::size_t expected = static_cast<std::size_t>(img.width_px) *
                               static_cast<std::size_t>(img.height_px) *
                               static_cast<std::size_t>(img.layers);
  if (img.pixels.size != expected) {
    throw ProtocolError(ProtocolErrc::kBadValue,
                        "getImageRemote: " + std::to_string(img.pixels.size) + " pixel bytes for " +
                            std::to_string(img.width_px) + "x" + std::to_string(img.height_px) +
                            "x" + std::to_string(img.layers) + " (expected " +
                            std::to_string(expected) + ")");
  }
  if (img.t_usec < 0 || img.t_usec >= 1'000'000) {
    throw ProtocolError(
        ProtocolErrc::kBadValue,
        "getImageRemote: microseconds " + std::to_string(img.t_usec) + " outside 0..999999");
  }
  return img;
}

void encode_image_remote(const ImageRemote& image, Writer& w) {
  auto dyn_int = [&](std::int32_t v) {
    w.string("i");
    w.u32(static_cast<std::uint32_t>(v));
  };
  w.string("[m]");
  w.u32(12);
  dyn_int(image.width_px);
  dyn_int(image.height_px);
  dyn_int(image.layers);
  dyn_int(image.color_space);
  dyn_int(image.t_sec);
  dyn_int(image.t_usec);
  w.string("r");
  w.bytes_with_length(image.pixels.view());
  dyn_int(image.camera_index);
  for (float a : image.angles_rad) {
    w.string("f");
    w.f32(a);
  }
}

}  // namespace pepper::naoqi_bridge::qi
