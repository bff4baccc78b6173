// libFuzzer target for the qi decoder: framing, signatures, values, capability maps, MetaObject,
// ServiceInfo and getImageRemote replies. Built with clang++ -fsanitize=fuzzer,address,undefined
// from the codec sources only (naoqi_bridge/CMakeLists.txt). Every input must either decode or
// throw ProtocolError; anything else (crash, leak, UB, other exception) is a bug.
//
// Input layout: byte 0 selects what to decode, the rest is the data.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "naoqi_bridge/qi/codec.hpp"
#include "naoqi_bridge/qi/image_remote.hpp"
#include "naoqi_bridge/qi/message.hpp"
#include "naoqi_bridge/qi/meta.hpp"

namespace qi = pepper::naoqi_bridge::qi;

namespace {

const char* const kSignatures[] = {
    "m",    "{sm}",       "(fff)", "(mm)",       "(mmf)",          "(mb)",  "(siiii)",
    "[f]",  "[s]",        "[m]",   "(sIsI[s]s)", "(Is)",           "(IIL)", "{sf}",
    "(bi)", "+[{s(ib)}]", "#s",    "o",          "(cCwWiIlLfdsr)", "[()]",  "[[[[i]]]]",
};

qi::CodecLimits small_limits() {
  qi::CodecLimits l;
  l.max_payload_bytes = 1u << 20;
  l.max_depth = 16;
  l.max_values = 1u << 14;
  return l;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const qi::CodecLimits limits = small_limits();
  const std::uint8_t mode = data[0];
  std::span<const std::uint8_t> rest(data + 1, size - 1);
  try {
    switch (mode % 8) {
      case 0: {  // a byte stream of messages, fed in two pieces
        qi::MessageSplitter splitter(limits);
        const std::size_t cut = rest.size() / 2;
        for (auto part : {rest.first(cut), rest.subspan(cut)}) {
          for (const auto& m : splitter.feed(part)) {
            if (m.header.type == qi::MessageType::kError) {
              (void)qi::decode_error_text(m.bytes(), limits);
            } else if (m.header.type == qi::MessageType::kCapability) {
              (void)qi::decode_capabilities(m.bytes(), limits);
            }
          }
        }
        break;
      }
      case 1: {  // a signature string
        const std::string_view text(reinterpret_cast<const char*>(rest.data()), rest.size());
        const qi::Type t = qi::parse_signature(text, limits.max_depth);
        (void)qi::min_encoded_size(t);
        (void)t.to_string();
        break;
      }
      case 2: {  // value of a fixed signature, then re-encode and decode again (round trip)
        if (rest.empty()) return 0;
        const auto n = sizeof(kSignatures) / sizeof(kSignatures[0]);
        const qi::Type t = qi::parse_signature(kSignatures[rest[0] % n]);
        const qi::Value v = qi::decode(t, rest.subspan(1), limits);
        const auto again = qi::encode(v);
        (void)qi::decode(t, again, limits);
        (void)v.to_debug_string();
        break;
      }
      case 3:
        (void)qi::decode_capabilities(rest, limits);
        break;
      case 4: {
        auto owner = std::make_shared<const std::vector<std::uint8_t>>(rest.begin(), rest.end());
        (void)qi::decode_image_remote(*owner, limits, owner);
        break;
      }
      case 5: {
        static const qi::Type t = qi::parse_signature(qi::MetaObject::signature());
        (void)qi::MetaObject::from_value(qi::decode(t, rest, limits));
        break;
      }
      case 6:
        (void)qi::ServiceInfo::decode(rest, limits);
        break;
      case 7: {  // a dynamic value, then its conversion to a few target types
        const qi::Value v = qi::decode(qi::Type::of(qi::TypeKind::kDynamic), rest, limits);
        for (const char* target : {"[f]", "(fff)", "s", "{sm}", "i"}) {
          try {
            (void)qi::convert(v, qi::parse_signature(target));
          } catch (const qi::ProtocolError&) {
          }
        }
        break;
      }
    }
  } catch (const qi::ProtocolError&) {
    // Expected for malformed input.
  }
  return 0;
}
