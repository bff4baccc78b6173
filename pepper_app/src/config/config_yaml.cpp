#include "config/config_yaml.hpp"

#include <yaml-cpp/yaml.h>

namespace pepper::app {
namespace {

void emit(YAML::Emitter& out, const nlohmann::json& j) {
  if (j.is_object()) {
    out << YAML::BeginMap;
    for (auto it = j.begin(); it != j.end(); ++it) {
      out << YAML::Key << it.key() << YAML::Value;
      emit(out, *it);
    }
    out << YAML::EndMap;
  } else if (j.is_array()) {
    out << YAML::Flow << YAML::BeginSeq;
    for (const auto& item : j) emit(out, item);
    out << YAML::EndSeq;
  } else if (j.is_boolean()) {
    out << j.get<bool>();
  } else if (j.is_number_unsigned()) {
    out << j.get<uint64_t>();
  } else if (j.is_number_integer()) {
    out << j.get<int64_t>();
  } else if (j.is_number_float()) {
    out << j.get<double>();
  } else if (j.is_string()) {
    out << YAML::DoubleQuoted << j.get<std::string>();
  } else {
    out << YAML::Null;
  }
}

}  // namespace

std::string json_to_yaml(const nlohmann::json& tree) {
  YAML::Emitter out;
  out.SetDoublePrecision(10);
  emit(out, tree);
  return std::string(out.c_str()) + "\n";
}

}  // namespace pepper::app
