#pragma once
// qi type signatures: the textual type language of qi messaging and its parsed tree form.
//
// Grammar (PROTOCOL.md 6.1): scalar letters b c C w W i I l L f d s r m o v X; containers
// `[X]` list, `{KV}` map, `(X...)` tuple with an optional `<Name,field,...>` annotation (a
// struct), `+X` optional, `#X` varargs (encoded as a list). parse_signature() builds a Type tree;
// Type::to_string() writes it back byte for byte (annotations kept).
//
// Limits: parsing stops with ProtocolError{kTooDeep} beyond `max_depth` nested containers and
// with kBadSignature on anything else unexpected (naming the character and its position).

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace pepper::naoqi_bridge::qi {

enum class TypeKind : std::uint8_t {
  kVoid,      // v
  kBool,      // b
  kInt8,      // c
  kUInt8,     // C
  kInt16,     // w
  kUInt16,    // W
  kInt32,     // i
  kUInt32,    // I
  kInt64,     // l
  kUInt64,    // L
  kFloat,     // f
  kDouble,    // d
  kString,    // s
  kRaw,       // r
  kDynamic,   // m
  kObject,    // o
  kUnknown,   // X
  kList,      // [X]
  kVarArgs,   // #X
  kMap,       // {KV}
  kTuple,     // (X...)<annotation>
  kOptional,  // +X
};

/// True for the eight integer kinds (c C w W i I l L).
bool is_integer(TypeKind kind);
/// True for b, the integers, f and d.
bool is_numeric(TypeKind kind);

struct Type {
  TypeKind kind = TypeKind::kVoid;
  std::vector<Type>
      children;  ///< list/varargs/optional: 1 element type; map: key, value; tuple: fields
  std::string annotation;  ///< tuple only: "Name,field1,field2" (without the angle brackets)

  static Type of(TypeKind kind);
  static Type list(Type element);
  static Type map(Type key, Type value);
  static Type tuple(std::vector<Type> fields, std::string annotation = {});
  static Type optional(Type inner);

  /// Signature text, e.g. "(sIsI[s]s)<ServiceInfo,name,...>".
  std::string to_string() const;

  /// Same wire layout (annotations ignored).
  bool same_layout(const Type& other) const;

  bool operator==(const Type& other) const = default;
};

/// Parses one complete type; throws ProtocolError (kBadSignature / kTooDeep).
Type parse_signature(std::string_view text, std::size_t max_depth = 32);

/// Smallest number of bytes any value of this type occupies on the wire (used to bound counts).
std::size_t min_encoded_size(const Type& type);

}  // namespace pepper::naoqi_bridge::qi
