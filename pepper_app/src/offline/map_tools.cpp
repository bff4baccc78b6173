#include "offline/map_tools.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace pepper::app {

namespace fs = std::filesystem;
namespace mem = core::memory;

namespace {

bool is_map_folder(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / "manifest.json", ec);
}

std::uintmax_t folder_bytes(const fs::path& dir) {
  std::uintmax_t total = 0;
  std::error_code ec;
  for (const auto& e : fs::recursive_directory_iterator(dir, ec)) {
    std::error_code size_ec;
    if (e.is_regular_file(size_ec)) {
      const auto n = e.file_size(size_ec);
      if (!size_ec) total += n;
    }
  }
  return total;
}

MapListing describe(const fs::path& root, const fs::path& dir) {
  MapListing m;
  m.dir = dir;
  const fs::path rel = dir.lexically_relative(root);
  m.name = rel.empty() || rel == "." ? fs::absolute(dir).lexically_normal().filename().string()
                                     : rel.string();
  if (m.name.empty()) m.name = dir.string();
  struct stat st {};
  if (::stat((dir / "manifest.json").c_str(), &st) == 0) m.saved = st.st_mtime;
  m.bytes = folder_bytes(dir);
  try {
    const mem::MapSummary s = mem::read_map_info(dir);
    m.readable = true;
    m.key_images = s.key_image_count;
    if (!s.key_images.empty()) {
      m.length_m = s.key_images.back().travelled_m - s.key_images.front().travelled_m;
    }
  } catch (const std::exception& e) {
    m.problem = e.what();
  }
  return m;
}

std::string human_bytes(std::uintmax_t bytes) {
  char buf[32];
  if (bytes >= 1'000'000) {
    std::snprintf(buf, sizeof buf, "%.1f MB", static_cast<double>(bytes) / 1e6);
  } else {
    std::snprintf(buf, sizeof buf, "%.0f kB", static_cast<double>(bytes) / 1e3);
  }
  return buf;
}

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

std::vector<MapListing> find_maps(const fs::path& root, int max_depth) {
  std::error_code ec;
  if (!fs::is_directory(root, ec)) {
    throw std::runtime_error(root.string() + ": not a folder: give the folder that holds the maps");
  }
  std::vector<MapListing> found;
  if (is_map_folder(root)) {
    found.push_back(describe(root, root));
    return found;
  }
  fs::recursive_directory_iterator it(root, fs::directory_options::skip_permission_denied, ec);
  for (; !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    std::error_code dir_ec;
    if (!it->is_directory(dir_ec)) continue;
    if (is_map_folder(it->path())) {
      found.push_back(describe(root, it->path()));
      it.disable_recursion_pending();  // a map holds key images, not maps
    } else if (it.depth() + 1 >= max_depth) {
      it.disable_recursion_pending();
    }
  }
  std::sort(found.begin(), found.end(),
            [](const MapListing& a, const MapListing& b) { return a.name < b.name; });
  return found;
}

std::string to_text(const MapListing& m) {
  std::string s = m.name;
  if (!m.readable) return s + "  unreadable: " + m.problem;
  char buf[64];
  s += "  " + std::to_string(m.key_images) + " key images  ";
  if (std::isfinite(m.length_m)) {
    std::snprintf(buf, sizeof buf, "%.2f m", m.length_m);
    s += buf;
  } else {
    s += "length unknown";
  }
  if (m.saved != 0) {
    std::tm local{};
    localtime_r(&m.saved, &local);
    std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M", &local);
    s += std::string("  ") + buf;
  }
  return s + "  " + human_bytes(m.bytes);
}

std::vector<TourWarning> check_tour(const mem::MapSummary& summary,
                                    const TourCheckOptions& options) {
  std::vector<TourWarning> warnings;
  const auto& keys = summary.key_images;
  const bool have_distances =
      !keys.empty() && std::all_of(keys.begin(), keys.end(),
                                   [](const auto& k) { return std::isfinite(k.travelled_m); });
  std::vector<double> gaps;  // gaps[i]: from key image i to i + 1 (m, or s without distances)
  for (std::size_t i = 1; i < keys.size(); ++i) {
    gaps.push_back(have_distances ? keys[i].travelled_m - keys[i - 1].travelled_m
                                  : static_cast<double>(keys[i].t_ns - keys[i - 1].t_ns) * 1e-9);
  }
  const double typical = median(gaps);
  const double floor = have_distances ? options.min_long_gap_m : options.min_long_gap_s;
  const char* unit = have_distances ? " m" : " s";
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const auto& k = keys[i];
    if (k.lines + k.corners < options.min_features) {
      warnings.push_back({static_cast<int>(i),
                          "key image " + std::to_string(i) + " has few features (" +
                              std::to_string(k.lines) + " lines, " + std::to_string(k.corners) +
                              " points, fewer than " + std::to_string(options.min_features) +
                              "): the replay may get lost there; add texture (a poster) "
                              "or re-teach this part facing a richer view"});
    }
    if (i > 0) {
      const double gap = gaps[i - 1];
      if (std::isfinite(typical) && gap > floor && gap > options.long_gap_factor * typical) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "%.1f%s between key images %zu and %zu (typical: %.1f%s)",
                      gap, unit, i - 1, i, typical, unit);
        warnings.push_back({static_cast<int>(i),
                            std::string("long gap: ") + buf +
                                ": little changed in view for a long way (a blank wall ahead?); "
                                "the replay servoes on one key image all along: re-teach this "
                                "part more slowly or with more to see"});
      }
    }
  }
  return warnings;
}

void check_trim_range(int from, int to, int final_index) {
  if (from < 0 || to > final_index || from >= to) {
    throw std::invalid_argument("--from " + std::to_string(from) + " --to " + std::to_string(to) +
                                ": the map has key images 0.." + std::to_string(final_index) +
                                "; give 0 <= --from < --to <= " + std::to_string(final_index) +
                                " (a map keeps at least two key images)");
  }
}

mem::VisualMemory trim_map(const mem::VisualMemory& map, int from, int to) {
  check_trim_range(from, to, map.final_index());
  mem::VisualMemory out;
  out.camera = map.camera;
  out.parameters_json = map.parameters_json;
  const double first_m = map.key_images[from].travelled_m;
  for (int i = from; i <= to; ++i) {
    mem::KeyImage k = map.key_images[i];
    // The map's distances are measured from the tour's first frame, which is now this one.
    if (std::isfinite(k.travelled_m)) k.travelled_m = std::max(0.0, k.travelled_m - first_m);
    out.key_images.push_back(std::move(k));
  }
  return out;
}

TaughtPath trim_taught_path(const TaughtPath& path, const mem::VisualMemory& map, int from,
                            int to) {
  TaughtPath out;
  out.world = path.world;
  const bool keys_match = path.key_images_m.size() == map.key_images.size();
  if (keys_match) {
    out.key_images_m.assign(path.key_images_m.begin() + from, path.key_images_m.begin() + to + 1);
  }
  // path_m has one position per frame the teach recorded, indexed as the key images' source
  // frames; a path that does not reach the last kept source frame is not this map's.
  const int64_t a = map.key_images[from].source_frame_index;
  const int64_t b = map.key_images[to].source_frame_index;
  if (a >= 0 && b >= a && static_cast<int64_t>(path.path_m.size()) > b) {
    out.path_m.assign(path.path_m.begin() + a, path.path_m.begin() + b + 1);
  } else {
    out.path_m = out.key_images_m;
  }
  return out;
}

}  // namespace pepper::app
