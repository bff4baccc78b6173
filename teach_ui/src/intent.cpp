// Parsing and printing of operator intents (see teach_ui/intent.hpp, docs/teach_ui.md).
#include "teach_ui/intent.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <utility>

namespace pepper::teach_ui {
namespace {

constexpr std::array<std::pair<IntentKind, std::string_view>, 7> kNames{{
    {IntentKind::kDrive, "drive"},
    {IntentKind::kDriveReleased, "drive_released"},
    {IntentKind::kEmergencyStop, "estop"},
    {IntentKind::kStartRecording, "start_recording"},
    {IntentKind::kStopRecording, "stop_recording"},
    {IntentKind::kFinishTeach, "finish_teach"},
    {IntentKind::kStartReplay, "start_replay"},
}};

constexpr std::size_t kMaxReasonChars = 64;

std::optional<double> finite_number(const nlohmann::json& msg, const char* key) {
  const auto it = msg.find(key);
  if (it == msg.end() || !it->is_number()) return std::nullopt;
  const double value = it->get<double>();
  if (!std::isfinite(value)) return std::nullopt;
  return value;
}

}  // namespace

std::string_view to_string(IntentKind kind) {
  for (const auto& [k, name] : kNames) {
    if (k == kind) return name;
  }
  return "unknown";
}

std::optional<IntentKind> intent_kind_from_string(std::string_view name) {
  for (const auto& [k, n] : kNames) {
    if (n == name) return k;
  }
  return std::nullopt;
}

IntentParse parse_intent(std::string_view text, const DriveLimits& limits,
                         std::uint64_t client_id) {
  IntentParse out;
  const nlohmann::json msg = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (msg.is_discarded()) {
    out.error = "not valid JSON";
    return out;
  }
  if (!msg.is_object()) {
    out.error = "not a JSON object";
    return out;
  }
  const auto type_it = msg.find("type");
  if (type_it == msg.end() || !type_it->is_string()) {
    out.error = "missing string field 'type'";
    return out;
  }
  const auto kind = intent_kind_from_string(type_it->get_ref<const std::string&>());
  if (!kind) {
    out.error = "unknown intent type '" + type_it->get<std::string>() + "'";
    return out;
  }
  Intent intent;
  intent.kind = *kind;
  intent.source = IntentSource::kClient;
  intent.client_id = client_id;
  if (*kind == IntentKind::kDrive) {
    const auto v = finite_number(msg, "v_m_s");
    const auto omega = finite_number(msg, "omega_rad_s");
    if (!v || !omega) {
      out.error = "drive needs finite numbers 'v_m_s' and 'omega_rad_s'";
      return out;
    }
    intent.v_m_s = std::clamp(*v, -limits.max_v_m_s, limits.max_v_m_s);
    intent.omega_rad_s = std::clamp(*omega, -limits.max_omega_rad_s, limits.max_omega_rad_s);
  }
  if (const auto reason = msg.find("reason"); reason != msg.end() && reason->is_string()) {
    std::string text_reason = reason->get<std::string>();
    if (text_reason.size() > kMaxReasonChars) {
      std::size_t cut = kMaxReasonChars;  // do not split a UTF-8 sequence
      while (cut > 0 && (static_cast<unsigned char>(text_reason[cut]) & 0xC0) == 0x80) --cut;
      text_reason.resize(cut);
    }
    intent.reason = std::move(text_reason);
  }
  out.intent = std::move(intent);
  return out;
}

nlohmann::json to_json(const Intent& intent) {
  nlohmann::json j;
  j["kind"] = std::string(to_string(intent.kind));
  if (intent.kind == IntentKind::kDrive) {
    j["v_m_s"] = intent.v_m_s;
    j["omega_rad_s"] = intent.omega_rad_s;
  }
  j["source"] = intent.source == IntentSource::kServer ? "server" : "client";
  j["client_id"] = intent.client_id;
  j["reason"] = intent.reason;
  return j;
}

}  // namespace pepper::teach_ui
