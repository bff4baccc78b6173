#pragma once
// Operator intents: what the person at the teach UI asks for (drive, record, replay, stop).
//
// The page sends them as JSON text messages over the WebSocket (schema in docs/teach_ui.md); the
// UiServer parses, clamps and queues them; the app (pepper_app) decides what to do with them. An
// intent is a request, not a command: teach_ui never talks to the robot or the core.
//
// Units and signs (docs/conventions.md): v_m_s forward base speed in m/s, omega_rad_s base yaw
// rate in rad/s, > 0 turns left.
//
// parse_intent() never throws on bad input: a malformed or unknown message is an expected outcome
// and comes back as an error string. Plain data, no threads.
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <string_view>

namespace pepper::teach_ui {

enum class IntentKind {
  kDrive,           ///< tele-operation: drive at (v_m_s, omega_rad_s) until released or refreshed
  kDriveReleased,   ///< dead-man: stop driving (key released, focus lost, client gone, timeout)
  kEmergencyStop,   ///< the big STOP button or the space bar: stop everything now
  kStartRecording,  ///< teach: start taking key images
  kStopRecording,   ///< teach: pause recording (driving still allowed)
  kFinishTeach,     ///< teach: close the tour, write the map, show its summary
  kStartReplay,     ///< replay: localise and follow the taught tour
};

/// Wire name of a kind ("drive", "drive_released", "estop", "start_recording", "stop_recording",
/// "finish_teach", "start_replay").
std::string_view to_string(IntentKind kind);
std::optional<IntentKind> intent_kind_from_string(std::string_view name);

/// Who emitted the intent: a WebSocket client of the page, or the server itself (dead-man on
/// disconnect or drive timeout).
enum class IntentSource { kClient, kServer };

struct Intent {
  IntentKind kind = IntentKind::kDriveReleased;
  double v_m_s = 0.0;        ///< kDrive only; already clamped to the server's limits
  double omega_rad_s = 0.0;  ///< kDrive only; > 0 turns left; already clamped
  IntentSource source = IntentSource::kClient;
  std::uint64_t client_id = 0;  ///< which WebSocket connection (1, 2, ...); 0 for none
  /// Free text for released/stop intents: "key_released", "blur", "button", "space",
  /// "client_disconnected", "drive_timeout"... Empty when not given.
  std::string reason;
};

/// Speed limits applied to drive intents (symmetric: |v| <= max_v_m_s, |omega| <= max_omega_rad_s).
struct DriveLimits {
  double max_v_m_s = 0.35;       ///< Pepper's base tops out near 0.35 m/s (ALMotion default)
  double max_omega_rad_s = 1.0;  ///< comfortable tele-operation turn rate
};

/// Result of parsing one client text message as an intent.
struct IntentParse {
  std::optional<Intent> intent;  ///< set when the message was a valid intent
  std::string error;             ///< set (non-empty) when the message was rejected; says why
};

/// Parses one text message from the page. Non-finite or missing speeds in a drive are errors;
/// speeds beyond `limits` are clamped (not rejected). `client_id` is copied into the intent.
/// Never throws.
IntentParse parse_intent(std::string_view text, const DriveLimits& limits, std::uint64_t client_id);

/// JSON form of an intent, as the fake session and the app log it:
/// {"kind":"drive","v_m_s":0.2,"omega_rad_s":0,"source":"client","client_id":1,"reason":""}.
nlohmann::json to_json(const Intent& intent);

}  // namespace pepper::teach_ui
