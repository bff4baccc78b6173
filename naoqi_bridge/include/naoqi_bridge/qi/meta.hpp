#pragma once
// Structured protocol values: MetaObject (an object's method table, PROTOCOL.md 5.1) and
// ServiceInfo (the directory's answer, 4.1), with conversions to and from qi Values.
//
// Method resolution is by name AND parameter signature: overloads exist (ALMotion.move is uid 135
// for (fff) and 136 for (fffm)). ServiceInfo decoding accepts both the 6-field (NAOqi 2.5) and
// the 7-field (libqi 4, + objectUid) forms.
//
// Plain C++ (no Asio, no OpenCV).

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "naoqi_bridge/qi/codec.hpp"

namespace pepper::naoqi_bridge::qi {

struct MetaMethodParameter {
  std::string name;
  std::string description;
};

struct MetaMethod {
  std::uint32_t uid = 0;
  std::string return_signature;
  std::string name;
  std::string parameters_signature;  ///< always a tuple, "()" when there are none
  std::string description;
  std::vector<MetaMethodParameter> parameters;
  std::string return_description;
};

struct MetaSignal {
  std::uint32_t uid = 0;
  std::string name;
  std::string signature;
};

struct MetaProperty {
  std::uint32_t uid = 0;
  std::string name;
  std::string signature;
};

struct MetaObject {
  std::map<std::uint32_t, MetaMethod> methods;
  std::map<std::uint32_t, MetaSignal> signals;
  std::map<std::uint32_t, MetaProperty> properties;
  std::string description;

  /// The method with this name and parameter signature (annotations ignored), if any.
  const MetaMethod* find(std::string_view name, std::string_view parameters_signature) const;
  /// Every overload of `name`, by uid.
  std::vector<const MetaMethod*> overloads(std::string_view name) const;

  /// Signature of the MetaObject struct on the wire.
  static const std::string& signature();
  Value to_value() const;
  /// Throws ProtocolError{kTypeMismatch} when `v` does not have the MetaObject layout.
  static MetaObject from_value(const Value& v);
};

struct ServiceInfo {
  std::string name;
  std::uint32_t service_id = 0;
  std::string machine_id;
  std::uint32_t process_id = 0;
  std::vector<std::string> endpoints;
  std::string session_id;
  std::optional<std::string> object_uid;  ///< 20 binary bytes (libqi 4 only)

  static const std::string& signature_v6();  ///< (sIsI[s]s)<ServiceInfo,...>
  static const std::string& signature_v7();  ///< (sIsI[s]ss)<ServiceInfo,...,objectUid>
  Value to_value() const;                    ///< 7-field form when object_uid is set, else 6
  /// Decodes the six common fields, then objectUid if bytes remain; anything after is ignored.
  static ServiceInfo decode(std::span<const std::uint8_t> payload, const CodecLimits& limits);
};

}  // namespace pepper::naoqi_bridge::qi
