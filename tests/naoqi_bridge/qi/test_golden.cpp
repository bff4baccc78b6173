// Golden byte sequences derived by hand from the captured examples of PROTOCOL.md (sections 3.4,
// 4.1, 5.1, 5.2, 5.3, 5.5, 6.2, 7.2): what we encode must equal them byte for byte, and what we
// decode from them must give the documented values.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "naoqi_bridge/qi/codec.hpp"
#include "naoqi_bridge/qi/image_remote.hpp"
#include "naoqi_bridge/qi/message.hpp"
#include "naoqi_bridge/qi/meta.hpp"

namespace qi = pepper::naoqi_bridge::qi;
using qi::Value;
using Bytes = std::vector<std::uint8_t>;

namespace {

Bytes hex(const std::string& text) {
  Bytes out;
  unsigned v = 0;
  int n = 0;
  for (char c : text) {
    int d = -1;
    if (c >= '0' && c <= '9') d = c - '0';
    if (c >= 'a' && c <= 'f') d = c - 'a' + 10;
    if (d < 0) continue;
    v = v * 16 + static_cast<unsigned>(d);
    if (++n == 2) {
      out.push_back(static_cast<std::uint8_t>(v));
      v = 0;
      n = 0;
    }
  }
  return out;
}

Bytes str(const std::string& s) { return Bytes(s.begin(), s.end()); }

Bytes cat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

Bytes encode_args(std::initializer_list<Value> args) {
  Bytes out;
  qi::Writer w(out);
  for (const auto& a : args) qi::encode_value(a, w);
  return out;
}

}  // namespace

TEST(QiGolden, MoveCallAndReply) {
  qi::MessageHeader h;
  h.id = 0x12;
  h.type = qi::MessageType::kCall;
  h.service = 2;
  h.object = 1;
  h.action = 135;
  const Bytes payload =
      encode_args({Value::float32(0.1f), Value::float32(0.f), Value::float32(0.f)});
  EXPECT_EQ(
      qi::serialize(h, payload),
      hex("42 de ad 42 12 00 00 00 0c 00 00 00 00 00 01 00 02 00 00 00 01 00 00 00 87 00 00 00"
          "cd cc cc 3d 00 00 00 00 00 00 00 00"));
  h.type = qi::MessageType::kReply;
  EXPECT_EQ(
      qi::serialize(h, {}),
      hex("42 de ad 42 12 00 00 00 00 00 00 00 00 00 02 00 02 00 00 00 01 00 00 00 87 00 00 00"));
  // And the header decodes back to the same fields.
  const auto d = qi::decode_header(qi::serialize(h, {}), {});
  EXPECT_EQ(d.id, 0x12u);
  EXPECT_EQ(d.type, qi::MessageType::kReply);
  EXPECT_EQ(d.service, 2u);
  EXPECT_EQ(d.action, 135u);
  EXPECT_EQ(d.size, 0u);
}

TEST(QiGolden, GetRobotPositionPayloads) {
  EXPECT_EQ(encode_args({Value::boolean(false)}), hex("00"));
  const Value v = qi::decode(qi::parse_signature("[f]"),
                             hex("03 00 00 00 cb 5e e3 38 00 00 00 00 00 00 00 00"), {});
  ASSERT_EQ(v.elements().size(), 3u);
  EXPECT_NEAR(v.elements()[0].as_double(), 1.08419e-4, 1e-8);
  EXPECT_EQ(v.elements()[1].as_double(), 0.0);
}

TEST(QiGolden, SetStiffnessesPayload) {
  EXPECT_EQ(
      encode_args({Value::dynamic(Value::string("Body")), Value::dynamic(Value::float32(1.0f))}),
      cat({hex("01 00 00 00 73 04 00 00 00"), str("Body"), hex("01 00 00 00 66 00 00 80 3f")}));
  // List of names with list of values: m "[s]" then m "[f]".
  const Bytes lists = encode_args({Value::dynamic(Value::strings({"HeadYaw", "HeadPitch"})),
                                   Value::dynamic(Value::floats({1.f, 1.f}))});
  const Bytes prefix = cat({hex("03 00 00 00 5b 73 5d 02 00 00 00 07 00 00 00"), str("HeadYaw")});
  ASSERT_GE(lists.size(), prefix.size());
  EXPECT_TRUE(std::equal(prefix.begin(), prefix.end(), lists.begin()));
  // Decoded through the method signature (mm) by a converter from plain values.
  const Value args = qi::convert(Value::tuple({Value::string("Body"), Value::float32(1.0f)}),
                                 qi::parse_signature("(mm)"));
  EXPECT_EQ(qi::encode(args), encode_args({Value::dynamic(Value::string("Body")),
                                           Value::dynamic(Value::float32(1.0f))}));
}

TEST(QiGolden, SubscribeCameraPayloads) {
  EXPECT_EQ(encode_args({Value::string("libqi_bench"), Value::int32(0), Value::int32(2),
                         Value::int32(0), Value::int32(30)}),
            cat({hex("0b 00 00 00"), str("libqi_bench"),
                 hex("00 00 00 00 02 00 00 00 00 00 00 00 1e 00 00 00")}));
  const Value reply =
      qi::decode(qi::parse_signature("s"), cat({hex("0d 00 00 00"), str("libqi_bench_0")}), {});
  EXPECT_EQ(reply.as_string(), "libqi_bench_0");
}

TEST(QiGolden, AuthenticationFailureError) {
  const std::string text = "Authentication failed: invalid user or token [1.0]";
  ASSERT_EQ(text.size(), 0x32u);
  const Bytes wire =
      cat({hex("42 de ad 42 02 00 00 00 3b 00 00 00 00 00 03 00 00 00 00 00 00 00 00 00 08 00 00 00"
               "01 00 00 00 73 32 00 00 00"),
           str(text)});
  qi::MessageHeader h;
  h.id = 2;
  h.type = qi::MessageType::kError;
  h.action = 8;
  EXPECT_EQ(qi::serialize(h, qi::encode_error_text(text)), wire);
  qi::MessageSplitter splitter;
  const auto msgs = splitter.feed(wire);
  ASSERT_EQ(msgs.size(), 1u);
  EXPECT_EQ(msgs[0].header.type, qi::MessageType::kError);
  EXPECT_EQ(qi::decode_error_text(msgs[0].bytes(), {}), text);
}

TEST(QiGolden, AuthenticateCallSizes) {
  // libqi's six capabilities: 161-byte payload; the reply adds __qi_auth_state = I 3: 189 bytes.
  qi::CapabilityMap caps;
  caps["ClientServerSocket"] = Value::boolean(true);
  caps["MessageFlags"] = Value::boolean(true);
  caps["MetaObjectCache"] = Value::boolean(false);
  caps["ObjectPtrUID"] = Value::boolean(true);
  caps["RelativeEndpointURI"] = Value::boolean(true);
  caps["RemoteCancelableCalls"] = Value::boolean(true);
  const Bytes call = qi::encode_capabilities(caps);
  EXPECT_EQ(call.size(), 161u);
  const Bytes start =
      cat({hex("06 00 00 00 12 00 00 00"), str("ClientServerSocket"), hex("01 00 00 00"), str("b"),
           hex("01 0c 00 00 00"), str("MessageFlags"), hex("01 00 00 00"), str("b"),
           hex("01 0f 00 00 00"), str("MetaObjectCache"), hex("01 00 00 00"), str("b"), hex("00")});
  EXPECT_TRUE(std::equal(start.begin(), start.end(), call.begin()));
  caps["__qi_auth_state"] = Value::uint32(3);
  const Bytes reply = qi::encode_capabilities(caps);
  EXPECT_EQ(reply.size(), 189u);
  const Bytes tail = cat({hex("0f 00 00 00"), str("__qi_auth_state"), hex("01 00 00 00"), str("I"),
                          hex("03 00 00 00")});
  EXPECT_TRUE(std::equal(tail.begin(), tail.end(), reply.end() - static_cast<long>(tail.size())));
  qi::MessageHeader h;
  h.id = 2;
  h.type = qi::MessageType::kCall;
  h.action = 8;
  const Bytes wire = qi::serialize(h, call);
  EXPECT_EQ(
      Bytes(wire.begin(), wire.begin() + 28),
      hex("42 de ad 42 02 00 00 00 a1 00 00 00 00 00 01 00 00 00 00 00 00 00 00 00 08 00 00 00"));
}

TEST(QiGolden, ServiceLookupCallAndReply) {
  qi::MessageHeader h;
  h.id = 7;
  h.type = qi::MessageType::kCall;
  h.service = 1;
  h.object = 1;
  h.action = 100;
  EXPECT_EQ(qi::serialize(h, encode_args({Value::string("ALVideoDevice")})),
            cat({hex("42 de ad 42 07 00 00 00 11 00 00 00 00 00 01 00 01 00 00 00 01 00 00 00 64 00"
                     "00 00 0d 00 00 00"),
                 str("ALVideoDevice")}));
  const Bytes uid = hex("07 e1 14 43 6e 1b fc a2 fe 5a 17 43 61 0e b6 f2 a3 2b d9 e7");
  const Bytes reply =
      cat({hex("0d 00 00 00"), str("ALVideoDevice"), hex("03 00 00 00 24 00 00 00"),
           str("9e4d5ece-364d-4ada-a658-b7ac54cc8fcf"), hex("87 55 00 00 02 00 00 00"),
           hex("13 00 00 00"), str("qi:ServiceDirectory"), hex("14 00 00 00"),
           str("tcp://127.0.0.1:9559"), hex("24 00 00 00"),
           str("322b679d-11af-47dd-9ec0-b9e878ba8cd6"), hex("14 00 00 00"), uid});
  const auto info = qi::ServiceInfo::decode(reply, {});
  EXPECT_EQ(info.name, "ALVideoDevice");
  EXPECT_EQ(info.service_id, 3u);
  EXPECT_EQ(info.process_id, 0x5587u);
  ASSERT_EQ(info.endpoints.size(), 2u);
  EXPECT_EQ(info.endpoints[1], "tcp://127.0.0.1:9559");
  ASSERT_TRUE(info.object_uid.has_value());
  EXPECT_EQ(Bytes(info.object_uid->begin(), info.object_uid->end()), uid);
  // And the 7-field value encodes back to the same bytes.
  EXPECT_EQ(qi::encode(info.to_value()), reply);
}

TEST(QiGolden, MetaMethodEntryOfMove) {
  const Bytes entry = cat({hex("87 00 00 00 87 00 00 00 01 00 00 00 76 04 00 00 00"), str("move"),
                           hex("05 00 00 00"), str("(fff)"), hex("00 00 00 00 03 00 00 00"),
                           hex("01 00 00 00 78 00 00 00 00 01 00 00 00 79 00 00 00 00"),
                           hex("05 00 00 00"), str("theta"), hex("00 00 00 00 00 00 00 00")});
  qi::MetaObject mo;
  mo.methods[135] = {135, "v", "move", "(fff)", "", {{"x", ""}, {"y", ""}, {"theta", ""}}, ""};
  const Bytes all = qi::encode(mo.to_value());
  // methods map: count 1, then the entry; then three empty containers/strings.
  EXPECT_EQ(all, cat({hex("01 00 00 00"), entry, hex("00 00 00 00 00 00 00 00 00 00 00 00")}));
  const auto back = qi::MetaObject::from_value(
      qi::decode(qi::parse_signature(qi::MetaObject::signature()), all, {}));
  EXPECT_EQ(back.find("move", "(fff)")->uid, 135u);
}

TEST(QiGolden, ServiceAddedEvent) {
  const Bytes wire =
      cat({hex("42 de ad 42 16 00 00 00 15 00 00 00 00 00 05 00 01 00 00 00 01 00 00 00 6a 00 00 00"
               "07 00 00 00 0d 00 00 00"),
           str("MyTestService")});
  qi::MessageSplitter splitter;
  // Fed one byte at a time: TCP segments do not follow message boundaries.
  std::vector<qi::Message> msgs;
  for (std::uint8_t b : wire) {
    for (auto& m : splitter.feed({&b, 1})) msgs.push_back(std::move(m));
  }
  ASSERT_EQ(msgs.size(), 1u);
  EXPECT_EQ(msgs[0].header.type, qi::MessageType::kEvent);
  EXPECT_EQ(msgs[0].header.action, 106u);
  const Value v = qi::decode(qi::parse_signature("(Is)"), msgs[0].bytes(), {});
  EXPECT_EQ(v.elements()[0].as_uint(), 7u);
  EXPECT_EQ(v.elements()[1].as_string(), "MyTestService");
}

TEST(QiGolden, DynamicValueExamples) {
  EXPECT_EQ(qi::encode(Value::string("abc")), hex("03 00 00 00 61 62 63"));
  EXPECT_EQ(qi::encode(Value::list(qi::Type::of(qi::TypeKind::kInt32),
                                   {Value::int32(1), Value::int32(2)})),
            hex("02 00 00 00 01 00 00 00 02 00 00 00"));
  EXPECT_EQ(
      qi::encode(Value::map(qi::Type::of(qi::TypeKind::kString), qi::Type::of(qi::TypeKind::kFloat),
                            {{Value::string("k"), Value::float32(1.5f)}})),
      hex("01 00 00 00 01 00 00 00 6b 00 00 c0 3f"));
  EXPECT_EQ(qi::encode(Value::tuple({Value::boolean(true), Value::int32(7)})),
            hex("01 07 00 00 00"));
  EXPECT_EQ(qi::encode(Value::dynamic(Value::int32(640))), hex("01 00 00 00 69 80 02 00 00"));
  EXPECT_EQ(qi::encode(Value::dynamic(Value::strings({"a"}))),
            hex("03 00 00 00 5b 73 5d 01 00 00 00 01 00 00 00 61"));
  const Value any = qi::decode(qi::Type::of(qi::TypeKind::kDynamic),
                               hex("03 00 00 00 5b 73 5d 01 00 00 00 01 00 00 00 61"), {});
  EXPECT_EQ(any.inner().signature(), "[s]");
  EXPECT_EQ(any.inner().elements()[0].as_string(), "a");
}

TEST(QiGolden, GetImageRemoteVgaReply) {
  qi::ImageRemote img;
  img.width_px = 640;
  img.height_px = 480;
  img.layers = 1;
  img.color_space = 0;
  img.t_sec = 0x6b01300e;
  img.t_usec = 0x0002a2d2;
  Bytes pixels(640 * 480);
  for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<std::uint8_t>(i);
  std::memset(pixels.data(), 0, 4);  // fake robot: bytes 0..3 = frame index 0
  img.pixels = qi::RawBytes::copy_of(pixels);
  img.camera_index = 0;
  // The captured angles (printed rounded as 0.4992 / 0.3866 rad), taken from their bytes.
  const Bytes angle_bytes = hex("72 92 ff 3e 2e ef c5 3e 72 92 ff be 2e ef c5 be");
  std::memcpy(img.angles_rad.data(), angle_bytes.data(), 16);
  Bytes payload;
  qi::Writer w(payload);
  qi::encode_image_remote(img, w);
  ASSERT_EQ(payload.size(), 307319u);
  qi::MessageHeader h;
  h.id = 14;
  h.type = qi::MessageType::kReply;
  h.service = 3;
  h.object = 1;
  h.action = 162;
  const Bytes wire = qi::serialize(h, payload);
  const Bytes head =
      hex("42 de ad 42 0e 00 00 00 77 b0 04 00 00 00 02 00 03 00 00 00 01 00 00 00 a2 00 00 00"
          "03 00 00 00 5b 6d 5d 0c 00 00 00"
          "01 00 00 00 69 80 02 00 00 01 00 00 00 69 e0 01 00 00 01 00 00 00 69 01 00 00 00"
          "01 00 00 00 69 00 00 00 00 01 00 00 00 69 0e 30 01 6b 01 00 00 00 69 d2 a2 02 00"
          "01 00 00 00 72 00 b0 04 00 00 00 00 00 04 05 06 07 08 09 0a 0b");
  EXPECT_TRUE(std::equal(head.begin(), head.end(), wire.begin()));
  const Bytes tail =
      hex("01 00 00 00 69 00 00 00 00 01 00 00 00 66 72 92 ff 3e"
          "01 00 00 00 66 2e ef c5 3e 01 00 00 00 66 72 92 ff be"
          "01 00 00 00 66 2e ef c5 be");
  EXPECT_TRUE(std::equal(tail.begin(), tail.end(), payload.begin() + 0x4b04a));
  // Pixels start 74 bytes into the payload (102 into the message).
  EXPECT_EQ(payload[74 + 4], 4);

  auto owner = std::make_shared<const Bytes>(payload);
  const qi::ImageRemote back = qi::decode_image_remote(*owner, {}, owner);
  EXPECT_EQ(back.width_px, 640);
  EXPECT_EQ(back.height_px, 480);
  EXPECT_EQ(back.t_ns(), 0x6b01300eLL * 1'000'000'000 + 0x2a2d2LL * 1000);
  EXPECT_EQ(back.pixels.size, 307200u);
  EXPECT_EQ(back.pixels.data, owner->data() + 74);  // a view: no copy
  EXPECT_NEAR(back.angles_rad[3], -0.3866f, 1e-4);
}
