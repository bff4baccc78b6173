#pragma once
// YAML text of a configuration tree (for `pepper_app config dump` and for echoing at start-up).
#include <string>

#include <nlohmann/json.hpp>

namespace pepper::app {

std::string json_to_yaml(const nlohmann::json& tree);

}  // namespace pepper::app
