// Codec round trips for every qi type, signature parsing/printing and value conversion.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "naoqi_bridge/qi/codec.hpp"
#include "naoqi_bridge/qi/meta.hpp"

namespace qi = pepper::naoqi_bridge::qi;
using qi::Type;
using qi::TypeKind;
using qi::Value;

namespace {

Value round_trip(const Value& v) {
  const auto bytes = qi::encode(v);
  return qi::decode(v.type(), bytes, qi::CodecLimits{});
}

// Byte-exact comparison through a second encoding: equal values encode identically.
void expect_round_trip(const Value& v) {
  const auto first = qi::encode(v);
  const Value back = round_trip(v);
  EXPECT_EQ(back.signature(), v.signature());
  EXPECT_EQ(qi::encode(back), first) << v.signature();
}

}  // namespace

TEST(QiSignature, ParsesAndPrintsEveryLetter) {
  for (const char* s :
       {"b", "c", "C", "w", "W", "i",   "I",    "l",    "L",  "f",  "d",           "s",
        "r", "m", "o", "v", "X", "[i]", "{sm}", "(bi)", "+s", "#s", "[[{s(ib)}]]", "()"}) {
    EXPECT_EQ(qi::parse_signature(s).to_string(), s);
  }
}

TEST(QiSignature, KeepsStructAnnotations) {
  const std::string sig = qi::MetaObject::signature();
  const Type t = qi::parse_signature(sig);
  EXPECT_EQ(t.to_string(), sig);
  EXPECT_EQ(t.annotation, "MetaObject,methods,signals,properties,description");
  EXPECT_EQ(t.children[0].children[1].children[5].children[0].annotation,
            "MetaMethodParameter,name,description");
}

TEST(QiSignature, RejectsMalformedSignatures) {
  for (const char* s : {"", "[i", "{s}", "(ii", "q", "i)", "[]", "(i)<Name", "{sii}"}) {
    try {
      (void)qi::parse_signature(s);
      ADD_FAILURE() << "accepted '" << s << "'";
    } catch (const qi::ProtocolError& e) {
      EXPECT_EQ(e.code(), qi::ProtocolErrc::kBadSignature) << s << ": " << e.what();
    }
  }
}

TEST(QiSignature, DepthIsBounded) {
  const std::string deep = std::string(40, '[') + "i" + std::string(40, ']');
  try {
    (void)qi::parse_signature(deep, 32);
    FAIL();
  } catch (const qi::ProtocolError& e) {
    EXPECT_EQ(e.code(), qi::ProtocolErrc::kTooDeep);
  }
  EXPECT_NO_THROW((void)qi::parse_signature(deep, 64));
}

TEST(QiCodec, RoundTripsScalars) {
  expect_round_trip(Value::boolean(true));
  expect_round_trip(Value::boolean(false));
  expect_round_trip(Value::integer(TypeKind::kInt8, -128));
  expect_round_trip(Value::integer(TypeKind::kUInt8, 255));
  expect_round_trip(Value::integer(TypeKind::kInt16, -32768));
  expect_round_trip(Value::integer(TypeKind::kUInt16, 65535));
  expect_round_trip(Value::int32(std::numeric_limits<std::int32_t>::min()));
  expect_round_trip(Value::uint32(0xFFFFFFFFu));
  expect_round_trip(Value::int64(std::numeric_limits<std::int64_t>::min()));
  expect_round_trip(Value::uint64(std::numeric_limits<std::uint64_t>::max()));
  expect_round_trip(Value::float32(-1.5f));
  expect_round_trip(Value::float64(3.141592653589793));
  expect_round_trip(Value::string(""));
  expect_round_trip(Value::string(std::string("a\0b", 3)));
  const std::uint8_t raw[] = {0, 1, 2, 255};
  expect_round_trip(Value::raw(raw));
  EXPECT_EQ(round_trip(Value::uint64(std::numeric_limits<std::uint64_t>::max())).as_uint(),
            std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(round_trip(Value::int32(-7)).as_int(), -7);
  EXPECT_FLOAT_EQ(static_cast<float>(round_trip(Value::float32(0.1f)).as_double()), 0.1f);
}

TEST(QiCodec, RoundTripsContainers) {
  expect_round_trip(Value::list(Type::of(TypeKind::kInt32), {Value::int32(1), Value::int32(2)}));
  expect_round_trip(Value::list(Type::of(TypeKind::kString), {}));
  expect_round_trip(Value::map(Type::of(TypeKind::kString), Type::of(TypeKind::kFloat),
                               {{Value::string("k"), Value::float32(1.5f)}}));
  expect_round_trip(Value::tuple({Value::boolean(true), Value::int32(7)}));
  expect_round_trip(Value::tuple({Value::string("x"), Value::float64(2.0)}, "Pair,name,value"));
  expect_round_trip(Value::optional(Type::of(TypeKind::kString), Value::string("yes")));
  expect_round_trip(Value::optional(Type::of(TypeKind::kString), std::nullopt));
  expect_round_trip(Value::dynamic(Value::int32(640)));
  expect_round_trip(Value::dynamic(Value::strings({"a", "b"})));
  expect_round_trip(Value::empty_dynamic());
  expect_round_trip(Value::dynamic(Value()));  // "v" inside m
  expect_round_trip(Value::dynamic(Value::dynamic(Value::float32(1.0f))));
  // Nested: list of maps of tuples.
  const Value inner =
      Value::map(Type::of(TypeKind::kString),
                 Type::tuple({Type::of(TypeKind::kInt32), Type::of(TypeKind::kBool)}),
                 {{Value::string("a"), Value::tuple({Value::int32(1), Value::boolean(false)})}});
  expect_round_trip(Value::list(inner.type(), {inner, inner}));
}

TEST(QiCodec, RoundTripsObjectAndMetaObject) {
  qi::MetaObject mo;
  qi::MetaMethod m;
  m.uid = 135;
  m.name = "move";
  m.return_signature = "v";
  m.parameters_signature = "(fff)";
  m.parameters = {{"x", ""}, {"y", ""}, {"theta", ""}};
  mo.methods[135] = m;
  mo.signals[106] = {106, "serviceAdded", "(Is)"};
  mo.properties[200] = {200, "prop", "i"};
  mo.description = "d";
  const Value v = mo.to_value();
  EXPECT_EQ(v.signature(), qi::MetaObject::signature());
  expect_round_trip(v);
  const qi::MetaObject back = qi::MetaObject::from_value(round_trip(v));
  ASSERT_EQ(back.methods.size(), 1u);
  EXPECT_EQ(back.methods.at(135).parameters.size(), 3u);
  EXPECT_EQ(back.signals.at(106).signature, "(Is)");
  EXPECT_EQ(back.properties.at(200).name, "prop");

  qi::ObjectRef ref;
  ref.meta_object = std::make_shared<const Value>(v);
  ref.service_id = 7;
  ref.object_id = 3;
  const Value obj = Value::object(ref);
  const Value obj_back = round_trip(obj);
  EXPECT_EQ(obj_back.as_object().service_id, 7u);
  EXPECT_EQ(obj_back.as_object().object_id, 3u);
}

TEST(QiCodec, OverloadsResolveByNameAndSignature) {
  qi::MetaObject mo;
  mo.methods[135] = {135, "v", "move", "(fff)", "", {}, ""};
  mo.methods[136] = {136, "v", "move", "(fffm)", "", {}, ""};
  ASSERT_NE(mo.find("move", "(fff)"), nullptr);
  EXPECT_EQ(mo.find("move", "(fff)")->uid, 135u);
  EXPECT_EQ(mo.find("move", "(fffm)")->uid, 136u);
  EXPECT_EQ(mo.find("move", "(ff)"), nullptr);
  EXPECT_EQ(mo.overloads("move").size(), 2u);
}

TEST(QiCodec, ServiceInfoBothForms) {
  qi::ServiceInfo info;
  info.name = "ALMotion";
  info.service_id = 2;
  info.machine_id = "m";
  info.process_id = 9;
  info.endpoints = {"tcp://127.0.0.1:9559"};
  info.session_id = "s";
  // 6-field (NAOqi 2.5)
  auto b6 = qi::encode(info.to_value());
  auto d6 = qi::ServiceInfo::decode(b6, {});
  EXPECT_EQ(d6.service_id, 2u);
  EXPECT_FALSE(d6.object_uid.has_value());
  // 7-field (libqi 4)
  info.object_uid = std::string(20, '\x01');
  auto b7 = qi::encode(info.to_value());
  EXPECT_EQ(b7.size(), b6.size() + 24);
  auto d7 = qi::ServiceInfo::decode(b7, {});
  ASSERT_TRUE(d7.object_uid.has_value());
  EXPECT_EQ(d7.object_uid->size(), 20u);
  EXPECT_EQ(d7.endpoints, info.endpoints);
}

TEST(QiConvert, NumbersListsAndDynamics) {
  const Value d = qi::convert(Value::float64(0.25), Type::of(TypeKind::kFloat));
  EXPECT_EQ(d.kind(), TypeKind::kFloat);
  EXPECT_EQ(qi::convert(Value::int32(3), Type::of(TypeKind::kDouble)).as_double(), 3.0);
  EXPECT_EQ(qi::convert(Value::int64(5), Type::of(TypeKind::kUInt8)).as_int(), 5);
  EXPECT_THROW(qi::convert(Value::int64(300), Type::of(TypeKind::kUInt8)), qi::ProtocolError);
  EXPECT_THROW(qi::convert(Value::float64(0.5), Type::of(TypeKind::kInt32)), qi::ProtocolError);
  EXPECT_THROW(qi::convert(Value::string("x"), Type::of(TypeKind::kInt32)), qi::ProtocolError);
  // (ddd) -> (fff), as libqi accepts a dynamic (ddd) for a (fff) method.
  const Value t = qi::convert(
      Value::dynamic(Value::tuple({Value::float64(0.1), Value::float64(0), Value::float64(0)})),
      qi::parse_signature("(fff)"));
  EXPECT_EQ(t.signature(), "(fff)");
  // Anything into m.
  EXPECT_EQ(qi::convert(Value::strings({"a"}), Type::of(TypeKind::kDynamic)).inner().signature(),
            "[s]");
  EXPECT_THROW(Value::list(Type::of(TypeKind::kInt32), {Value::string("x")}), qi::ProtocolError);
}

TEST(QiConvert, AccessorsNameTheMismatch) {
  try {
    (void)Value::int32(1).as_string();
    FAIL();
  } catch (const qi::ProtocolError& e) {
    EXPECT_EQ(e.code(), qi::ProtocolErrc::kTypeMismatch);
    EXPECT_NE(std::string(e.what()).find("'i'"), std::string::npos) << e.what();
  }
}

TEST(QiCodec, CapabilityMapRoundTrip) {
  qi::CapabilityMap caps;
  caps["MessageFlags"] = Value::boolean(true);
  caps["auth_user"] = Value::string("nao");
  caps["__qi_auth_state"] = Value::uint32(3);
  const auto back = qi::decode_capabilities(qi::encode_capabilities(caps), {});
  ASSERT_EQ(back.size(), 3u);
  EXPECT_TRUE(back.at("MessageFlags").as_bool());
  EXPECT_EQ(back.at("auth_user").as_string(), "nao");
  EXPECT_EQ(back.at("__qi_auth_state").as_int(), 3);
}

TEST(QiCodec, LimitsValidateNamesFields) {
  qi::CodecLimits l;
  EXPECT_TRUE(l.validate().empty());
  l.max_depth = 1;
  l.max_values = 0;
  const auto errors = l.validate();
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].find("max_depth"), std::string::npos);
  EXPECT_NE(errors[1].find("max_values"), std::string::npos);
}
