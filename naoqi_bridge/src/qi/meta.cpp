// MetaObject and ServiceInfo <-> qi Values (PROTOCOL.md 4.1 and 5.1).
#include "naoqi_bridge/qi/meta.hpp"

namespace pepper::naoqi_bridge::qi {

namespace {

const Type& meta_object_type() {
  static const Type t = parse_signature(MetaObject::signature());
  return t;
}

const std::string& field_string(const std::vector<Value>& f, std::size_t i, const char* what) {
  if (i >= f.size()) {
    throw ProtocolError(ProtocolErrc::kTypeMismatch, std::string(what) + ": missing field");
  }
  return f[i].as_string();
}

}  // namespace

const std::string& MetaObject::signature() {
  static const std::string s =
      "({I(Issss[(ss)<MetaMethodParameter,name,description>]s)<MetaMethod,uid,returnSignature,"
      "name,parametersSignature,description,parameters,returnDescription>}{I(Iss)<MetaSignal,uid,"
      "name,signature>}{I(Iss)<MetaProperty,uid,name,signature>}s)<MetaObject,methods,signals,"
      "properties,description>";
  return s;
}

const MetaMethod* MetaObject::find(std::string_view name,
                                   std::string_view parameters_signature) const {
  Type wanted;
  try {
    wanted = parse_signature(parameters_signature);
  } catch (const ProtocolError&) {
    return nullptr;
  }
  for (const auto& [uid, m] : methods) {
    if (m.name != name) continue;
    if (m.parameters_signature == parameters_signature) return &m;
    try {
      if (parse_signature(m.parameters_signature).same_layout(wanted)) return &m;
    } catch (const ProtocolError&) {
    }
  }
  return nullptr;
}

std::vector<const MetaMethod*> MetaObject::overloads(std::string_view name) const {
  std::vector<const MetaMethod*> out;
  for (const auto& [uid, m] : methods) {
    if (m.name == name) out.push_back(&m);
  }
  return out;
}

Value MetaObject::to_value() const {
  const Type& t = meta_object_type();
  const Type& method_type = t.children[0].children[1];
  const Type& param_type = method_type.children[5].children[0];
  const Type& signal_type = t.children[1].children[1];
  const Type& prop_type = t.children[2].children[1];
  Value::Entries ms;
  for (const auto& [uid, m] : methods) {
    std::vector<Value> params;
    for (const auto& p : m.parameters) {
      params.push_back(Value::tuple({Value::string(p.name), Value::string(p.description)},
                                    param_type.annotation));
    }
    ms.emplace_back(
        Value::uint32(uid),
        Value::tuple(
            {Value::uint32(m.uid), Value::string(m.return_signature), Value::string(m.name),
             Value::string(m.parameters_signature), Value::string(m.description),
             Value::list(param_type, std::move(params)), Value::string(m.return_description)},
            method_type.annotation));
  }
  Value::Entries ss;
  for (const auto& [uid, s] : signals) {
    ss.emplace_back(Value::uint32(uid), Value::tuple({Value::uint32(s.uid), Value::string(s.name),
                                                      Value::string(s.signature)},
                                                     signal_type.annotation));
  }
  Value::Entries ps;
  for (const auto& [uid, p] : properties) {
    ps.emplace_back(Value::uint32(uid), Value::tuple({Value::uint32(p.uid), Value::string(p.name),
                                                      Value::string(p.signature)},
                                                     prop_type.annotation));
  }
  const Type u32 = Type::of(TypeKind::kUInt32);
  return Value::tuple(
      {Value::map(u32, method_type, std::move(ms)), Value::map(u32, signal_type, std::move(ss)),
       Value::map(u32, prop_type, std::move(ps)), Value::string(description)},
      t.annotation);
}

MetaObject MetaObject::from_value(const Value& v) {
  const auto& f = v.elements();
  if (f.size() < 4) {
    throw ProtocolError(ProtocolErrc::kTypeMismatch,
                        "MetaObject: expected 4 fields, got " + std::to_string(f.size()));
  }
  MetaObject mo;
  for (const auto& [k, e] : f[0].entries()) {
    const auto& mf = e.elements();
    MetaMethod m;
    m.uid = static_cast<std::uint32_t>(mf.at(0).as_uint());
    m.return_signature = field_string(mf, 1, "MetaMethod.returnSignature");
    m.name = field_string(mf, 2, "MetaMethod.name");
    m.parameters_signature = field_string(mf, 3, "MetaMethod.parametersSignature");
    m.description = field_string(mf, 4, "MetaMethod.description");
    if (mf.size() > 5) {
      for (const auto& p : mf[5].elements()) {
        const auto& pf = p.elements();
        m.parameters.push_back(
            {field_string(pf, 0, "parameter name"), field_string(pf, 1, "parameter description")});
      }
    }
    if (mf.size() > 6) m.return_description = mf[6].as_string();
    mo.methods[static_cast<std::uint32_t>(k.as_uint())] = std::move(m);
  }
  for (const auto& [k, e] : f[1].entries()) {
    const auto& sf = e.elements();
    MetaSignal s{static_cast<std::uint32_t>(sf.at(0).as_uint()), field_string(sf, 1, "signal"),
                 field_string(sf, 2, "signal signature")};
    mo.signals[static_cast<std::uint32_t>(k.as_uint())] = std::move(s);
  }
  for (const auto& [k, e] : f[2].entries()) {
    const auto& pf = e.elements();
    MetaProperty p{static_cast<std::uint32_t>(pf.at(0).as_uint()), field_string(pf, 1, "property"),
                   field_string(pf, 2, "property signature")};
    mo.properties[static_cast<std::uint32_t>(k.as_uint())] = std::move(p);
  }
  mo.description = f[3].as_string();
  return mo;
}

const std::string& ServiceInfo::signature_v6() {
  static const std::string s =
      "(sIsI[s]s)<ServiceInfo,name,serviceId,machineId,processId,endpoints,sessionId>";
  return s;
}

const std::string& ServiceInfo::signature_v7() {
  static const std::string s =
      "(sIsI[s]ss)<ServiceInfo,name,serviceId,machineId,processId,endpoints,sessionId,objectUid>";
  return s;
}

Value ServiceInfo::to_value() const {
  std::vector<Value> f{Value::string(name),       Value::uint32(service_id),
                       Value::string(machine_id), Value::uint32(process_id),
                       Value::strings(endpoints), Value::string(session_id)};
  if (object_uid) {
    f.push_back(Value::string(*object_uid));
    return Value::tuple(std::move(f), parse_signature(signature_v7()).annotation);
  }
  return Value::tuple(std::move(f), parse_signature(signature_v6()).annotation);
}

ServiceInfo ServiceInfo::decode(std::span<const std::uint8_t> payload, const CodecLimits& limits) {
  static const Type t6 = parse_signature(signature_v6());
  Reader r(payload, limits);
  const Value v = decode_value(t6, r);
  const auto& f = v.elements();
  ServiceInfo info;
  info.name = f[0].as_string();
  info.service_id = static_cast<std::uint32_t>(f[1].as_uint());
  info.machine_id = f[2].as_string();
  info.process_id = static_cast<std::uint32_t>(f[3].as_uint());
  for (const auto& e : f[4].elements()) info.endpoints.push_back(e.as_string());
  info.session_id = f[5].as_string();
  if (r.remaining() >= 4) info.object_uid = r.string("ServiceInfo.objectUid");
  return info;
}

}  // namespace pepper::naoqi_bridge::qi
