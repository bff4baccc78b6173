// Binary encoding and strict decoding of qi values (PROTOCOL.md section 6).
#include "naoqi_bridge/qi/codec.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>

namespace pepper::naoqi_bridge::qi {

static_assert(std::endian::native == std::endian::little,
              "the qi codec assumes a little-endian host (x86, ARM)");

std::vector<std::string> CodecLimits::validate() const {
  std::vector<std::string> errors;
  if (max_payload_bytes == 0 || max_payload_bytes > 0xFFFFFFFFu) {
    errors.push_back("max_payload_bytes must be in 1..4294967295, got " +
                     std::to_string(max_payload_bytes));
  }
  if (max_depth < 2 || max_depth > 256) {
    errors.push_back("max_depth must be in 2..256, got " + std::to_string(max_depth));
  }
  if (max_values < 16) {
    errors.push_back("max_values must be >= 16, got " + std::to_string(max_values));
  }
  return errors;
}

// ---------------------------------------------------------------------------------------------
// Writer

void Writer::u16(std::uint16_t v) {
  std::uint8_t b[2];
  std::memcpy(b, &v, 2);
  out_.insert(out_.end(), b, b + 2);
}
void Writer::u32(std::uint32_t v) {
  std::uint8_t b[4];
  std::memcpy(b, &v, 4);
  out_.insert(out_.end(), b, b + 4);
}
void Writer::u64(std::uint64_t v) {
  std::uint8_t b[8];
  std::memcpy(b, &v, 8);
  out_.insert(out_.end(), b, b + 8);
}
void Writer::f32(float v) { u32(std::bit_cast<std::uint32_t>(v)); }
void Writer::f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }

void Writer::string(std::string_view s) {
  bytes_with_length({reinterpret_cast<const std::uint8_t*>(s.data()), s.size()});
}

void Writer::bytes_with_length(std::span<const std::uint8_t> b) {
  if (b.size() > 0xFFFFFFFFu) {
    throw ProtocolError(ProtocolErrc::kPayloadTooLarge,
                        "buffer of " + std::to_string(b.size()) + " bytes exceeds the 4 GiB limit");
  }
  u32(static_cast<std::uint32_t>(b.size()));
  bytes(b);
}

// ---------------------------------------------------------------------------------------------
// Reader

void Reader::need(std::size_t n, const char* what) const {
  if (n > remaining()) {
    throw ProtocolError(ProtocolErrc::kTruncated, std::string(what) + " needs " +
                                                      std::to_string(n) + " bytes at offset " +
                                                      std::to_string(pos_) + ", only " +
                                                      std::to_string(remaining()) + " remain");
  }
}

std::uint8_t Reader::u8(const char* what) {
  need(1, what);
  return data_[pos_++];
}
std::uint16_t Reader::u16(const char* what) {
  need(2, what);
  std::uint16_t v;
  std::memcpy(&v, data_.data() + pos_, 2);
  pos_ += 2;
  return v;
}
std::uint32_t Reader::u32(const char* what) {
  need(4, what);
  std::uint32_t v;
  std::memcpy(&v, data_.data() + pos_, 4);
  pos_ += 4;
  return v;
}
std::uint64_t Reader::u64(const char* what) {
  need(8, what);
  std::uint64_t v;
  std::memcpy(&v, data_.data() + pos_, 8);
  pos_ += 8;
  return v;
}
float Reader::f32(const char* what) { return std::bit_cast<float>(u32(what)); }
double Reader::f64(const char* what) { return std::bit_cast<double>(u64(what)); }

std::span<const std::uint8_t> Reader::bytes_with_length(const char* what) {
  const std::size_t at = pos_;
  const std::uint32_t n = u32(what);
  if (n > remaining()) {
    throw ProtocolError(ProtocolErrc::kCountTooLarge,
                        std::string(what) + " length " + std::to_string(n) + " at offset " +
                            std::to_string(at) + " exceeds remaining " +
                            std::to_string(remaining()) + " bytes");
  }
  auto s = data_.subspan(pos_, n);
  pos_ += n;
  return s;
}

std::string Reader::string(const char* what) {
  auto b = bytes_with_length(what);
  return {reinterpret_cast<const char*>(b.data()), b.size()};
}

RawBytes Reader::raw(const char* what) {
  auto b = bytes_with_length(what);
  if (!owner_) return RawBytes::copy_of(b);
  RawBytes r;
  r.owner = owner_;
  r.data = b.data();
  r.size = b.size();
  return r;
}

std::uint32_t Reader::count(const char* what, std::size_t min_element_bytes) {
  const std::size_t at = pos_;
  const std::uint32_t n = u32(what);
  // Elements that take no bytes (e.g. empty tuples) are bounded by max_values instead.
  const bool too_many = min_element_bytes == 0
                            ? n > limits_.max_values
                            : static_cast<std::uint64_t>(n) * min_element_bytes > remaining();
  if (too_many) {
    throw ProtocolError(ProtocolErrc::kCountTooLarge,
                        std::string(what) + " count " + std::to_string(n) + " at offset " +
                            std::to_string(at) + " exceeds remaining " +
                            std::to_string(remaining()) + " bytes");
  }
  if (n > limits_.max_values - std::min(values_, limits_.max_values)) {
    throw ProtocolError(ProtocolErrc::kTooManyValues,
                        std::string(what) + " count " + std::to_string(n) + " at offset " +
                            std::to_string(at) + " exceeds the limit of " +
                            std::to_string(limits_.max_values) + " values per payload");
  }
  return n;
}

void Reader::account_value() {
  if (++values_ > limits_.max_values) {
    throw ProtocolError(ProtocolErrc::kTooManyValues,
                        "more than " + std::to_string(limits_.max_values) +
                            " values in one payload (at offset " + std::to_string(pos_) + ")");
  }
}

void Reader::expect_end(const char* what) const {
  if (remaining() != 0) {
    throw ProtocolError(ProtocolErrc::kTrailingBytes, std::to_string(remaining()) +
                                                          " unexpected bytes after " + what +
                                                          " at offset " + std::to_string(pos_));
  }
}

// ---------------------------------------------------------------------------------------------
// Encoding

void encode_value(const Value& v, Writer& w) {
  switch (v.kind()) {
    case TypeKind::kVoid:
      return;
    case TypeKind::kBool:
      w.u8(v.as_bool() ? 1 : 0);
      return;
    case TypeKind::kInt8:
    case TypeKind::kUInt8:
      w.u8(static_cast<std::uint8_t>(v.as_int()));
      return;
    case TypeKind::kInt16:
    case TypeKind::kUInt16:
      w.u16(static_cast<std::uint16_t>(v.as_int()));
      return;
    case TypeKind::kInt32:
    case TypeKind::kUInt32:
      w.u32(static_cast<std::uint32_t>(v.as_int()));
      return;
    case TypeKind::kInt64:
      w.u64(static_cast<std::uint64_t>(v.as_int()));
      return;
    case TypeKind::kUInt64:
      w.u64(v.as_uint());
      return;
    case TypeKind::kFloat:
      w.f32(static_cast<float>(v.as_double()));
      return;
    case TypeKind::kDouble:
      w.f64(v.as_double());
      return;
    case TypeKind::kString:
      w.string(v.as_string());
      return;
    case TypeKind::kRaw:
      w.bytes_with_length(v.as_raw().view());
      return;
    case TypeKind::kDynamic:
      if (v.is_empty()) {
        w.string("");
        return;
      }
      w.string(v.inner().signature());
      encode_value(v.inner(), w);
      return;
    case TypeKind::kOptional:
      w.u8(v.is_empty() ? 0 : 1);
      if (!v.is_empty()) encode_value(v.inner(), w);
      return;
    case TypeKind::kList:
    case TypeKind::kVarArgs:
      w.u32(static_cast<std::uint32_t>(v.elements().size()));
      for (const auto& e : v.elements()) encode_value(e, w);
      return;
    case TypeKind::kTuple:
      for (const auto& e : v.elements()) encode_value(e, w);
      return;
    case TypeKind::kMap:
      w.u32(static_cast<std::uint32_t>(v.entries().size()));
      for (const auto& [k, e] : v.entries()) {
        encode_value(k, w);
        encode_value(e, w);
      }
      return;
    case TypeKind::kObject: {
      const auto& o = v.as_object();
      if (o.meta_object) {
        encode_value(*o.meta_object, w);
      } else {
        // Empty MetaObject: three empty maps and an empty description.
        w.u32(0);
        w.u32(0);
        w.u32(0);
        w.u32(0);
      }
      w.u32(o.service_id);
      w.u32(o.object_id);
      return;
    }
    case TypeKind::kUnknown:
      throw ProtocolError(ProtocolErrc::kUnsupported, "type 'X' cannot be serialized");
  }
}

std::vector<std::uint8_t> encode(const Value& v) {
  std::vector<std::uint8_t> out;
  Writer w(out);
  encode_value(v, w);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Decoding

class Decoder {
 public:
  static Value make(Type t, Value::Data d) { return Value(std::move(t), std::move(d)); }
};

namespace {

void check_depth(std::size_t depth, const Reader& r) {
  if (depth >= r.limits().max_depth) {
    throw ProtocolError(ProtocolErrc::kTooDeep,
                        "value nests deeper than " + std::to_string(r.limits().max_depth) +
                            " levels at offset " + std::to_string(r.offset()));
  }
}

}  // namespace

Value decode_value(const Type& t, Reader& r, std::size_t depth) {
  r.account_value();
  switch (t.kind) {
    case TypeKind::kVoid:
      return Value();
    case TypeKind::kBool: {
      const std::size_t at = r.offset();
      const std::uint8_t b = r.u8("bool");
      if (b > 1) {
        throw ProtocolError(ProtocolErrc::kBadValue, "bool byte " + std::to_string(b) +
                                                         " at offset " + std::to_string(at) +
                                                         " is neither 0 nor 1");
      }
      return Value::boolean(b == 1);
    }
    case TypeKind::kInt8:
      return Value::integer(t.kind, static_cast<std::int8_t>(r.u8("int8")));
    case TypeKind::kUInt8:
      return Value::integer(t.kind, r.u8("uint8"));
    case TypeKind::kInt16:
      return Value::integer(t.kind, static_cast<std::int16_t>(r.u16("int16")));
    case TypeKind::kUInt16:
      return Value::integer(t.kind, r.u16("uint16"));
    case TypeKind::kInt32:
      return Value::integer(t.kind, static_cast<std::int32_t>(r.u32("int32")));
    case TypeKind::kUInt32:
      return Value::integer(t.kind, r.u32("uint32"));
    case TypeKind::kInt64:
      return Value::integer(t.kind, static_cast<std::int64_t>(r.u64("int64")));
    case TypeKind::kUInt64:
      return Value::unsigned_integer(t.kind, r.u64("uint64"));
    case TypeKind::kFloat:
      return Value::float32(r.f32("float"));
    case TypeKind::kDouble:
      return Value::float64(r.f64("double"));
    case TypeKind::kString:
      return Value::string(r.string("string"));
    case TypeKind::kRaw:
      return Value::raw(r.raw("raw buffer"));
    case TypeKind::kDynamic: {
      check_depth(depth, r);
      const std::size_t at = r.offset();
      const std::string sig = r.string("dynamic signature");
      if (sig.empty()) return Value::empty_dynamic();
      Type inner_type;
      try {
        inner_type = parse_signature(sig, r.limits().max_depth - depth);
      } catch (const ProtocolError& e) {
        throw ProtocolError(e.code(), std::string(e.what()) + " (dynamic value at offset " +
                                          std::to_string(at) + ")");
      }
      if (inner_type.kind == TypeKind::kUnknown) {
        throw ProtocolError(ProtocolErrc::kUnsupported,
                            "dynamic value of type 'X' at offset " + std::to_string(at));
      }
      return Value::dynamic(decode_value(inner_type, r, depth + 1));
    }
    case TypeKind::kOptional: {
      check_depth(depth, r);
      const std::size_t at = r.offset();
      const std::uint8_t flag = r.u8("optional flag");
      if (flag > 1) {
        throw ProtocolError(ProtocolErrc::kBadValue, "optional flag " + std::to_string(flag) +
                                                         " at offset " + std::to_string(at) +
                                                         " is neither 0 nor 1");
      }
      if (flag == 0) return Value::optional(t.children[0], std::nullopt);
      return Value::optional(t.children[0], decode_value(t.children[0], r, depth + 1));
    }
    case TypeKind::kList:
    case TypeKind::kVarArgs: {
      check_depth(depth, r);
      const Type& et = t.children[0];
      const std::uint32_t n = r.count("list", min_encoded_size(et));
      std::vector<Value> elements;
      elements.reserve(n);
      for (std::uint32_t i = 0; i < n; ++i) elements.push_back(decode_value(et, r, depth + 1));
      return Decoder::make(t, std::move(elements));
    }
    case TypeKind::kMap: {
      check_depth(depth, r);
      const Type& kt = t.children[0];
      const Type& vt = t.children[1];
      const std::uint32_t n = r.count("map", min_encoded_size(kt) + min_encoded_size(vt));
      Value::Entries entries;
      entries.reserve(n);
      for (std::uint32_t i = 0; i < n; ++i) {
        Value k = decode_value(kt, r, depth + 1);
        Value v = decode_value(vt, r, depth + 1);
        entries.emplace_back(std::move(k), std::move(v));
      }
      return Decoder::make(t, std::move(entries));
    }
    case TypeKind::kTuple: {
      check_depth(depth, r);
      std::vector<Value> fields;
      fields.reserve(t.children.size());
      for (const auto& ft : t.children) fields.push_back(decode_value(ft, r, depth + 1));
      return Decoder::make(t, std::move(fields));
    }
    case TypeKind::kObject: {
      check_depth(depth, r);
      static const Type meta_type = parse_signature(
          "({I(Issss[(ss)<MetaMethodParameter,name,description>]s)<MetaMethod,uid,"
          "returnSignature,name,parametersSignature,description,parameters,returnDescription>}"
          "{I(Iss)<MetaSignal,uid,name,signature>}{I(Iss)<MetaProperty,uid,name,signature>}s)"
          "<MetaObject,methods,signals,properties,description>");
      ObjectRef ref;
      ref.meta_object = std::make_shared<const Value>(decode_value(meta_type, r, depth + 1));
      ref.service_id = r.u32("object service id");
      ref.object_id = r.u32("object id");
      return Value::object(std::move(ref));
    }
    case TypeKind::kUnknown:
      throw ProtocolError(ProtocolErrc::kUnsupported, "type 'X' cannot be deserialized (offset " +
                                                          std::to_string(r.offset()) + ")");
  }
  throw ProtocolError(ProtocolErrc::kUnsupported, "unhandled type kind");
}

Value decode(const Type& t, std::span<const std::uint8_t> payload, const CodecLimits& limits,
             std::shared_ptr<const std::vector<std::uint8_t>> owner) {
  Reader r(payload, limits, std::move(owner));
  Value v = decode_value(t, r);
  r.expect_end(("value of type '" + t.to_string() + "'").c_str());
  return v;
}

std::vector<std::uint8_t> encode_capabilities(const CapabilityMap& caps) {
  std::vector<std::uint8_t> out;
  Writer w(out);
  w.u32(static_cast<std::uint32_t>(caps.size()));
  for (const auto& [k, v] : caps) {
    w.string(k);
    encode_value(v.kind() == TypeKind::kDynamic ? v : Value::dynamic(v), w);
  }
  return out;
}

CapabilityMap decode_capabilities(std::span<const std::uint8_t> payload,
                                  const CodecLimits& limits) {
  static const Type type = parse_signature("{sm}");
  const Value v = decode(type, payload, limits);
  CapabilityMap caps;
  for (const auto& [k, e] : v.entries()) {
    caps[k.as_string()] = e.is_empty() ? Value() : e.inner();
  }
  return caps;
}

std::string decode_error_text(std::span<const std::uint8_t> payload, const CodecLimits& limits) {
  const Value v = decode(Type::of(TypeKind::kDynamic), payload, limits);
  const Value& u = v.unwrapped();
  if (u.kind() == TypeKind::kString) return u.as_string();
  return v.to_debug_string();
}

std::vector<std::uint8_t> encode_error_text(std::string_view text) {
  return encode(Value::dynamic(Value::string(std::string(text))));
}

}  // namespace pepper::naoqi_bridge::qi
