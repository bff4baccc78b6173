#pragma once
// Value: a dynamically typed qi value (the `m` / "any" of qi messaging) carrying its own Type.
//
// Every value knows its exact signature (type()), so it can be encoded without outside help and
// wrapped in a dynamic. Integers are stored widened (int64 / uint64), floats as double; the Type
// remembers the wire width. Raw buffers (`r`) are views sharing ownership of the bytes they point
// into (usually the received message), so decoding a 300 KB image copies nothing.
//
// Accessors throw ProtocolError{kTypeMismatch} naming the expected and actual signatures.
// Values are immutable after construction and safe to share between threads.

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "naoqi_bridge/qi/signature.hpp"

namespace pepper::naoqi_bridge::qi {

/// Bytes of a raw buffer: a view plus shared ownership of the storage it points into.
struct RawBytes {
  std::shared_ptr<const std::vector<std::uint8_t>> owner;
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;

  std::span<const std::uint8_t> view() const { return {data, size}; }
  static RawBytes copy_of(std::span<const std::uint8_t> bytes);
};

class Value;

/// An object reference (`o`), kept opaque: its MetaObject value and its address.
struct ObjectRef {
  std::shared_ptr<const Value> meta_object;  ///< a MetaObject tuple (see meta.hpp)
  std::uint32_t service_id = 0;
  std::uint32_t object_id = 0;
};

class Value {
 public:
  using Entries = std::vector<std::pair<Value, Value>>;

  /// A void value (signature "v"): what a method returning nothing gives.
  Value();

  static Value boolean(bool b);
  /// Any integer kind; throws kTypeMismatch when `v` does not fit the kind's range.
  static Value integer(TypeKind kind, std::int64_t v);
  static Value unsigned_integer(TypeKind kind, std::uint64_t v);
  static Value int32(std::int32_t v) { return integer(TypeKind::kInt32, v); }
  static Value uint32(std::uint32_t v) { return unsigned_integer(TypeKind::kUInt32, v); }
  static Value int64(std::int64_t v) { return integer(TypeKind::kInt64, v); }
  static Value uint64(std::uint64_t v) { return unsigned_integer(TypeKind::kUInt64, v); }
  static Value float32(float v);
  static Value float64(double v);
  static Value string(std::string s);
  static Value raw(RawBytes bytes);
  static Value raw(std::span<const std::uint8_t> bytes) { return raw(RawBytes::copy_of(bytes)); }
  /// A list whose elements must all have type `element` (checked).
  static Value list(Type element, std::vector<Value> elements);
  static Value map(Type key, Type value, Entries entries);
  /// A tuple; its type is built from the fields' types. `annotation` makes it a named struct.
  static Value tuple(std::vector<Value> fields, std::string annotation = {});
  /// A dynamic (`m`) holding `inner`; Value::empty_dynamic() holds nothing (empty signature).
  static Value dynamic(Value inner);
  static Value empty_dynamic();
  static Value optional(Type inner, std::optional<Value> v);
  static Value object(ObjectRef ref);

  /// Convenience: list of strings / floats, and a dynamic string.
  static Value strings(const std::vector<std::string>& v);
  static Value floats(const std::vector<float>& v);

  const Type& type() const { return type_; }
  TypeKind kind() const { return type_.kind; }
  std::string signature() const { return type_.to_string(); }

  bool as_bool() const;
  /// Any integer kind (or bool); throws if a uint64 does not fit.
  std::int64_t as_int() const;
  std::uint64_t as_uint() const;
  /// Any numeric kind.
  double as_double() const;
  const std::string& as_string() const;
  const RawBytes& as_raw() const;
  /// Elements of a list / varargs, or fields of a tuple.
  const std::vector<Value>& elements() const;
  const Entries& entries() const;
  /// The value inside a dynamic (throws on an empty dynamic) or a present optional.
  const Value& inner() const;
  /// Dynamic that holds nothing, or optional that is absent.
  bool is_empty() const;
  const ObjectRef& as_object() const;

  /// Looks through any number of dynamic wrappers.
  const Value& unwrapped() const;

  /// Short human-readable rendering for logs and errors (raw buffers shown by size only).
  std::string to_debug_string(std::size_t max_elements = 8) const;

 private:
  using Data =
      std::variant<std::monostate, bool, std::int64_t, std::uint64_t, double, std::string, RawBytes,
                   std::vector<Value>, Entries, std::shared_ptr<const Value>, ObjectRef>;
  Value(Type type, Data data) : type_(std::move(type)), data_(std::move(data)) {}
  [[noreturn]] void mismatch(const char* wanted) const;

  Type type_;
  Data data_;

  friend class Decoder;
};

/// Converts `v` to `target` where qi would: numeric kinds to any numeric kind (range-checked for
/// integers), anything into `m` (wrapped), lists/maps/tuples/optionals element by element,
/// dynamics unwrapped when the target is concrete. Throws ProtocolError{kTypeMismatch}.
Value convert(const Value& v, const Type& target);

}  // namespace pepper::naoqi_bridge::qi
