// Strictness of the decoder: every truncation and overflow of a header or payload is rejected
// with a typed ProtocolError that names the problem; nothing crashes or over-allocates.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "naoqi_bridge/qi/codec.hpp"
#include "naoqi_bridge/qi/image_remote.hpp"
#include "naoqi_bridge/qi/message.hpp"
#include "naoqi_bridge/qi/meta.hpp"

namespace qi = pepper::naoqi_bridge::qi;
using qi::ProtocolErrc;
using qi::Value;
using Bytes = std::vector<std::uint8_t>;

namespace {

template <class F>
ProtocolErrc error_code_of(F&& f) {
  try {
    f();
  } catch (const qi::ProtocolError& e) {
    return e.code();
  }
  ADD_FAILURE() << "no ProtocolError thrown";
  return ProtocolErrc::kUnsupported;
}

template <class F>
std::string error_text_of(F&& f) {
  try {
    f();
  } catch (const qi::ProtocolError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ProtocolError thrown";
  return {};
}

void put32(Bytes& b, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

Bytes valid_header(std::uint32_t size = 0) {
  qi::MessageHeader h;
  h.id = 1;
  h.size = size;
  h.type = qi::MessageType::kCall;
  const auto a = qi::encode_header(h);
  return Bytes(a.begin(), a.end());
}

/// Every proper prefix of a valid payload must be refused (it is a truncated value).
void expect_all_truncations_rejected(const qi::Type& t, const Bytes& full) {
  ASSERT_NO_THROW((void)qi::decode(t, full, {})) << t.to_string();
  for (std::size_t n = 0; n < full.size(); ++n) {
    const Bytes prefix(full.begin(), full.begin() + static_cast<long>(n));
    const auto code = error_code_of([&] { (void)qi::decode(t, prefix, {}); });
    EXPECT_TRUE(code == ProtocolErrc::kTruncated || code == ProtocolErrc::kCountTooLarge)
        << t.to_string() << " prefix " << n << " gave " << qi::to_string(code);
  }
  // One byte too many is refused as well.
  Bytes longer = full;
  longer.push_back(0);
  EXPECT_EQ(error_code_of([&] { (void)qi::decode(t, longer, {}); }), ProtocolErrc::kTrailingBytes);
}

}  // namespace

TEST(QiMalformed, HeaderTruncatedAtEveryLength) {
  const Bytes h = valid_header();
  for (std::size_t n = 0; n < qi::kHeaderSize; ++n) {
    EXPECT_EQ(error_code_of(
                  [&] { (void)qi::decode_header(std::span<const std::uint8_t>(h.data(), n), {}); }),
              ProtocolErrc::kTruncated)
        << n;
  }
}

TEST(QiMalformed, HeaderBadMagicTypeAndSize) {
  Bytes h = valid_header();
  h[1] = 0xDF;
  EXPECT_EQ(error_code_of([&] { (void)qi::decode_header(h, {}); }), ProtocolErrc::kBadMagic);
  h = valid_header();
  h[14] = 9;
  EXPECT_EQ(error_code_of([&] { (void)qi::decode_header(h, {}); }), ProtocolErrc::kUnknownType);
  qi::CodecLimits limits;
  limits.max_payload_bytes = 1000;
  h = valid_header(1001);
  const std::string text = error_text_of([&] { (void)qi::decode_header(h, limits); });
  EXPECT_EQ(text, "payload size 1001 at offset 8 exceeds limit 1000 bytes");
  h = valid_header(1000);
  EXPECT_NO_THROW((void)qi::decode_header(h, limits));
  // A version other than 0 is accepted, as libqi does.
  h[12] = 7;
  EXPECT_NO_THROW((void)qi::decode_header(h, limits));
}

TEST(QiMalformed, SplitterRejectsHostileSizeBeforeReadingIt) {
  qi::CodecLimits limits;
  limits.max_payload_bytes = 1u << 20;
  qi::MessageSplitter splitter(limits);
  const Bytes h = valid_header(0xFFFFFFFFu);
  EXPECT_EQ(error_code_of([&] { (void)splitter.feed(h); }), ProtocolErrc::kPayloadTooLarge);
  // A partial message yields nothing and keeps the bytes.
  qi::MessageSplitter ok(limits);
  const Bytes partial = valid_header(10);
  EXPECT_TRUE(ok.feed(partial).empty());
  EXPECT_EQ(ok.buffered(), qi::kHeaderSize);
}

TEST(QiMalformed, ListCountBeyondRemainingBytesNamesIt) {
  // (iii[i]): the list count sits at offset 12; 30 bytes follow it.
  Bytes b(12, 0);
  put32(b, 0xFFFFFFFFu);
  b.resize(b.size() + 30, 0);
  const std::string text =
      error_text_of([&] { (void)qi::decode(qi::parse_signature("(iii[i])"), b, {}); });
  EXPECT_EQ(text, "list count 4294967295 at offset 12 exceeds remaining 30 bytes");
}

TEST(QiMalformed, StringAndRawLengthsBeyondRemaining) {
  Bytes b;
  put32(b, 100);
  b.push_back('a');
  EXPECT_EQ(error_code_of([&] { (void)qi::decode(qi::parse_signature("s"), b, {}); }),
            ProtocolErrc::kCountTooLarge);
  EXPECT_EQ(error_code_of([&] { (void)qi::decode(qi::parse_signature("r"), b, {}); }),
            ProtocolErrc::kCountTooLarge);
  EXPECT_EQ(error_code_of([&] { (void)qi::decode(qi::parse_signature("m"), b, {}); }),
            ProtocolErrc::kCountTooLarge);
}

TEST(QiMalformed, MapCountAndZeroSizeElementCount) {
  Bytes b;
  put32(b, 1000);
  b.resize(40, 0);
  EXPECT_EQ(error_code_of([&] { (void)qi::decode(qi::parse_signature("{ii}"), b, {}); }),
            ProtocolErrc::kCountTooLarge);
  // Elements of zero bytes ([()]) cannot be bounded by the remaining bytes: max_values does it.
  Bytes z;
  put32(z, 0xFFFFFFFFu);
  EXPECT_EQ(error_code_of([&] { (void)qi::decode(qi::parse_signature("[()]"), z, {}); }),
            ProtocolErrc::kCountTooLarge);
}

TEST(QiMalformed, TooManyValuesIsBounded) {
  qi::CodecLimits limits;
  limits.max_values = 100;
  Bytes b;
  put32(b, 1000);
  b.resize(4 + 1000, 0);
  EXPECT_EQ(error_code_of([&] { (void)qi::decode(qi::parse_signature("[b]"), b, limits); }),
            ProtocolErrc::kTooManyValues);
  limits.max_values = 2000;
  EXPECT_NO_THROW((void)qi::decode(qi::parse_signature("[b]"), b, limits));
}

TEST(QiMalformed, DepthOfNestedDynamicsIsBounded) {
  Bytes b;
  for (int i = 0; i < 100; ++i) {
    put32(b, 1);
    b.push_back('m');
  }
  put32(b, 1);
  b.push_back('i');
  put32(b, 5);
  EXPECT_EQ(error_code_of([&] {
              (void)qi::decode(qi::Type::of(qi::TypeKind::kDynamic), b, qi::CodecLimits{});
            }),
            ProtocolErrc::kTooDeep);
}

TEST(QiMalformed, BadBoolOptionalSignatureAndUnknownType) {
  EXPECT_EQ(error_code_of([&] { (void)qi::decode(qi::parse_signature("b"), Bytes{2}, {}); }),
            ProtocolErrc::kBadValue);
  EXPECT_EQ(error_code_of([&] { (void)qi::decode(qi::parse_signature("+i"), Bytes{5}, {}); }),
            ProtocolErrc::kBadValue);
  Bytes bad_sig;
  put32(bad_sig, 2);
  bad_sig.push_back('[');
  bad_sig.push_back('q');
  EXPECT_EQ(
      error_code_of([&] { (void)qi::decode(qi::Type::of(qi::TypeKind::kDynamic), bad_sig, {}); }),
      ProtocolErrc::kBadSignature);
  Bytes unknown;
  put32(unknown, 1);
  unknown.push_back('X');
  EXPECT_EQ(
      error_code_of([&] { (void)qi::decode(qi::Type::of(qi::TypeKind::kDynamic), unknown, {}); }),
      ProtocolErrc::kUnsupported);
}

TEST(QiMalformed, EveryTruncationOfRealPayloadsIsRejected) {
  using qi::Type;
  expect_all_truncations_rejected(
      qi::parse_signature("(fff)"),
      qi::encode(Value::tuple({Value::float32(0.1f), Value::float32(0), Value::float32(0)})));
  expect_all_truncations_rejected(
      qi::parse_signature("(mm)"),
      qi::encode(Value::tuple({Value::dynamic(Value::strings({"HeadYaw", "HeadPitch"})),
                               Value::dynamic(Value::floats({1.f, 1.f}))})));
  qi::MetaObject mo;
  mo.methods[135] = {135, "v", "move", "(fff)", "", {{"x", ""}}, ""};
  mo.signals[106] = {106, "serviceAdded", "(Is)"};
  expect_all_truncations_rejected(qi::parse_signature(qi::MetaObject::signature()),
                                  qi::encode(mo.to_value()));
  qi::CapabilityMap caps;
  caps["MessageFlags"] = Value::boolean(true);
  caps["auth_user"] = Value::string("nao");
  expect_all_truncations_rejected(qi::parse_signature("{sm}"), qi::encode_capabilities(caps));
}

TEST(QiMalformed, ImageReplyTruncationsAndWrongPixelCount) {
  qi::ImageRemote img;
  img.width_px = 8;
  img.height_px = 4;
  img.layers = 1;
  const Bytes pixels(32, 9);
  img.pixels = qi::RawBytes::copy_of(pixels);
  Bytes payload;
  qi::Writer w(payload);
  qi::encode_image_remote(img, w);
  ASSERT_NO_THROW((void)qi::decode_image_remote(payload, {}));
  for (std::size_t n = 0; n < payload.size(); ++n) {
    const Bytes prefix(payload.begin(), payload.begin() + static_cast<long>(n));
    EXPECT_THROW((void)qi::decode_image_remote(prefix, {}), qi::ProtocolError) << n;
  }
  img.width_px = 9;  // 9x4 claims 36 bytes, 32 present
  Bytes wrong;
  qi::Writer w2(wrong);
  qi::encode_image_remote(img, w2);
  EXPECT_EQ(error_code_of([&] { (void)qi::decode_image_remote(wrong, {}); }),
            ProtocolErrc::kBadValue);
  // "No image": an empty dynamic.
  EXPECT_EQ(error_code_of([&] {
              (void)qi::decode_image_remote(Bytes{0, 0, 0, 0}, {});
            }),
            ProtocolErrc::kBadValue);
}

TEST(QiMalformed, ServiceInfoTruncationsRejected) {
  qi::ServiceInfo info;
  info.name = "ALMotion";
  info.service_id = 2;
  info.endpoints = {"tcp://127.0.0.1:9559"};
  const Bytes b = qi::encode(info.to_value());
  for (std::size_t n = 0; n < b.size(); ++n) {
    EXPECT_THROW(
        (void)qi::ServiceInfo::decode(Bytes(b.begin(), b.begin() + static_cast<long>(n)), {}),
        qi::ProtocolError)
        << n;
  }
}
