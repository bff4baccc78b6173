#include "session/taught_path.hpp"

#include <algorithm>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace pepper::app {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kFormat = "pepper-taught-path";
constexpr int kVersion = 1;

json points_to_json(const std::vector<Eigen::Vector2d>& points) {
  json a = json::array();
  for (const auto& p : points) a.push_back({p.x(), p.y()});
  return a;
}

std::vector<Eigen::Vector2d> points_from_json(const json& a) {
  std::vector<Eigen::Vector2d> out;
  for (const auto& p : a) {
    if (!p.is_array() || p.size() != 2) throw std::runtime_error("a position is not [x, y]");
    out.emplace_back(p.at(0).get<double>(), p.at(1).get<double>());
  }
  return out;
}

}  // namespace

void save_taught_path(const fs::path& map_dir, const TaughtPath& path) {
  const fs::path file = map_dir / kTaughtPathFile;
  const fs::path tmp = file.string() + ".tmp";
  const json j = {{"format", kFormat},
                  {"version", kVersion},
                  {"world", path.world},
                  {"path_m", points_to_json(path.path_m)},
                  {"key_images_m", points_to_json(path.key_images_m)}};
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << j.dump() << "\n";
    out.flush();
    if (!out) throw std::runtime_error(tmp.string() + ": cannot write");
  }
  std::error_code ec;
  fs::rename(tmp, file, ec);
  if (ec) throw std::runtime_error(file.string() + ": cannot rename into place: " + ec.message());
}

std::optional<TaughtPath> load_taught_path(const fs::path& map_dir) {
  const fs::path file = map_dir / kTaughtPathFile;
  if (!fs::exists(file)) return std::nullopt;
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot read");
  try {
    const json j = json::parse(in);
    if (j.at("format") != kFormat)
      throw std::runtime_error(std::string("format is not ") + kFormat);
    if (j.at("version") != kVersion) {
      throw std::runtime_error("version " + j.at("version").dump() + " (this build reads " +
                               std::to_string(kVersion) + ")");
    }
    TaughtPath p;
    p.world = j.at("world").get<std::string>();
    p.path_m = points_from_json(j.at("path_m"));
    p.key_images_m = points_from_json(j.at("key_images_m"));
    return p;
  } catch (const std::exception& e) {  // json errors and the checks above
    throw std::runtime_error(file.string() + ": not a taught path: " + e.what());
  }
}

double distance_to_path_m(const std::vector<Eigen::Vector2d>& path_m, const Eigen::Vector2d& p_m) {
  if (path_m.empty()) return std::numeric_limits<double>::quiet_NaN();
  double best = (p_m - path_m.front()).norm();
  for (std::size_t i = 1; i < path_m.size(); ++i) {
    const Eigen::Vector2d a = path_m[i - 1], ab = path_m[i] - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p_m - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (p_m - (a + t * ab)).norm());
  }
  return best;
}

}  // namespace pepper::app
