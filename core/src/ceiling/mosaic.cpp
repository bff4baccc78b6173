// The ceiling mosaic's file (see mosaic.hpp).
#include "core/ceiling/mosaic.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "memory/detail/binary_io.hpp"
#include "memory/detail/file_io.hpp"

namespace pepper::core::ceiling {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kFormatName = "pepper-ceiling-mosaic";

std::string to_hex(const cv::Mat& d) {
  static const char* kDigits = "0123456789abcdef";
  std::string s;
  for (int i = 0; i < d.cols; ++i) {
    const uint8_t b = d.at<uint8_t>(0, i);
    s += kDigits[b >> 4];
    s += kDigits[b & 15];
  }
  return s;
}

bool from_hex(const std::string& s, cv::Mat& out) {
  if (s.size() != 2 * kMosaicDescriptorBytes) return false;
  out.create(1, kMosaicDescriptorBytes, CV_8U);
  for (int i = 0; i < kMosaicDescriptorBytes; ++i) {
    int v = 0;
    for (int k = 0; k < 2; ++k) {
      const char c = s[static_cast<size_t>(2 * i + k)];
      int d = -1;
      if (c >= '0' && c <= '9') d = c - '0';
      if (c >= 'a' && c <= 'f') d = c - 'a' + 10;
      if (d < 0) return false;
      v = 16 * v + d;
    }
    out.at<uint8_t>(0, i) = static_cast<uint8_t>(v);
  }
  return true;
}

// CRC over the canonical dump (nlohmann's objects are key-sorted) without the "crc32" field.
uint32_t body_crc(json j) {
  j.erase("crc32");
  return memory::detail::crc32(j.dump());
}

[[noreturn]] void io_error(const fs::path& path, const std::string& what) {
  throw MosaicError(path, what + " (" + std::strerror(errno) + ")");
}

}  // namespace

MosaicError::MosaicError(fs::path path, const std::string& what)
    : std::runtime_error(path.string() + ": " + what), path_(std::move(path)) {}

std::vector<std::string> Mosaic::validate() const {
  std::vector<std::string> errors;
  if (!(std::isfinite(px_per_m) && px_per_m > 0.0))
    errors.push_back("px_per_m = " + std::to_string(px_per_m) + " must be finite and > 0");
  std::set<int64_t> ids;
  for (size_t i = 0; i < landmarks.size(); ++i) {
    const MosaicLandmark& l = landmarks[i];
    const std::string at = "landmarks[" + std::to_string(i) + "] (id " + std::to_string(l.id) + ")";
    if (l.id < 0) errors.push_back(at + ": id must be >= 0");
    if (!ids.insert(l.id).second) errors.push_back(at + ": id used twice");
    if (!(std::isfinite(l.position_m.x) && std::isfinite(l.position_m.y) &&
          std::isfinite(l.orientation_rad)))
      errors.push_back(at + ": position_m and orientation_rad must be finite");
    if (l.observations < 1) errors.push_back(at + ": observations must be >= 1");
    if (l.descriptor.rows != 1 || l.descriptor.cols != kMosaicDescriptorBytes ||
        l.descriptor.type() != CV_8U)
      errors.push_back(at + ": descriptor must be 1x" + std::to_string(kMosaicDescriptorBytes) +
                       " CV_8U");
  }
  return errors;
}

void save_mosaic(const Mosaic& mosaic, const fs::path& file) {
  const auto errors = mosaic.validate();
  if (!errors.empty()) throw MosaicError(file, "invalid mosaic, not saved: " + errors.front());
  json landmarks = json::array();
  for (const MosaicLandmark& l : mosaic.landmarks) {
    landmarks.push_back({{"id", l.id},
                         {"x_m", l.position_m.x},
                         {"y_m", l.position_m.y},
                         {"orientation_rad", l.orientation_rad},
                         {"observations", l.observations},
                         {"descriptor", to_hex(l.descriptor)}});
  }
  json j = {{"format", kFormatName},
            {"format_version", kMosaicFormatVersion},
            {"px_per_m", mosaic.px_per_m},
            {"landmarks", landmarks}};
  j["crc32"] = body_crc(j);
  const std::string text = j.dump(1) + "\n";

  memory::detail::replace_file_atomically(file, text, io_error);
}

Mosaic load_mosaic(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw MosaicError(file, "missing or unreadable");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    throw MosaicError(file, std::string("not valid JSON (truncated or corrupt): ") + e.what());
  }
  Mosaic m;
  try {
    if (!j.is_object() || j.value("format", std::string()) != kFormatName)
      throw MosaicError(file, std::string("not a mosaic file (format != ") + kFormatName + ")");
    const int version = j.at("format_version").get<int>();
    if (version != kMosaicFormatVersion)
      throw MosaicError(file, "mosaic format version " + std::to_string(version) +
                                  ", this build reads version " +
                                  std::to_string(kMosaicFormatVersion));
    if (j.at("crc32").get<uint32_t>() != body_crc(j))
      throw MosaicError(file, "CRC-32 mismatch (edited or corrupt)");
    m.px_per_m = j.at("px_per_m").get<double>();
    for (const json& l : j.at("landmarks")) {
      MosaicLandmark lm;
      lm.id = l.at("id").get<int64_t>();
      lm.position_m = {l.at("x_m").get<double>(), l.at("y_m").get<double>()};
      lm.orientation_rad = l.at("orientation_rad").get<double>();
      lm.observations = l.at("observations").get<int>();
      if (!from_hex(l.at("descriptor").get<std::string>(), lm.descriptor))
        throw MosaicError(file, "landmark id " + std::to_string(lm.id) + ": descriptor must be " +
                                    std::to_string(2 * kMosaicDescriptorBytes) +
                                    " lower-case hex digits");
      m.landmarks.push_back(std::move(lm));
    }
  } catch (const json::exception& e) {
    throw MosaicError(file, std::string("missing or mistyped field: ") + e.what());
  }
  const auto errors = m.validate();
  if (!errors.empty()) throw MosaicError(file, errors.front());
  return m;
}

}  // namespace pepper::core::ceiling
