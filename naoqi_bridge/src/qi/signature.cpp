// qi signature parser and printer (PROTOCOL.md 6.1).
#include "naoqi_bridge/qi/signature.hpp"

#include <string>

#include "naoqi_bridge/qi/protocol_error.hpp"

namespace pepper::naoqi_bridge::qi {

const char* to_string(ProtocolErrc code) {
  switch (code) {
    case ProtocolErrc::kBadMagic:
      return "bad magic";
    case ProtocolErrc::kUnknownType:
      return "unknown message type";
    case ProtocolErrc::kPayloadTooLarge:
      return "payload too large";
    case ProtocolErrc::kTruncated:
      return "truncated";
    case ProtocolErrc::kCountTooLarge:
      return "count too large";
    case ProtocolErrc::kTooDeep:
      return "nesting too deep";
    case ProtocolErrc::kTooManyValues:
      return "too many values";
    case ProtocolErrc::kBadSignature:
      return "bad signature";
    case ProtocolErrc::kBadValue:
      return "bad value";
    case ProtocolErrc::kTrailingBytes:
      return "trailing bytes";
    case ProtocolErrc::kTypeMismatch:
      return "type mismatch";
    case ProtocolErrc::kUnsupported:
      return "unsupported type";
  }
  return "unknown";
}

bool is_integer(TypeKind kind) {
  switch (kind) {
    case TypeKind::kInt8:
    case TypeKind::kUInt8:
    case TypeKind::kInt16:
    case TypeKind::kUInt16:
    case TypeKind::kInt32:
    case TypeKind::kUInt32:
    case TypeKind::kInt64:
    case TypeKind::kUInt64:
      return true;
    default:
      return false;
  }
}

bool is_numeric(TypeKind kind) {
  return is_integer(kind) || kind == TypeKind::kBool || kind == TypeKind::kFloat ||
         kind == TypeKind::kDouble;
}

Type Type::of(TypeKind kind) {
  Type t;
  t.kind = kind;
  return t;
}
Type Type::list(Type element) {
  Type t = of(TypeKind::kList);
  t.children.push_back(std::move(element));
  return t;
}
Type Type::map(Type key, Type value) {
  Type t = of(TypeKind::kMap);
  t.children.push_back(std::move(key));
  t.children.push_back(std::move(value));
  return t;
}
Type Type::tuple(std::vector<Type> fields, std::string annotation) {
  Type t = of(TypeKind::kTuple);
  t.children = std::move(fields);
  t.annotation = std::move(annotation);
  return t;
}
Type Type::optional(Type inner) {
  Type t = of(TypeKind::kOptional);
  t.children.push_back(std::move(inner));
  return t;
}

namespace {

char letter(TypeKind kind) {
  switch (kind) {
    case TypeKind::kVoid:
      return 'v';
    case TypeKind::kBool:
      return 'b';
    case TypeKind::kInt8:
      return 'c';
    case TypeKind::kUInt8:
      return 'C';
    case TypeKind::kInt16:
      return 'w';
    case TypeKind::kUInt16:
      return 'W';
    case TypeKind::kInt32:
      return 'i';
    case TypeKind::kUInt32:
      return 'I';
    case TypeKind::kInt64:
      return 'l';
    case TypeKind::kUInt64:
      return 'L';
    case TypeKind::kFloat:
      return 'f';
    case TypeKind::kDouble:
      return 'd';
    case TypeKind::kString:
      return 's';
    case TypeKind::kRaw:
      return 'r';
    case TypeKind::kDynamic:
      return 'm';
    case TypeKind::kObject:
      return 'o';
    case TypeKind::kUnknown:
      return 'X';
    default:
      return '?';
  }
}

void print(const Type& t, std::string& out) {
  switch (t.kind) {
    case TypeKind::kList:
      out += '[';
      print(t.children.at(0), out);
      out += ']';
      return;
    case TypeKind::kVarArgs:
      out += '#';
      print(t.children.at(0), out);
      return;
    case TypeKind::kOptional:
      out += '+';
      print(t.children.at(0), out);
      return;
    case TypeKind::kMap:
      out += '{';
      print(t.children.at(0), out);
      print(t.children.at(1), out);
      out += '}';
      return;
    case TypeKind::kTuple:
      out += '(';
      for (const auto& c : t.children) print(c, out);
      out += ')';
      if (!t.annotation.empty()) {
        out += '<';
        out += t.annotation;
        out += '>';
      }
      return;
    default:
      out += letter(t.kind);
  }
}

class Parser {
 public:
  Parser(std::string_view text, std::size_t max_depth) : text_(text), max_depth_(max_depth) {}

  Type parse_all() {
    if (text_.empty()) fail("empty signature");
    Type t = parse(0);
    if (pos_ != text_.size()) fail("unexpected '" + std::string(1, text_[pos_]) + "'");
    return t;
  }

 private:
  [[noreturn]] void fail(const std::string& why) const {
    throw ProtocolError(ProtocolErrc::kBadSignature, "signature \"" + printable() + "\": " + why +
                                                         " at position " + std::to_string(pos_));
  }
  std::string printable() const {
    std::string s;
    for (char c : text_.substr(0, 120)) s += (c >= 32 && c < 127) ? c : '?';
    if (text_.size() > 120) s += "...";
    return s;
  }
  void enter(std::size_t depth) const {
    if (depth >= max_depth_) {
      throw ProtocolError(ProtocolErrc::kTooDeep, "signature \"" + printable() +
                                                      "\" nests deeper than " +
                                                      std::to_string(max_depth_) + " levels");
    }
  }

  Type parse(std::size_t depth) {
    if (pos_ >= text_.size()) fail("unexpected end");
    const char c = text_[pos_++];
    switch (c) {
      case 'v':
        return Type::of(TypeKind::kVoid);
      case 'b':
        return Type::of(TypeKind::kBool);
      case 'c':
        return Type::of(TypeKind::kInt8);
      case 'C':
        return Type::of(TypeKind::kUInt8);
      case 'w':
        return Type::of(TypeKind::kInt16);
      case 'W':
        return Type::of(TypeKind::kUInt16);
      case 'i':
        return Type::of(TypeKind::kInt32);
      case 'I':
        return Type::of(TypeKind::kUInt32);
      case 'l':
        return Type::of(TypeKind::kInt64);
      case 'L':
        return Type::of(TypeKind::kUInt64);
      case 'f':
        return Type::of(TypeKind::kFloat);
      case 'd':
        return Type::of(TypeKind::kDouble);
      case 's':
        return Type::of(TypeKind::kString);
      case 'r':
        return Type::of(TypeKind::kRaw);
      case 'm':
        return Type::of(TypeKind::kDynamic);
      case 'o':
        return Type::of(TypeKind::kObject);
      case 'X':
        return Type::of(TypeKind::kUnknown);
      case '[': {
        enter(depth);
        Type t = Type::list(parse(depth + 1));
        expect(']');
        return t;
      }
      case '#': {
        enter(depth);
        Type t = Type::of(TypeKind::kVarArgs);
        t.children.push_back(parse(depth + 1));
        return t;
      }
      case '+': {
        enter(depth);
        return Type::optional(parse(depth + 1));
      }
      case '{': {
        enter(depth);
        Type k = parse(depth + 1);
        Type v = parse(depth + 1);
        expect('}');
        return Type::map(std::move(k), std::move(v));
      }
      case '(': {
        enter(depth);
        std::vector<Type> fields;
        while (pos_ < text_.size() && text_[pos_] != ')') fields.push_back(parse(depth + 1));
        expect(')');
        std::string annotation;
        if (pos_ < text_.size() && text_[pos_] == '<') {
          const std::size_t start = ++pos_;
          int level = 1;
          while (pos_ < text_.size() && level > 0) {
            if (text_[pos_] == '<') ++level;
            if (text_[pos_] == '>') --level;
            ++pos_;
          }
          if (level != 0) fail("unterminated annotation");
          annotation = std::string(text_.substr(start, pos_ - 1 - start));
        }
        return Type::tuple(std::move(fields), std::move(annotation));
      }
      default:
        --pos_;
        fail("unknown type letter '" + std::string(1, (c >= 32 && c < 127) ? c : '?') + "'");
    }
  }

  void expect(char c) {
    if (pos_ >= text_.size() || text_[pos_] != c) fail(std::string("expected '") + c + "'");
    ++pos_;
  }

  std::string_view text_;
  std::size_t max_depth_;
  std::size_t pos_ = 0;
};

}  // namespace

std::string Type::to_string() const {
  std::string out;
  print(*this, out);
  return out;
}

bool Type::same_layout(const Type& other) const {
  if (kind != other.kind || children.size() != other.children.size()) return false;
  for (std::size_t i = 0; i < children.size(); ++i) {
    if (!children[i].same_layout(other.children[i])) return false;
  }
  return true;
}

Type parse_signature(std::string_view text, std::size_t max_depth) {
  return Parser(text, max_depth).parse_all();
}

std::size_t min_encoded_size(const Type& type) {
  switch (type.kind) {
    case TypeKind::kVoid:
      return 0;
    case TypeKind::kBool:
    case TypeKind::kInt8:
    case TypeKind::kUInt8:
      return 1;
    case TypeKind::kInt16:
    case TypeKind::kUInt16:
      return 2;
    case TypeKind::kInt32:
    case TypeKind::kUInt32:
    case TypeKind::kFloat:
      return 4;
    case TypeKind::kInt64:
    case TypeKind::kUInt64:
    case TypeKind::kDouble:
      return 8;
    case TypeKind::kString:
    case TypeKind::kRaw:
    case TypeKind::kDynamic:
      return 4;
    case TypeKind::kList:
    case TypeKind::kVarArgs:
    case TypeKind::kMap:
      return 4;
    case TypeKind::kOptional:
      return 1;
    case TypeKind::kObject:
      return 16 + 8;  // empty MetaObject (3 maps + string), 2 ids
    case TypeKind::kUnknown:
      return 0;
    case TypeKind::kTuple: {
      std::size_t n = 0;
      for (const auto& c : type.children) n += min_encoded_size(c);
      return n;
    }
  }
  return 0;
}

}  // namespace pepper::naoqi_bridge::qi
