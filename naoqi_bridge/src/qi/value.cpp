// Dynamic qi values: construction, typed access and conversion between compatible types.
#include "naoqi_bridge/qi/value.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "naoqi_bridge/qi/protocol_error.hpp"

namespace pepper::naoqi_bridge::qi {

RawBytes RawBytes::copy_of(std::span<const std::uint8_t> bytes) {
  auto owner = std::make_shared<const std::vector<std::uint8_t>>(bytes.begin(), bytes.end());
  RawBytes r;
  r.data = owner->data();
  r.size = owner->size();
  r.owner = std::move(owner);
  return r;
}

namespace {

[[noreturn]] void type_error(const std::string& what) {
  throw ProtocolError(ProtocolErrc::kTypeMismatch, what);
}

bool int_fits(TypeKind kind, std::int64_t v) {
  switch (kind) {
    case TypeKind::kInt8:
      return v >= INT8_MIN && v <= INT8_MAX;
    case TypeKind::kUInt8:
      return v >= 0 && v <= UINT8_MAX;
    case TypeKind::kInt16:
      return v >= INT16_MIN && v <= INT16_MAX;
    case TypeKind::kUInt16:
      return v >= 0 && v <= UINT16_MAX;
    case TypeKind::kInt32:
      return v >= INT32_MIN && v <= INT32_MAX;
    case TypeKind::kUInt32:
      return v >= 0 && v <= static_cast<std::int64_t>(UINT32_MAX);
    case TypeKind::kInt64:
      return true;
    case TypeKind::kUInt64:
      return v >= 0;
    default:
      return false;
  }
}

}  // namespace

Value::Value() : type_(Type::of(TypeKind::kVoid)), data_(std::monostate{}) {}

Value Value::boolean(bool b) { return Value(Type::of(TypeKind::kBool), b); }

Value Value::integer(TypeKind kind, std::int64_t v) {
  if (!is_integer(kind)) type_error("Value::integer: kind is not an integer type");
  if (!int_fits(kind, v)) {
    type_error("integer " + std::to_string(v) + " does not fit type '" +
               Type::of(kind).to_string() + "'");
  }
  if (kind == TypeKind::kUInt64) return Value(Type::of(kind), static_cast<std::uint64_t>(v));
  return Value(Type::of(kind), v);
}

Value Value::unsigned_integer(TypeKind kind, std::uint64_t v) {
  if (kind == TypeKind::kUInt64) return Value(Type::of(kind), v);
  if (v > static_cast<std::uint64_t>(INT64_MAX)) {
    type_error("integer " + std::to_string(v) + " does not fit type '" +
               Type::of(kind).to_string() + "'");
  }
  return integer(kind, static_cast<std::int64_t>(v));
}

Value Value::float32(float v) { return Value(Type::of(TypeKind::kFloat), static_cast<double>(v)); }
Value Value::float64(double v) { return Value(Type::of(TypeKind::kDouble), v); }
Value Value::string(std::string s) { return Value(Type::of(TypeKind::kString), std::move(s)); }
Value Value::raw(RawBytes bytes) { return Value(Type::of(TypeKind::kRaw), std::move(bytes)); }

Value Value::list(Type element, std::vector<Value> elements) {
  for (const auto& e : elements) {
    if (!e.type().same_layout(element)) {
      type_error("list of '" + element.to_string() + "' given an element of type '" +
                 e.signature() + "'");
    }
  }
  return Value(Type::list(std::move(element)), std::move(elements));
}

Value Value::map(Type key, Type value, Entries entries) {
  for (const auto& [k, v] : entries) {
    if (!k.type().same_layout(key) || !v.type().same_layout(value)) {
      type_error("map {" + key.to_string() + value.to_string() + "} given an entry of types '" +
                 k.signature() + "', '" + v.signature() + "'");
    }
  }
  return Value(Type::map(std::move(key), std::move(value)), std::move(entries));
}

Value Value::tuple(std::vector<Value> fields, std::string annotation) {
  std::vector<Type> types;
  types.reserve(fields.size());
  for (const auto& f : fields) types.push_back(f.type());
  return Value(Type::tuple(std::move(types), std::move(annotation)), std::move(fields));
}

Value Value::dynamic(Value inner) {
  return Value(Type::of(TypeKind::kDynamic), std::make_shared<const Value>(std::move(inner)));
}
Value Value::empty_dynamic() {
  return Value(Type::of(TypeKind::kDynamic), std::shared_ptr<const Value>());
}

Value Value::optional(Type inner, std::optional<Value> v) {
  if (v && !v->type().same_layout(inner)) {
    type_error("optional of '" + inner.to_string() + "' given '" + v->signature() + "'");
  }
  std::shared_ptr<const Value> p;
  if (v) p = std::make_shared<const Value>(std::move(*v));
  return Value(Type::optional(std::move(inner)), std::move(p));
}

Value Value::object(ObjectRef ref) { return Value(Type::of(TypeKind::kObject), std::move(ref)); }

Value Value::strings(const std::vector<std::string>& v) {
  std::vector<Value> e;
  e.reserve(v.size());
  for (const auto& s : v) e.push_back(string(s));
  return list(Type::of(TypeKind::kString), std::move(e));
}

Value Value::floats(const std::vector<float>& v) {
  std::vector<Value> e;
  e.reserve(v.size());
  for (float f : v) e.push_back(float32(f));
  return list(Type::of(TypeKind::kFloat), std::move(e));
}

void Value::mismatch(const char* wanted) const {
  type_error(std::string("expected ") + wanted + ", got value of type '" + signature() + "'");
}

bool Value::as_bool() const {
  const Value& v = unwrapped();
  if (v.kind() == TypeKind::kBool) return std::get<bool>(v.data_);
  if (is_integer(v.kind())) return v.as_int() != 0;
  v.mismatch("a bool");
}

std::int64_t Value::as_int() const {
  const Value& v = unwrapped();
  if (v.kind() == TypeKind::kBool) return std::get<bool>(v.data_) ? 1 : 0;
  if (v.kind() == TypeKind::kUInt64) {
    const auto u = std::get<std::uint64_t>(v.data_);
    if (u > static_cast<std::uint64_t>(INT64_MAX)) v.mismatch("an integer within int64");
    return static_cast<std::int64_t>(u);
  }
  if (is_integer(v.kind())) return std::get<std::int64_t>(v.data_);
  v.mismatch("an integer");
}

std::uint64_t Value::as_uint() const {
  const Value& v = unwrapped();
  if (v.kind() == TypeKind::kUInt64) return std::get<std::uint64_t>(v.data_);
  const std::int64_t i = v.as_int();
  if (i < 0) v.mismatch("a non-negative integer");
  return static_cast<std::uint64_t>(i);
}

double Value::as_double() const {
  const Value& v = unwrapped();
  if (v.kind() == TypeKind::kFloat || v.kind() == TypeKind::kDouble) {
    return std::get<double>(v.data_);
  }
  if (v.kind() == TypeKind::kUInt64) return static_cast<double>(std::get<std::uint64_t>(v.data_));
  if (is_integer(v.kind()) || v.kind() == TypeKind::kBool) return static_cast<double>(v.as_int());
  v.mismatch("a number");
}

const std::string& Value::as_string() const {
  const Value& v = unwrapped();
  if (v.kind() != TypeKind::kString) v.mismatch("a string");
  return std::get<std::string>(v.data_);
}

const RawBytes& Value::as_raw() const {
  const Value& v = unwrapped();
  if (v.kind() != TypeKind::kRaw) v.mismatch("a raw buffer");
  return std::get<RawBytes>(v.data_);
}

const std::vector<Value>& Value::elements() const {
  const Value& v = unwrapped();
  if (v.kind() != TypeKind::kList && v.kind() != TypeKind::kVarArgs &&
      v.kind() != TypeKind::kTuple) {
    v.mismatch("a list or tuple");
  }
  return std::get<std::vector<Value>>(v.data_);
}

const Value::Entries& Value::entries() const {
  const Value& v = unwrapped();
  if (v.kind() != TypeKind::kMap) v.mismatch("a map");
  return std::get<Entries>(v.data_);
}

const Value& Value::inner() const {
  if (kind() != TypeKind::kDynamic && kind() != TypeKind::kOptional) mismatch("a dynamic");
  const auto& p = std::get<std::shared_ptr<const Value>>(data_);
  if (!p) type_error("empty " + signature() + " has no value");
  return *p;
}

bool Value::is_empty() const {
  if (kind() != TypeKind::kDynamic && kind() != TypeKind::kOptional) return false;
  return !std::get<std::shared_ptr<const Value>>(data_);
}

const ObjectRef& Value::as_object() const {
  const Value& v = unwrapped();
  if (v.kind() != TypeKind::kObject) v.mismatch("an object");
  return std::get<ObjectRef>(v.data_);
}

const Value& Value::unwrapped() const {
  const Value* v = this;
  while (v->kind() == TypeKind::kDynamic && !v->is_empty()) v = &v->inner();
  return *v;
}

std::string Value::to_debug_string(std::size_t max_elements) const {
  std::ostringstream os;
  switch (kind()) {
    case TypeKind::kVoid:
      return "void";
    case TypeKind::kBool:
      return as_bool() ? "true" : "false";
    case TypeKind::kUInt64:
      return std::to_string(as_uint());
    case TypeKind::kFloat:
    case TypeKind::kDouble:
      os << as_double();
      return os.str();
    case TypeKind::kString:
      return "\"" + as_string() + "\"";
    case TypeKind::kRaw:
      return "<raw " + std::to_string(as_raw().size) + " bytes>";
    case TypeKind::kDynamic:
      return is_empty() ? "m()" : "m(" + inner().to_debug_string(max_elements) + ")";
    case TypeKind::kOptional:
      return is_empty() ? "none" : inner().to_debug_string(max_elements);
    case TypeKind::kObject:
      return "<object>";
    case TypeKind::kUnknown:
      return "<unknown>";
    case TypeKind::kMap: {
      os << '{';
      std::size_t n = 0;
      for (const auto& [k, v] : entries()) {
        if (n++ == max_elements) {
          os << ", ...";
          break;
        }
        os << (n > 1 ? ", " : "") << k.to_debug_string(max_elements) << ": "
           << v.to_debug_string(max_elements);
      }
      os << '}';
      return os.str();
    }
    case TypeKind::kList:
    case TypeKind::kVarArgs:
    case TypeKind::kTuple: {
      const bool tup = kind() == TypeKind::kTuple;
      os << (tup ? '(' : '[');
      std::size_t n = 0;
      for (const auto& e : elements()) {
        if (n++ == max_elements) {
          os << ", ...";
          break;
        }
        os << (n > 1 ? ", " : "") << e.to_debug_string(max_elements);
      }
      os << (tup ? ')' : ']');
      return os.str();
    }
    default:
      return std::to_string(as_int());
  }
}

Value convert(const Value& v, const Type& target) {
  if (target.kind == TypeKind::kDynamic) {
    return v.kind() == TypeKind::kDynamic ? v : Value::dynamic(v);
  }
  const Value& src = (v.kind() == TypeKind::kDynamic && !v.is_empty()) ? v.unwrapped() : v;
  auto fail = [&]() -> Value {
    type_error("cannot convert a value of type '" + src.signature() + "' to '" +
               target.to_string() + "'");
  };
  if (is_numeric(target.kind)) {
    if (!is_numeric(src.kind())) return fail();
    if (target.kind == TypeKind::kBool) return Value::boolean(src.as_bool());
    if (target.kind == TypeKind::kFloat) return Value::float32(static_cast<float>(src.as_double()));
    if (target.kind == TypeKind::kDouble) return Value::float64(src.as_double());
    if (src.kind() == TypeKind::kFloat || src.kind() == TypeKind::kDouble) {
      const double d = src.as_double();
      if (!std::isfinite(d) || d != std::floor(d) || std::fabs(d) > 9.0e18) return fail();
      return Value::integer(target.kind, static_cast<std::int64_t>(d));
    }
    if (src.kind() == TypeKind::kUInt64) return Value::unsigned_integer(target.kind, src.as_uint());
    return Value::integer(target.kind, src.as_int());
  }
  switch (target.kind) {
    case TypeKind::kString:
    case TypeKind::kRaw:
    case TypeKind::kObject:
    case TypeKind::kVoid:
      if (src.kind() != target.kind) return fail();
      return src;
    case TypeKind::kList:
    case TypeKind::kVarArgs: {
      if (src.kind() != TypeKind::kList && src.kind() != TypeKind::kVarArgs &&
          src.kind() != TypeKind::kTuple) {
        return fail();
      }
      std::vector<Value> out;
      out.reserve(src.elements().size());
      for (const auto& e : src.elements()) out.push_back(convert(e, target.children[0]));
      Value l = Value::list(target.children[0], std::move(out));
      if (target.kind == TypeKind::kVarArgs) {
        // Same wire layout as a list; keep the list representation.
      }
      return l;
    }
    case TypeKind::kMap: {
      if (src.kind() != TypeKind::kMap) return fail();
      Value::Entries out;
      out.reserve(src.entries().size());
      for (const auto& [k, e] : src.entries()) {
        out.emplace_back(convert(k, target.children[0]), convert(e, target.children[1]));
      }
      return Value::map(target.children[0], target.children[1], std::move(out));
    }
    case TypeKind::kTuple: {
      if (src.kind() != TypeKind::kTuple && src.kind() != TypeKind::kList) return fail();
      const auto& fields = src.elements();
      if (fields.size() != target.children.size()) {
        type_error("cannot convert a value of type '" + src.signature() + "' to '" +
                   target.to_string() + "': " + std::to_string(fields.size()) + " fields for " +
                   std::to_string(target.children.size()));
      }
      std::vector<Value> out;
      out.reserve(fields.size());
      for (std::size_t i = 0; i < fields.size(); ++i) {
        out.push_back(convert(fields[i], target.children[i]));
      }
      return Value::tuple(std::move(out), target.annotation);
    }
    case TypeKind::kOptional: {
      if (src.kind() == TypeKind::kOptional) {
        if (src.is_empty()) return Value::optional(target.children[0], std::nullopt);
        return Value::optional(target.children[0], convert(src.inner(), target.children[0]));
      }
      return Value::optional(target.children[0], convert(src, target.children[0]));
    }
    default:
      return fail();
  }
}

}  // namespace pepper::naoqi_bridge::qi
