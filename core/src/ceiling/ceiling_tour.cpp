// The ceiling tour's file (see ceiling_tour.hpp).
#include "core/ceiling/ceiling_tour.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "memory/detail/binary_io.hpp"
#include "memory/detail/file_io.hpp"

namespace pepper::core::ceiling {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kFormatName = "pepper-ceiling-tour";

// CRC over the canonical dump (nlohmann's objects are key-sorted) without the "crc32" field.
uint32_t body_crc(json j) {
  j.erase("crc32");
  return memory::detail::crc32(j.dump());
}

[[noreturn]] void io_error(const fs::path& path, const std::string& what) {
  throw CeilingTourError(path, what + " (" + std::strerror(errno) + ")");
}

bool finite(const PlanarPose& p) {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad);
}


HeightCheck height_check_from_json(const json& j) {
  HeightCheck h;  // an unknown status throws std::invalid_argument
  h.status = height_check_status_from_string(j.at("status").get<std::string>());
  h.configured_height_m = j.at("configured_height_m").get<double>();
  h.configured_above_camera_m = j.at("configured_above_camera_m").get<double>();
  h.windows = j.at("windows").get<int>();
  h.windows_rejected = j.at("windows_rejected").get<int>();
  h.windows_turning = j.at("windows_turning").get<int>();
  h.odometry_m = j.at("odometry_m").get<double>();
  h.scale_ratio = j.at("scale_ratio").get<double>();
  h.scale_ratio_spread = j.at("scale_ratio_spread").get<double>();
  h.scale_ratio_sigma = j.at("scale_ratio_sigma").get<double>();
  h.estimated_above_camera_m = j.at("estimated_above_camera_m").get<double>();
  h.estimated_height_m = j.at("estimated_height_m").get<double>();
  h.estimated_sigma_m = j.at("estimated_sigma_m").get<double>();
  h.disagrees = j.at("disagrees").get<bool>();
  return h;
}

}  // namespace

json height_check_to_json(const HeightCheck& h) {
  return {{"status", to_string(h.status)},
          {"configured_height_m", h.configured_height_m},
          {"configured_above_camera_m", h.configured_above_camera_m},
          {"windows", h.windows},
          {"windows_rejected", h.windows_rejected},
          {"windows_turning", h.windows_turning},
          {"odometry_m", h.odometry_m},
          {"scale_ratio", h.scale_ratio},
          {"scale_ratio_spread", h.scale_ratio_spread},
          {"scale_ratio_sigma", h.scale_ratio_sigma},
          {"estimated_above_camera_m", h.estimated_above_camera_m},
          {"estimated_height_m", h.estimated_height_m},
          {"estimated_sigma_m", h.estimated_sigma_m},
          {"disagrees", h.disagrees}};
}

CeilingTourError::CeilingTourError(fs::path path, const std::string& what)
    : std::runtime_error(path.string() + ": " + what), path_(std::move(path)) {}

std::vector<std::string> CeilingTour::validate() const {
  std::vector<std::string> e;
  if (frames < 2) e.push_back("frames " + std::to_string(frames) + " must be >= 2");
  if (unlocalised_frames < 0 || unlocalised_frames > frames)
    e.push_back("unlocalised_frames " + std::to_string(unlocalised_frames) +
                " must be in [0, frames]");
  if (relay_images.size() < 2)
    e.push_back("relay_images: " + std::to_string(relay_images.size()) + ", at least 2 needed");
  for (size_t i = 0; i < relay_images.size(); ++i) {
    const RelayImageRecord& r = relay_images[i];
    const std::string where = "relay image " + std::to_string(i) + ": ";
    if (r.frame < 0 || r.frame >= frames)
      e.push_back(where + "frame " + std::to_string(r.frame) + " outside the tour's frames");
    if (i > 0 && r.frame <= relay_images[i - 1].frame) e.push_back(where + "frames must increase");
    if (!finite(r.T_mosaic_base)) e.push_back(where + "pose must be finite");
    for (const int64_t id : r.landmark_ids)
      if (id < 0) e.push_back(where + "landmark id " + std::to_string(id) + " must be >= 0");
  }
  for (const int64_t b : breaks)
    if (b < 0 || b + 1 >= static_cast<int64_t>(relay_images.size()))
      e.push_back("break " + std::to_string(b) + " names no pair of relay images");
  if (odometry_disagreement_m && !(*odometry_disagreement_m >= 0.0))
    e.push_back("odometry_disagreement_m must be >= 0");
  if (!(driven_m >= 0.0)) e.push_back("driven_m must be >= 0");
  if (ceiling && !(ceiling->above_camera_m > 0.0 && std::isfinite(ceiling->height_m) &&
                   ceiling->height_m > ceiling->above_camera_m)) {
    e.push_back("ceiling: above_camera_m must be > 0 and below height_m");
  }
  if (height_check) {
    for (const std::string& m : height_check->validate()) e.push_back(m);
  }
  return e;
}

void save_ceiling_tour(const CeilingTour& tour, const fs::path& file) {
  const auto errors = tour.validate();
  if (!errors.empty()) throw CeilingTourError(file, "invalid tour, not saved: " + errors.front());
  json relays = json::array();
  for (const RelayImageRecord& r : tour.relay_images) {
    relays.push_back({{"frame", r.frame},
                      {"x_m", r.T_mosaic_base.x_m},
                      {"y_m", r.T_mosaic_base.y_m},
                      {"theta_rad", r.T_mosaic_base.theta_rad},
                      {"landmark_ids", r.landmark_ids}});
  }
  json j = {{"format", kFormatName},
            {"format_version", kCeilingTourFormatVersion},
            {"frames", tour.frames},
            {"unlocalised_frames", tour.unlocalised_frames},
            {"relay_images", relays},
            {"breaks", tour.breaks},
            {"odometry_disagreement_m",
             tour.odometry_disagreement_m ? json(*tour.odometry_disagreement_m) : json(nullptr)},
            {"driven_m", tour.driven_m},
            {"ceiling", tour.ceiling ? json{{"height_m", tour.ceiling->height_m},
                                            {"above_camera_m", tour.ceiling->above_camera_m}}
                                     : json(nullptr)},
            {"height_check", tour.height_check ? height_check_to_json(*tour.height_check)
                                               : json(nullptr)}};
  j["crc32"] = body_crc(j);
  const std::string text = j.dump(1) + "\n";

  memory::detail::replace_file_atomically(file, text, io_error);
}

CeilingTour load_ceiling_tour(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw CeilingTourError(file, "missing or unreadable");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    throw CeilingTourError(file, std::string("not valid JSON (truncated or corrupt): ") + e.what());
  }
  CeilingTour t;
  try {
    if (!j.is_object() || j.value("format", std::string()) != kFormatName)
      throw CeilingTourError(
          file, std::string("not a ceiling tour file (format != ") + kFormatName + ")");
    const int version = j.at("format_version").get<int>();
    if (version < 1 || version > kCeilingTourFormatVersion)
      throw CeilingTourError(file, "ceiling tour format version " + std::to_string(version) +
                                       ", this build reads versions 1 to " +
                                       std::to_string(kCeilingTourFormatVersion));
    if (j.at("crc32").get<uint32_t>() != body_crc(j))
      throw CeilingTourError(file, "CRC-32 mismatch (edited or corrupt)");
    t.frames = j.at("frames").get<int64_t>();
    t.unlocalised_frames = j.at("unlocalised_frames").get<int64_t>();
    for (const json& r : j.at("relay_images")) {
      RelayImageRecord rec;
      rec.frame = r.at("frame").get<int64_t>();
      rec.T_mosaic_base = {r.at("x_m").get<double>(), r.at("y_m").get<double>(),
                           r.at("theta_rad").get<double>()};
      rec.landmark_ids = r.at("landmark_ids").get<std::vector<int64_t>>();
      t.relay_images.push_back(std::move(rec));
    }
    t.breaks = j.at("breaks").get<std::vector<int64_t>>();
    const json& d = j.at("odometry_disagreement_m");
    if (!d.is_null()) t.odometry_disagreement_m = d.get<double>();
    t.driven_m = j.at("driven_m").get<double>();
    if (version >= 2) {  // version 1 did not record the ceiling
      const json& c = j.at("ceiling");
      if (!c.is_null()) {
        t.ceiling = TaughtCeiling{c.at("height_m").get<double>(),
                                  c.at("above_camera_m").get<double>()};
      }
    }
    if (version >= 3) {  // versions 1 and 2 did not check the height
      const json& h = j.at("height_check");
      if (!h.is_null()) t.height_check = height_check_from_json(h);
    }
  } catch (const json::exception& e) {
    throw CeilingTourError(file, std::string("missing or mistyped field: ") + e.what());
  } catch (const std::invalid_argument& e) {
    throw CeilingTourError(file, std::string("height_check: ") + e.what());
  }
  const auto errors = t.validate();
  if (!errors.empty()) throw CeilingTourError(file, errors.front());
  return t;
}

}  // namespace pepper::core::ceiling
