// Binary key-image feature file (docs/method/map_format.md):
//   "PEPKFEAT" | u32 version | i32 w, h | 6 x f64 intrinsics (w, h as f64 unused: fx fy cx cy)
//   | u32 n_lines, n x line record | mat line_descriptors | u32 n_corners, n x 2 f32
//   | u32 n_kp, n x keypoint record | mat keypoint_descriptors | u32 crc32(all previous bytes)
// mat = i32 rows, i32 cols, i32 type, rows*cols*elemSize bytes. Little-endian host order (x86-64,
// ARM64 both little-endian; a big-endian host fails the magic/CRC check rather than misreading).
#include <array>
#include <cstring>

#include "memory/detail/binary_io.hpp"

namespace pepper::core::memory::detail {
namespace {

constexpr std::array<char, 8> kMagic = {'P', 'E', 'P', 'K', 'F', 'E', 'A', 'T'};

const std::array<uint32_t, 256>& crc_table() {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  return table;
}

void put_mat(ByteWriter& w, const cv::Mat& m) {
  const cv::Mat c = m.isContinuous() ? m : m.clone();
  w.put<int32_t>(c.rows);
  w.put<int32_t>(c.cols);
  w.put<int32_t>(c.empty() ? 0 : c.type());
  if (!c.empty()) w.put_bytes(c.data, c.total() * c.elemSize());
}

cv::Mat get_mat(ByteReader& r, const char* what) {
  const auto rows = r.get<int32_t>();
  const auto cols = r.get<int32_t>();
  const auto type = r.get<int32_t>();
  if (rows == 0 || cols == 0) return {};
  if (rows < 0 || cols < 0 || (type != CV_32F && type != CV_8U)) {
    r.fail(std::string("bad ") + what + " matrix header");
  }
  const size_t elem = type == CV_32F ? 4 : 1;
  const size_t bytes = static_cast<size_t>(rows) * static_cast<size_t>(cols) * elem;
  if (bytes / elem / static_cast<size_t>(cols) != static_cast<size_t>(rows) ||
      bytes > r.remaining()) {
    r.fail(std::string("impossible ") + what + " matrix size");
  }
  cv::Mat m(rows, cols, type);
  std::memcpy(m.data, r.take(bytes), bytes);
  return m;
}

}  // namespace

uint32_t crc32(const uint8_t* data, size_t size) {
  const auto& t = crc_table();
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < size; ++i) c = t[(c ^ data[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

std::vector<uint8_t> encode_features(const features::ImageFeatures& f) {
  ByteWriter w;
  w.put_bytes(kMagic.data(), kMagic.size());
  w.put<uint32_t>(kFeatureFileVersion);
  w.put<int32_t>(f.image_size.width);
  w.put<int32_t>(f.image_size.height);
  w.put<double>(f.intrinsics.fx_px);
  w.put<double>(f.intrinsics.fy_px);
  w.put<double>(f.intrinsics.cx_px);
  w.put<double>(f.intrinsics.cy_px);
  w.put<int32_t>(f.intrinsics.width_px);
  w.put<int32_t>(f.intrinsics.height_px);
  w.put<uint32_t>(static_cast<uint32_t>(f.lines.size()));
  for (const features::LineSegment& l : f.lines) {
    w.put<float>(l.p0_px.x);
    w.put<float>(l.p0_px.y);
    w.put<float>(l.p1_px.x);
    w.put<float>(l.p1_px.y);
    w.put<double>(l.p0_norm.x);
    w.put<double>(l.p0_norm.y);
    w.put<double>(l.p1_norm.x);
    w.put<double>(l.p1_norm.y);
    w.put<double>(l.line.rho);
    w.put<double>(l.line.theta_rad);
    w.put<float>(l.length_px);
  }
  put_mat(w, f.line_descriptors);
  w.put<uint32_t>(static_cast<uint32_t>(f.corners_px.size()));
  for (const cv::Point2f& c : f.corners_px) {
    w.put<float>(c.x);
    w.put<float>(c.y);
  }
  w.put<uint32_t>(static_cast<uint32_t>(f.keypoints.size()));
  for (const cv::KeyPoint& k : f.keypoints) {
    w.put<float>(k.pt.x);
    w.put<float>(k.pt.y);
    w.put<float>(k.size);
    w.put<float>(k.angle);
    w.put<float>(k.response);
    w.put<int32_t>(k.octave);
    w.put<int32_t>(k.class_id);
  }
  put_mat(w, f.keypoint_descriptors);
  const uint32_t crc = crc32(w.bytes());
  w.put<uint32_t>(crc);
  return std::move(w.bytes());
}

features::ImageFeatures decode_features(const std::vector<uint8_t>& bytes,
                                        const std::filesystem::path& path) {
  if (bytes.size() < kMagic.size() + 8) {
    throw MapError(MapError::Kind::kMalformed, path, path.string() + ": too short for a header");
  }
  const size_t body = bytes.size() - 4;
  uint32_t stored_crc;
  std::memcpy(&stored_crc, bytes.data() + body, 4);
  if (crc32(bytes.data(), body) != stored_crc) {
    throw MapError(MapError::Kind::kChecksumMismatch, path,
                   path.string() + ": internal CRC-32 mismatch (corrupt file)");
  }
  ByteReader r(bytes.data(), body, path);
  if (std::memcmp(r.take(kMagic.size()), kMagic.data(), kMagic.size()) != 0) {
    r.fail("not a key-image feature file (bad magic)");
  }
  const auto version = r.get<uint32_t>();
  if (version != static_cast<uint32_t>(kFeatureFileVersion)) {
    throw MapError(MapError::Kind::kWrongVersion, path,
                   path.string() + ": feature file version " + std::to_string(version) +
                       ", supported " + std::to_string(kFeatureFileVersion));
  }
  features::ImageFeatures f;
  f.image_size.width = r.get<int32_t>();
  f.image_size.height = r.get<int32_t>();
  f.intrinsics.fx_px = r.get<double>();
  f.intrinsics.fy_px = r.get<double>();
  f.intrinsics.cx_px = r.get<double>();
  f.intrinsics.cy_px = r.get<double>();
  f.intrinsics.width_px = r.get<int32_t>();
  f.intrinsics.height_px = r.get<int32_t>();
  if (f.image_size.width <= 0 || f.image_size.height <= 0 || !f.intrinsics.validate().empty()) {
    r.fail("invalid image size or intrinsics");
  }
  constexpr size_t kLineBytes = 4 * 4 + 8 * 6 + 4;
  f.lines.resize(r.count(kLineBytes, "line"));
  for (features::LineSegment& l : f.lines) {
    l.p0_px.x = r.get<float>();
    l.p0_px.y = r.get<float>();
    l.p1_px.x = r.get<float>();
    l.p1_px.y = r.get<float>();
    l.p0_norm.x = r.get<double>();
    l.p0_norm.y = r.get<double>();
    l.p1_norm.x = r.get<double>();
    l.p1_norm.y = r.get<double>();
    l.line.rho = r.get<double>();
    l.line.theta_rad = r.get<double>();
    l.length_px = r.get<float>();
  }
  f.line_descriptors = get_mat(r, "line descriptor");
  if (!f.line_descriptors.empty() && f.line_descriptors.rows != static_cast<int>(f.lines.size())) {
    r.fail("line descriptor rows differ from the line count");
  }
  f.corners_px.resize(r.count(8, "corner"));
  for (cv::Point2f& c : f.corners_px) {
    c.x = r.get<float>();
    c.y = r.get<float>();
  }
  f.keypoints.resize(r.count(28, "keypoint"));
  for (cv::KeyPoint& k : f.keypoints) {
    k.pt.x = r.get<float>();
    k.pt.y = r.get<float>();
    k.size = r.get<float>();
    k.angle = r.get<float>();
    k.response = r.get<float>();
    k.octave = r.get<int32_t>();
    k.class_id = r.get<int32_t>();
  }
  f.keypoint_descriptors = get_mat(r, "keypoint descriptor");
  if (!f.keypoint_descriptors.empty() &&
      f.keypoint_descriptors.rows != static_cast<int>(f.keypoints.size())) {
    r.fail("keypoint descriptor rows differ from the keypoint count");
  }
  if (r.remaining() != 0) r.fail("trailing bytes");
  return f;
}

}  // namespace pepper::core::memory::detail
