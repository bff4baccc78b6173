#include "core/memory/visual_memory.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "core/camera/intrinsics_json.hpp"
#include "memory/detail/binary_io.hpp"
#include "memory/detail/file_io.hpp"

namespace pepper::core::memory {
namespace fs = std::filesystem;
using nlohmann::json;
using Kind = MapError::Kind;

MapError::MapError(Kind kind, fs::path path, const std::string& what)
    : std::runtime_error(what), kind_(kind), path_(std::move(path)) {}

const char* to_string(MapError::Kind kind) {
  switch (kind) {
    case Kind::kIo:
      return "io";
    case Kind::kMissingFile:
      return "missing_file";
    case Kind::kSizeMismatch:
      return "size_mismatch";
    case Kind::kChecksumMismatch:
      return "checksum_mismatch";
    case Kind::kMalformed:
      return "malformed";
    case Kind::kWrongVersion:
      return "wrong_version";
    case Kind::kIntrinsicsMismatch:
      return "intrinsics_mismatch";
    case Kind::kInvalidMap:
      return "invalid_map";
    case Kind::kModeMismatch:
      return "mode_mismatch";
  }
  return "unknown";
}

namespace {

constexpr const char* kManifestName = "manifest.json";
constexpr const char* kFormatName = "pepper-visual-memory";

[[noreturn]] void io_error(const fs::path& path, const std::string& what) {
  throw MapError(Kind::kIo, path, path.string() + ": " + what + " (" + std::strerror(errno) + ")");
}

void write_file_synced(const fs::path& path, const uint8_t* data, size_t size) {
  detail::write_file_synced(path, data, size, io_error);
}

void fsync_dir(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) io_error(dir, "cannot open folder to fsync");
  ::fsync(fd);  // best effort: some filesystems refuse fsync on folders
  ::close(fd);
}

std::vector<uint8_t> read_file(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw MapError(Kind::kMissingFile, path, path.string() + ": missing");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) io_error(path, "cannot open");
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
  if (in.bad()) io_error(path, "read failed");
  return bytes;
}

std::string key_name(size_t i, const char* ext) {
  std::ostringstream os;
  os << "key_" << std::setw(4) << std::setfill('0') << i << ext;
  return os.str();
}

// Manifest CRC: over dump() of the manifest without its "manifest_crc32" field (nlohmann's
// object keys are sorted, so dump() is canonical).
uint32_t manifest_crc(json j) {
  j.erase("manifest_crc32");
  return detail::crc32(j.dump());
}

struct ManifestKey {
  int64_t source_frame_index = -1;
  int64_t t_ns = 0;
  double travelled_m = std::numeric_limits<double>::quiet_NaN();  // optional field
  std::optional<OdometryPose> odom;                               // optional field
  std::string image, features;
  uint64_t image_bytes = 0, features_bytes = 0;
  uint32_t image_crc32 = 0, features_crc32 = 0;
  int lines = 0, corners = 0, keypoints = 0;
};

struct Manifest {
  NavMode mode = NavMode::kForward;
  CameraIntrinsics camera;
  std::string parameters_json;
  std::vector<ManifestKey> keys;
  int final_index = -1;
};

bool finite(const OdometryPose& p) {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.yaw_rad);
}

json odom_to_json(const OdometryPose& p) {
  return {{"x_m", p.x_m}, {"y_m", p.y_m}, {"yaw_rad", p.yaw_rad}};
}

bool is_plain_file_name(const std::string& name) {
  return !name.empty() && name.find('/') == std::string::npos && name != "." && name != "..";
}

Manifest parse_manifest(const fs::path& dir) {
  const fs::path path = dir / kManifestName;
  const std::vector<uint8_t> bytes = read_file(path);
  auto malformed = [&](const std::string& what) -> MapError {
    return MapError(Kind::kMalformed, path, path.string() + ": " + what);
  };
  json j;
  try {
    j = json::parse(bytes.begin(), bytes.end());
  } catch (const json::exception& e) {
    throw malformed(std::string("not valid JSON: ") + e.what());
  }
  Manifest m;
  try {
    if (!j.is_object() || j.value("format", std::string()) != kFormatName) {
      throw malformed(std::string("not a map manifest (format != ") + kFormatName + ")");
    }
    const int version = j.at("format_version").get<int>();
    if (version != kMapFormatVersion) {
      throw MapError(Kind::kWrongVersion, path,
                     path.string() + ": map format version " + std::to_string(version) +
                         ", this build reads version " + std::to_string(kMapFormatVersion));
    }
    if (j.at("manifest_crc32").get<uint32_t>() != manifest_crc(j)) {
      throw MapError(Kind::kChecksumMismatch, path,
                     path.string() + ": manifest CRC-32 mismatch (edited or corrupt)");
    }
    if (j.contains("mode")) {  // absent in maps saved before issue 24: forward, the only mode
      const json& mode = j.at("mode");
      const auto parsed =
          mode.is_string() ? nav_mode_from_string(mode.get<std::string>()) : std::nullopt;
      if (!parsed) throw malformed("mode " + mode.dump() + ": must be \"forward\" or \"ceiling\"");
      m.mode = *parsed;
    }
    try {
      m.camera = camera::intrinsics_from_json(j.at("camera"));
    } catch (const std::invalid_argument& e) {
      throw malformed(std::string("camera: ") + e.what());
    }
    m.parameters_json = j.at("parameters").dump();
    for (const json& k : j.at("key_images")) {
      ManifestKey mk;
      mk.source_frame_index = k.at("source_frame_index").get<int64_t>();
      mk.t_ns = k.at("t_ns").get<int64_t>();
      if (k.contains("travelled_m")) {
        mk.travelled_m = k.at("travelled_m").get<double>();
        const double before_m = m.keys.empty() ? 0.0 : m.keys.back().travelled_m;
        if (!std::isfinite(mk.travelled_m) || mk.travelled_m < 0.0 ||
            !(mk.travelled_m >= before_m)) {  // NaN before: some keys have it, some not
          throw malformed("key image " + std::to_string(m.keys.size()) + ": travelled_m " +
                          std::to_string(mk.travelled_m) +
                          " must be >= 0, not below the previous key image's, and given for "
                          "every key image or none");
        }
      } else if (!m.keys.empty() && !std::isnan(m.keys.back().travelled_m)) {
        throw malformed("key image " + std::to_string(m.keys.size()) +
                        ": travelled_m missing while earlier key images have it");
      }
      if (k.contains("odom")) {  // absent in maps taught without odometry or before it existed
        const json& o = k.at("odom");
        mk.odom = OdometryPose{o.at("x_m").get<double>(), o.at("y_m").get<double>(),
                               o.at("yaw_rad").get<double>()};
        if (!finite(*mk.odom)) {
          throw malformed("key image " + std::to_string(m.keys.size()) +
                          ": odom must hold finite x_m, y_m and yaw_rad");
        }
      }
      mk.image = k.at("image").get<std::string>();
      mk.features = k.at("features").get<std::string>();
      mk.image_bytes = k.at("image_bytes").get<uint64_t>();
      mk.features_bytes = k.at("features_bytes").get<uint64_t>();
      mk.image_crc32 = k.at("image_crc32").get<uint32_t>();
      mk.features_crc32 = k.at("features_crc32").get<uint32_t>();
      mk.lines = k.at("lines").get<int>();
      mk.corners = k.at("corners").get<int>();
      mk.keypoints = k.at("keypoints").get<int>();
      if (!is_plain_file_name(mk.image) || !is_plain_file_name(mk.features)) {
        throw malformed("key image file names must be plain names inside the map folder");
      }
      m.keys.push_back(std::move(mk));
    }
    m.final_index = j.at("final_image_index").get<int>();
  } catch (const json::exception& e) {
    throw malformed(std::string("missing or mistyped field: ") + e.what());
  }
  if (m.keys.size() < 2) throw malformed("a map needs at least 2 key images");
  if (m.final_index != static_cast<int>(m.keys.size()) - 1) {
    throw malformed("final_image_index must be the last key image");
  }
  return m;
}

std::vector<uint8_t> read_checked(const fs::path& path, uint64_t expected_bytes,
                                  uint32_t expected_crc) {
  std::vector<uint8_t> bytes = read_file(path);
  if (bytes.size() != expected_bytes) {
    throw MapError(Kind::kSizeMismatch, path,
                   path.string() + ": " + std::to_string(bytes.size()) + " bytes, manifest says " +
                       std::to_string(expected_bytes) + " (truncated or overwritten)");
  }
  if (detail::crc32(bytes) != expected_crc) {
    throw MapError(Kind::kChecksumMismatch, path, path.string() + ": CRC-32 mismatch (corrupt)");
  }
  return bytes;
}

bool same_camera(const CameraIntrinsics& a, const CameraIntrinsics& b) {
  auto close = [](double x, double y) {
    return std::abs(x - y) <= 1e-6 * std::max(1.0, std::abs(y));
  };
  return a.width_px == b.width_px && a.height_px == b.height_px && close(a.fx_px, b.fx_px) &&
         close(a.fy_px, b.fy_px) && close(a.cx_px, b.cx_px) && close(a.cy_px, b.cy_px);
}

fs::path sibling(const fs::path& dir, const std::string& tag) {
  static std::atomic<unsigned> counter{0};
  return dir.parent_path() / (dir.filename().string() + "." + tag + "-" +
                              std::to_string(::getpid()) + "-" + std::to_string(counter++));
}

MapSummary summary_from_manifest(const Manifest& m) {
  MapSummary s;
  s.mode = m.mode;
  s.key_image_count = static_cast<int>(m.keys.size());
  s.final_index = m.final_index;
  s.camera = m.camera;
  for (const ManifestKey& k : m.keys) {
    s.key_images.push_back(
        {k.source_frame_index, k.t_ns, k.lines, k.corners, k.keypoints, k.travelled_m, k.odom});
  }
  if (!m.keys.empty()) {
    s.taught_duration_s = static_cast<double>(m.keys.back().t_ns - m.keys.front().t_ns) * 1e-9;
    s.first_frame_index = m.keys.front().source_frame_index;
    s.last_frame_index = m.keys.back().source_frame_index;
  }
  return s;
}

}  // namespace

void save_map(const VisualMemory& map, const fs::path& dir_in,
              const std::function<void(const fs::path& tmp_dir)>& write_extra) {
  const fs::path dir = fs::absolute(dir_in).lexically_normal();
  if (map.key_images.size() < 2) {
    throw MapError(Kind::kInvalidMap, dir, dir.string() + ": a map needs at least 2 key images");
  }
  if (const auto errors = map.camera.validate(); !errors.empty()) {
    throw MapError(Kind::kInvalidMap, dir, dir.string() + ": camera: " + errors.front());
  }
  // travelled_m: on every key image (>= 0, never decreasing) or on none; a map that would not
  // load is not written.
  const bool with_travelled = !std::isnan(map.key_images.front().travelled_m);
  for (size_t i = 0; i < map.key_images.size(); ++i) {
    const double d = map.key_images[i].travelled_m;
    const double before = i == 0 ? 0.0 : map.key_images[i - 1].travelled_m;
    const bool ok = with_travelled ? std::isfinite(d) && d >= 0.0 && d >= before : std::isnan(d);
    if (!ok) {
      throw MapError(Kind::kInvalidMap, dir,
                     dir.string() + ": key image " + std::to_string(i) + ": travelled_m " +
                         std::to_string(d) +
                         " must be given for every key image or none, >= 0 and never decreasing");
    }
  }
  // Every key image's features went through the map camera's projection model: the file keeps
  // only its pinhole part and load_map gives it the map's model back, so a key image
  // normalised through another model would come back undistorted differently.
  for (size_t i = 0; i < map.key_images.size(); ++i) {
    const CameraIntrinsics& k = map.key_images[i].features.intrinsics;
    if (k.model != map.camera.model || k.kud != map.camera.kud || k.kdu != map.camera.kdu) {
      throw MapError(Kind::kInvalidMap, dir,
                     dir.string() + ": key image " + std::to_string(i) + ": camera model " +
                         to_string(k.model) + " differs from the map's " +
                         to_string(map.camera.model));
    }
  }
  for (size_t i = 0; i < map.key_images.size(); ++i) {
    if (map.key_images[i].odom && !finite(*map.key_images[i].odom)) {
      throw MapError(
          Kind::kInvalidMap, dir,
          dir.string() + ": key image " + std::to_string(i) + ": odom must hold finite numbers");
    }
  }
  json parameters;
  try {
    parameters = json::parse(map.parameters_json.empty() ? "{}" : map.parameters_json);
  } catch (const json::exception& e) {
    throw MapError(Kind::kInvalidMap, dir, dir.string() + ": parameters_json is not JSON");
  }
  std::error_code ec;
  if (!dir.parent_path().empty()) fs::create_directories(dir.parent_path(), ec);
  const fs::path tmp = sibling(dir, "tmp");
  fs::remove_all(tmp, ec);
  if (!fs::create_directory(tmp, ec)) io_error(tmp, "cannot create temporary folder");
  try {
    json keys = json::array();
    for (size_t i = 0; i < map.key_images.size(); ++i) {
      const KeyImage& k = map.key_images[i];
      const features::ImageFeatures& f = k.features;
      if (f.gray.empty() || f.gray.type() != CV_8UC1 || f.gray.size() != f.image_size) {
        throw MapError(Kind::kInvalidMap, dir,
                       dir.string() + ": key image " + std::to_string(i) +
                           " has no 8-bit grey image of its features' size");
      }
      std::vector<uint8_t> png;
      if (!cv::imencode(".png", f.gray, png)) {
        throw MapError(Kind::kIo, tmp / key_name(i, ".png"), "PNG encoding failed");
      }
      const std::vector<uint8_t> feat = detail::encode_features(f);
      const std::string image_name = key_name(i, ".png"), feat_name = key_name(i, ".feat");
      write_file_synced(tmp / image_name, png.data(), png.size());
      write_file_synced(tmp / feat_name, feat.data(), feat.size());
      json entry = {{"source_frame_index", k.source_frame_index},
                    {"t_ns", k.t_ns},
                    {"image", image_name},
                    {"image_bytes", png.size()},
                    {"image_crc32", detail::crc32(png)},
                    {"features", feat_name},
                    {"features_bytes", feat.size()},
                    {"features_crc32", detail::crc32(feat)},
                    {"lines", f.lines.size()},
                    {"corners", f.corners_px.size()},
                    {"keypoints", f.keypoints.size()}};
      if (with_travelled) entry["travelled_m"] = k.travelled_m;
      if (k.odom) entry["odom"] = odom_to_json(*k.odom);
      keys.push_back(std::move(entry));
    }
    json manifest = {
        {"format", kFormatName},
        {"format_version", kMapFormatVersion},
        {"mode", to_string(map.mode)},
        {"camera", camera::intrinsics_to_json(map.camera)},
        {"parameters", parameters},
        {"key_images", keys},
        {"final_image_index", map.final_index()},
        {"taught_duration_s",
         static_cast<double>(map.key_images.back().t_ns - map.key_images.front().t_ns) * 1e-9}};
    manifest["manifest_crc32"] = manifest_crc(manifest);
    const std::string text = manifest.dump(2) + "\n";
    write_file_synced(tmp / kManifestName, reinterpret_cast<const uint8_t*>(text.data()),
                      text.size());
    if (write_extra) write_extra(tmp);
    fsync_dir(tmp);
    fs::path old;
    if (fs::exists(dir, ec)) {
      old = sibling(dir, "old");
      fs::rename(dir, old, ec);
      if (ec) io_error(dir, "cannot move the existing map aside");
    }
    fs::rename(tmp, dir, ec);
    if (ec) {
      if (!old.empty()) fs::rename(old, dir, ec);  // put the previous map back
      io_error(dir, "cannot rename the new map into place");
    }
    fsync_dir(dir.parent_path().empty() ? fs::path(".") : dir.parent_path());
    if (!old.empty()) fs::remove_all(old, ec);
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
}

VisualMemory load_map(const fs::path& dir, const LoadOptions& options) {
  if (!fs::is_directory(dir)) {
    throw MapError(Kind::kMissingFile, dir, dir.string() + ": no such map folder");
  }
  const Manifest m = parse_manifest(dir);
  if (options.expected_mode && *options.expected_mode != m.mode) {
    // Before the camera: a map of the other mode is the wrong map, whatever its camera.
    throw MapError(Kind::kModeMismatch, dir / kManifestName,
                   (dir / kManifestName).string() + ": map taught in " + to_string(m.mode) +
                       " mode, this run is in " + to_string(*options.expected_mode) +
                       " mode: run with --mode " + to_string(m.mode) + " or teach a " +
                       to_string(*options.expected_mode) + "-mode map");
  }
  if (options.expected_camera) {
    const CameraIntrinsics expected =
        options.expected_camera->scaled_to(m.camera.width_px, m.camera.height_px);
    // The projection model first: features taught through one model do not compare with features
    // seen through another (a map written before the model was recorded is without distortion).
    auto close = [](double x, double y) { return std::abs(x - y) <= 1e-9 + 1e-6 * std::abs(y); };
    if (m.camera.model != expected.model || !close(m.camera.kud, expected.kud) ||
        !close(m.camera.kdu, expected.kdu)) {
      std::ostringstream os;
      os << (dir / kManifestName).string() << ": map taught with camera model "
         << to_string(m.camera.model) << " (kud " << m.camera.kud << ", kdu " << m.camera.kdu
         << "), the camera is " << to_string(expected.model) << " (kud " << expected.kud
         << ", kdu " << expected.kdu << ")";
      throw MapError(Kind::kIntrinsicsMismatch, dir / kManifestName, os.str());
    }
    if (!same_camera(m.camera, expected)) {
      std::ostringstream os;
      os << (dir / kManifestName).string() << ": map camera fx " << m.camera.fx_px << " fy "
         << m.camera.fy_px << " cx " << m.camera.cx_px << " cy " << m.camera.cy_px
         << " differs from the expected fx " << expected.fx_px << " fy " << expected.fy_px << " cx "
         << expected.cx_px << " cy " << expected.cy_px;
      throw MapError(Kind::kIntrinsicsMismatch, dir / kManifestName, os.str());
    }
  }
  VisualMemory map;
  map.mode = m.mode;
  map.camera = m.camera;
  map.parameters_json = m.parameters_json;
  for (const ManifestKey& k : m.keys) {
    const fs::path feat_path = dir / k.features;
    const fs::path image_path = dir / k.image;
    KeyImage key;
    key.source_frame_index = k.source_frame_index;
    key.t_ns = k.t_ns;
    key.travelled_m = k.travelled_m;
    key.odom = k.odom;
    key.features = detail::decode_features(
        read_checked(feat_path, k.features_bytes, k.features_crc32), feat_path);
    const std::vector<uint8_t> png = read_checked(image_path, k.image_bytes, k.image_crc32);
    cv::Mat gray;
    try {
      gray = cv::imdecode(png, cv::IMREAD_GRAYSCALE);
    } catch (const cv::Exception& e) {
      gray.release();
    }
    if (gray.empty()) {
      throw MapError(Kind::kMalformed, image_path, image_path.string() + ": not a decodable PNG");
    }
    if (gray.size() != key.features.image_size) {
      throw MapError(Kind::kMalformed, image_path,
                     image_path.string() + ": image size differs from its features file");
    }
    if (key.features.image_size != cv::Size(m.camera.width_px, m.camera.height_px)) {
      throw MapError(Kind::kIntrinsicsMismatch, feat_path,
                     feat_path.string() + ": image size differs from the manifest camera");
    }
    // A feature file holds the pinhole part of the camera; the projection model is the map's
    // (the manifest records it), and the key image's corners are undistorted through it when
    // matched, as the current frame's are (core/camera/distortion.hpp).
    key.features.intrinsics.model = m.camera.model;
    key.features.intrinsics.kud = m.camera.kud;
    key.features.intrinsics.kdu = m.camera.kdu;
    key.features.gray = gray;
    if (options.build_klt_pyramids) features::build_klt_pyramid(key.features);
    map.key_images.push_back(std::move(key));
  }
  return map;
}

MapSummary summarize(const VisualMemory& map) {
  MapSummary s;
  s.mode = map.mode;
  s.key_image_count = static_cast<int>(map.key_images.size());
  s.final_index = map.final_index();
  s.camera = map.camera;
  for (const KeyImage& k : map.key_images) {
    s.key_images.push_back({k.source_frame_index, k.t_ns, static_cast<int>(k.features.lines.size()),
                            static_cast<int>(k.features.corners_px.size()),
                            static_cast<int>(k.features.keypoints.size()), k.travelled_m, k.odom});
  }
  if (!map.key_images.empty()) {
    s.taught_duration_s =
        static_cast<double>(map.key_images.back().t_ns - map.key_images.front().t_ns) * 1e-9;
    s.first_frame_index = map.key_images.front().source_frame_index;
    s.last_frame_index = map.key_images.back().source_frame_index;
  }
  return s;
}

MapSummary read_map_info(const fs::path& dir) {
  if (!fs::is_directory(dir)) {
    throw MapError(Kind::kMissingFile, dir, dir.string() + ": no such map folder");
  }
  return summary_from_manifest(parse_manifest(dir));
}

std::string MapSummary::to_text() const {
  std::ostringstream os;
  os << "mode: " << to_string(mode) << "\n"
     << "key images: " << key_image_count << " (final image: " << final_index << ")\n"
     << "taught duration: " << std::fixed << std::setprecision(1) << taught_duration_s << " s"
     << " (frames " << first_frame_index << ".." << last_frame_index << ")\n"
     << "camera: " << camera.width_px << "x" << camera.height_px << " fx " << std::setprecision(2)
     << camera.fx_px << " fy " << camera.fy_px << " cx " << camera.cx_px << " cy " << camera.cy_px;
  if (camera.model != ProjectionModel::kWithoutDistortion) {
    os << " " << to_string(camera.model) << " kud " << std::setprecision(4) << camera.kud << " kdu "
       << camera.kdu;
  }
  os << "\n";
  if (!key_images.empty()) {
    const double driven_m = key_images.back().travelled_m - key_images.front().travelled_m;
    os << "driven: ";
    if (std::isnan(driven_m)) {
      os << "unknown (no odometry in this map: segments are measured by taught time)\n";
    } else {
      // Teach measures with the robot's odometry where its frames had it (drive_odometer.hpp),
      // and the map keeps that odometry with each key image.
      const bool odometry = std::all_of(key_images.begin(), key_images.end(),
                                        [](const PerKeyImage& k) { return k.odom.has_value(); });
      os << std::setprecision(2) << driven_m
         << (odometry ? " m (the robot's odometry during teach)\n"
                      : " m (commanded during teach)\n");
    }
  }
  for (size_t i = 0; i < key_images.size(); ++i) {
    const PerKeyImage& k = key_images[i];
    os << "  #" << i << " frame " << k.source_frame_index << " t " << std::setprecision(3)
       << static_cast<double>(k.t_ns) * 1e-9 << " s: " << k.lines << " lines, " << k.corners
       << " corners, " << k.keypoints << " keypoints";
    if (!std::isnan(k.travelled_m)) os << std::setprecision(2) << ", at " << k.travelled_m << " m";
    if (k.odom) {
      os << std::setprecision(2) << ", odom (" << k.odom->x_m << ", " << k.odom->y_m << ") m "
         << std::setprecision(1) << k.odom->yaw_rad * 180.0 / M_PI << " deg";
    }
    os << "\n";
  }
  return os.str();
}

}  // namespace pepper::core::memory
