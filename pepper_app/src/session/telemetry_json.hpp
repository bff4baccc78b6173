#pragma once
// JSON form of the navigator's per-frame output, shared by replay-log, the teach UI and the
// replay recorder. Field names are the telemetry's own (units in names); NaN becomes null.

#include <nlohmann/json.hpp>

#include "core/navigator/navigator.hpp"

namespace pepper::app {

nlohmann::json command_to_json(const core::navigator::Command& command);
nlohmann::json telemetry_to_json(const core::navigator::Telemetry& telemetry);

}  // namespace pepper::app
