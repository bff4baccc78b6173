#pragma once
// Private helpers of the map format: CRC-32 (IEEE 802.3, reflected, poly 0xEDB88320), a byte
// writer and a bounds-checked reader that throws MapError(kMalformed) on any overrun, so corrupt
// lengths never allocate or read past the buffer.

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

#include "core/memory/visual_memory.hpp"

namespace pepper::core::memory::detail {

uint32_t crc32(const uint8_t* data, size_t size);
inline uint32_t crc32(const std::vector<uint8_t>& bytes) {
  return crc32(bytes.data(), bytes.size());
}
inline uint32_t crc32(const std::string& s) {
  return crc32(reinterpret_cast<const uint8_t*>(s.data()), s.size());
}

class ByteWriter {
 public:
  template <typename T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const uint8_t*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  void put_bytes(const void* data, size_t size) {
    const auto* p = static_cast<const uint8_t*>(data);
    bytes_.insert(bytes_.end(), p, p + size);
  }
  std::vector<uint8_t>& bytes() { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
};

class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size, std::filesystem::path path)
      : data_(data), size_(size), path_(std::move(path)) {}
  template <typename T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    T value;
    std::memcpy(&value, take(sizeof(T)), sizeof(T));
    return value;
  }
  const uint8_t* take(size_t n) {
    if (n > size_ - pos_)
      fail("truncated: need " + std::to_string(n) + " bytes at offset " + std::to_string(pos_));
    const uint8_t* p = data_ + pos_;
    pos_ += n;
    return p;
  }
  /// A count whose elements take at least elem_bytes each: bounded by what remains.
  uint32_t count(size_t elem_bytes, const char* what) {
    const auto n = get<uint32_t>();
    if (elem_bytes > 0 && n > (size_ - pos_) / elem_bytes) {
      fail(std::string("impossible ") + what + " count " + std::to_string(n));
    }
    return n;
  }
  size_t remaining() const { return size_ - pos_; }
  [[noreturn]] void fail(const std::string& msg) const {
    throw MapError(MapError::Kind::kMalformed, path_, path_.string() + ": " + msg);
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  std::filesystem::path path_;
};

/// Serialises everything of ImageFeatures except gray and the derived pyramid.
std::vector<uint8_t> encode_features(const features::ImageFeatures& f);
/// Inverse of encode_features (gray left empty). Checks magic, version, CRC; throws MapError.
features::ImageFeatures decode_features(const std::vector<uint8_t>& bytes,
                                        const std::filesystem::path& path);

}  // namespace pepper::core::memory::detail
