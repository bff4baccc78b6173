// parse_intent / to_json and the binary framing (teach_ui/intent.hpp, teach_ui/wire.hpp).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "teach_ui/intent.hpp"
#include "teach_ui/wire.hpp"

namespace pepper::teach_ui {
namespace {

const DriveLimits kLimits{0.3, 0.8};

TEST(ParseIntent, DriveIsParsedAndClampedToLimits) {
  const auto ok = parse_intent(R"({"type":"drive","v_m_s":0.1,"omega_rad_s":-0.2})", kLimits, 7);
  ASSERT_TRUE(ok.intent) << ok.error;
  EXPECT_EQ(ok.intent->kind, IntentKind::kDrive);
  EXPECT_DOUBLE_EQ(ok.intent->v_m_s, 0.1);
  EXPECT_DOUBLE_EQ(ok.intent->omega_rad_s, -0.2);
  EXPECT_EQ(ok.intent->client_id, 7u);
  EXPECT_EQ(ok.intent->source, IntentSource::kClient);

  const auto fast = parse_intent(R"({"type":"drive","v_m_s":5,"omega_rad_s":-9})", kLimits, 1);
  ASSERT_TRUE(fast.intent);
  EXPECT_DOUBLE_EQ(fast.intent->v_m_s, 0.3);
  EXPECT_DOUBLE_EQ(fast.intent->omega_rad_s, -0.8);
}

TEST(ParseIntent, EveryKindRoundTripsByName) {
  for (const auto kind :
       {IntentKind::kDrive, IntentKind::kDriveReleased, IntentKind::kEmergencyStop,
        IntentKind::kStartRecording, IntentKind::kStopRecording, IntentKind::kFinishTeach,
        IntentKind::kStartReplay}) {
    EXPECT_EQ(intent_kind_from_string(to_string(kind)), kind);
  }
  const auto estop = parse_intent(R"({"type":"estop","reason":"space"})", kLimits, 2);
  ASSERT_TRUE(estop.intent);
  EXPECT_EQ(estop.intent->kind, IntentKind::kEmergencyStop);
  EXPECT_EQ(estop.intent->reason, "space");
}

TEST(ParseIntent, MalformedMessagesAreErrorsNotExceptions) {
  for (const char* text :
       {"", "{", "[]", "42", R"({"type":3})", R"({"kind":"drive"})", R"({"type":"fly"})",
        R"({"type":"drive","v_m_s":0.1})", R"({"type":"drive","v_m_s":"0.1","omega_rad_s":0})",
        R"({"type":"drive","v_m_s":1e999,"omega_rad_s":0})", "\xff\xfe"}) {
    SCOPED_TRACE(text);
    IntentParse p;
    EXPECT_NO_THROW(p = parse_intent(text, kLimits, 1));
    EXPECT_FALSE(p.intent);
    EXPECT_FALSE(p.error.empty());
  }
}

TEST(ParseIntent, LongReasonIsCutOnACharacterBoundary) {
  std::string reason(63, 'a');
  reason += "\xc3\xa9\xc3\xa9";  // "éé": the cut at 64 bytes would split the first one
  const nlohmann::json msg = {{"type", "drive_released"}, {"reason", reason}};
  const auto p = parse_intent(msg.dump(), kLimits, 1);
  ASSERT_TRUE(p.intent);
  EXPECT_EQ(p.intent->reason, std::string(63, 'a'));
  EXPECT_NO_THROW((void)to_json(*p.intent).dump());
}

TEST(IntentJson, DriveCarriesSpeedsOthersDoNot) {
  Intent drive{IntentKind::kDrive, 0.2, 0.5, IntentSource::kClient, 3, ""};
  const nlohmann::json j = to_json(drive);
  EXPECT_EQ(j.at("kind"), "drive");
  EXPECT_DOUBLE_EQ(j.at("v_m_s").get<double>(), 0.2);
  EXPECT_EQ(j.at("client_id"), 3);
  Intent stop{IntentKind::kDriveReleased, 0, 0, IntentSource::kServer, 3, "client_disconnected"};
  const nlohmann::json s = to_json(stop);
  EXPECT_FALSE(s.contains("v_m_s"));
  EXPECT_EQ(s.at("source"), "server");
  EXPECT_EQ(s.at("reason"), "client_disconnected");
}

TEST(WireFormat, BinaryMessageRoundTrip) {
  const std::string payload("\xff\xd8\x00\x01jpeg", 8);
  const std::string m = encode_binary_message(kBinaryFrame, R"({"seq":1})", payload);
  const auto v = decode_binary_message(m);
  ASSERT_TRUE(v);
  EXPECT_EQ(v->kind, kBinaryFrame);
  EXPECT_EQ(v->header_json, R"({"seq":1})");
  EXPECT_EQ(v->payload, payload);
  EXPECT_FALSE(decode_binary_message(m.substr(0, 4)));
  EXPECT_FALSE(decode_binary_message(m.substr(0, 8)));  // header cut short
}

}  // namespace
}  // namespace pepper::teach_ui
