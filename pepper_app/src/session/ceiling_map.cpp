#include "session/ceiling_map.hpp"

#include <algorithm>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <unordered_set>

namespace pepper::app {

namespace fs = std::filesystem;
namespace cc = core::ceiling;

void save_ceiling_map(const CeilingMap& map, const fs::path& dir) {
  if (map.map.mode != core::NavMode::kCeiling) {
    throw std::invalid_argument(dir.string() + ": save_ceiling_map needs a ceiling-mode map");
  }
  if (map.map.key_images.size() != map.tour.relay_images.size()) {
    throw std::invalid_argument(dir.string() + ": " + std::to_string(map.map.key_images.size()) +
                                " key images for " + std::to_string(map.tour.relay_images.size()) +
                                " relay images");
  }
  // Refuse invalid parts before the map replaces anything in `dir`.
  if (const auto e = map.mosaic.validate(); !e.empty())
    throw cc::MosaicError(dir / kMosaicFileName, "invalid mosaic, not saved: " + e.front());
  if (const auto e = map.tour.validate(); !e.empty())
    throw cc::CeilingTourError(dir / kCeilingTourFileName, "invalid tour, not saved: " + e.front());
  // The mosaic and the tour go into the map's temporary folder: the three parts replace the
  // previous map together (a crash leaves the old map or the new one, never a mix).
  core::memory::save_map(map.map, dir, [&](const fs::path& tmp) {
    cc::save_mosaic(map.mosaic, tmp / kMosaicFileName);
    cc::save_ceiling_tour(map.tour, tmp / kCeilingTourFileName);
  });
}

CeilingParts load_ceiling_parts(const fs::path& dir, const core::memory::MapSummary& summary) {
  if (summary.mode != core::NavMode::kCeiling) {
    throw std::invalid_argument(dir.string() + ": not a ceiling-mode map");
  }
  CeilingParts p;
  p.mosaic = cc::load_mosaic(dir / kMosaicFileName);
  p.tour = cc::load_ceiling_tour(dir / kCeilingTourFileName);
  const fs::path tour_file = dir / kCeilingTourFileName;
  if (p.tour.relay_images.size() != summary.key_images.size()) {
    throw std::runtime_error(
        tour_file.string() + ": " + std::to_string(p.tour.relay_images.size()) +
        " relay images, the manifest has " + std::to_string(summary.key_images.size()) +
        " key images (parts of different teaches?)");
  }
  for (size_t i = 0; i < p.tour.relay_images.size(); ++i) {
    if (p.tour.relay_images[i].frame != summary.key_images[i].source_frame_index) {
      throw std::runtime_error(tour_file.string() + ": relay image " + std::to_string(i) +
                               " is frame " + std::to_string(p.tour.relay_images[i].frame) +
                               ", the manifest's key image " + std::to_string(i) + " frame " +
                               std::to_string(summary.key_images[i].source_frame_index) +
                               " (parts of different teaches?)");
    }
  }
  std::unordered_set<int64_t> ids;
  for (const auto& l : p.mosaic.landmarks) ids.insert(l.id);
  for (size_t i = 0; i < p.tour.relay_images.size(); ++i) {
    for (const int64_t id : p.tour.relay_images[i].landmark_ids) {
      if (ids.count(id) == 0) {
        throw std::runtime_error(tour_file.string() + ": relay image " + std::to_string(i) +
                                 " sees landmark " + std::to_string(id) + ", which " +
                                 (dir / kMosaicFileName).string() +
                                 " does not hold (parts of different teaches?)");
      }
    }
  }
  return p;
}

std::string ceiling_summary_text(const CeilingParts& parts) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(3);
  const cc::CeilingTour& t = parts.tour;
  os << "ceiling mosaic: " << parts.mosaic.landmarks.size() << " landmarks at "
     << std::setprecision(0) << parts.mosaic.px_per_m << " px/m; " << t.frames << " frames taught, "
     << t.unlocalised_frames << " without a pose\n";
  os << std::setprecision(3);
  os << "relay images: " << t.relay_images.size() << ", " << t.breaks.size()
     << " break(s) in the chain\n";
  for (size_t i = 0; i < t.relay_images.size(); ++i) {
    const auto& r = t.relay_images[i];
    os << "  relay " << i << ": frame " << r.frame << ", pose (" << r.T_mosaic_base.x_m << ", "
       << r.T_mosaic_base.y_m << ") m, " << r.T_mosaic_base.theta_rad << " rad, "
       << r.landmark_ids.size() << " landmarks\n";
  }
  if (t.ceiling) {
    os << std::setprecision(2) << "taught under a ceiling " << t.ceiling->height_m
       << " m above the floor, " << t.ceiling->above_camera_m << " m above the camera\n"
       << std::setprecision(3);
  } else {
    os << "ceiling height not recorded (format version 1)\n";
  }
  os << "driven " << t.driven_m << " m; chained pose vs odometry at the end: ";
  if (t.odometry_disagreement_m) {
    os << *t.odometry_disagreement_m << " m\n";
  } else {
    os << "no odometry\n";
  }
  return os.str();
}

std::vector<std::string> ceiling_warnings(const cc::CeilingTour& t) {
  std::vector<std::string> w;
  if (t.unlocalised_frames > 0) {
    w.push_back(std::to_string(t.unlocalised_frames) + " of " + std::to_string(t.frames) +
                " teach frames found no pose in the mosaic (ceiling lost or too poor there): "
                "the mosaic has a gap; re-teach that part");
  }
  for (const int64_t b : t.breaks) {
    w.push_back("relay images " + std::to_string(b) + " and " + std::to_string(b + 1) +
                " share too few landmarks or turn too much (ceiling lost or turn too fast): a "
                "replay cannot servo across");
  }
  if (t.odometry_disagreement_m) {
    const double limit_m = std::max(0.1, 0.05 * t.driven_m);
    if (*t.odometry_disagreement_m > limit_m) {
      std::ostringstream os;
      os << std::fixed << std::setprecision(2) << "the mosaic's chained pose and the odometry "
         << "disagree by " << *t.odometry_disagreement_m << " m over " << t.driven_m
         << " m driven (more than " << limit_m << " m): one of them drifted; check the "
         << "ceiling height and re-teach";
      w.push_back(os.str());
    }
  }
  return w;
}

}  // namespace pepper::app
