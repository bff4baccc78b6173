#include "evaluation/disturbance.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "evaluation/metrics.hpp"

namespace pepper::app::evaluation {
namespace {

constexpr double kDeg = M_PI / 180.0;

/// Distance from p to an oriented rectangle (0 inside).
double distance_to_rect(const Eigen::Vector2d& p, const Eigen::Vector2d& c,
                        const Eigen::Vector2d& half, double yaw) {
  const Eigen::Vector2d d = p - c;
  const double lx = std::cos(yaw) * d.x() + std::sin(yaw) * d.y();
  const double ly = -std::sin(yaw) * d.x() + std::cos(yaw) * d.y();
  const double ex = std::max(std::abs(lx) - half.x(), 0.0);
  const double ey = std::max(std::abs(ly) - half.y(), 0.0);
  return std::hypot(ex, ey);
}

/// The path resampled every 5 cm (clearance checks).
std::vector<Eigen::Vector2d> sample_path(const std::vector<Eigen::Vector2d>& path) {
  std::vector<Eigen::Vector2d> out;
  if (path.size() < 2) return path;
  const Polyline pl(path);
  for (double s = 0.0; s <= pl.length_m(); s += 0.05) out.push_back(pl.at(s));
  out.push_back(pl.at(pl.length_m()));
  return out;
}

double clearance(const std::vector<Eigen::Vector2d>& samples, const Eigen::Vector2d& c,
                 const Eigen::Vector2d& half, double yaw) {
  double m = std::numeric_limits<double>::infinity();
  for (const auto& p : samples) m = std::min(m, distance_to_rect(p, c, half, yaw));
  return m;
}

Eigen::Vector2d vec2(const YAML::Node& n) { return {n[0].as<double>(), n[1].as<double>()}; }

YAML::Node flow_pair(double a, double b) {
  YAML::Node n(YAML::NodeType::Sequence);
  n.push_back(a);
  n.push_back(b);
  n.SetStyle(YAML::EmitterStyle::Flow);
  return n;
}

/// Moves every box and table of the YAML tree (see DisturbanceOptions).
void move_furniture(YAML::Node root, const std::vector<Eigen::Vector2d>& samples,
                    const DisturbanceOptions& o, std::mt19937_64& rng,
                    std::vector<std::string>& notes) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (const char* list : {"boxes", "tables"}) {
    YAML::Node items = root[list];
    if (!items || !items.IsSequence()) continue;
    for (size_t i = 0; i < items.size(); ++i) {
      YAML::Node item = items[i];
      const std::string name = item["name"] ? item["name"].as<std::string>()
                                            : std::string(list) + "[" + std::to_string(i) + "]";
      const Eigen::Vector2d c = vec2(item["center"]);
      const Eigen::Vector2d half = 0.5 * vec2(item["size_m"]);
      const double yaw = (item["yaw_deg"] ? item["yaw_deg"].as<double>() : 0.0) * kDeg;
      const double dir = 2.0 * M_PI * u01(rng);
      const double len = o.furniture_shift_m * (0.5 + 0.5 * u01(rng));
      const double dyaw = o.furniture_yaw_deg * kDeg * (2.0 * u01(rng) - 1.0);
      const bool collides = (!item["collide"] || item["collide"].as<bool>()) &&
                            (!item["z_m"] || item["z_m"].as<double>() < 1.2);
      const double before = clearance(samples, c, half, yaw);
      double scale = 1.0;
      for (; scale > 0.2; scale *= 0.5) {
        const Eigen::Vector2d c2 = c + scale * len * Eigen::Vector2d(std::cos(dir), std::sin(dir));
        const double after = clearance(samples, c2, half, yaw + scale * dyaw);
        if (!collides || after >= std::min(before, o.min_path_clearance_m)) break;
      }
      if (scale <= 0.2) {
        notes.push_back("kept " + name + " in place (a move would block the taught path)");
        continue;
      }
      const Eigen::Vector2d c2 = c + scale * len * Eigen::Vector2d(std::cos(dir), std::sin(dir));
      item["center"] = flow_pair(c2.x(), c2.y());
      item["yaw_deg"] = (yaw + scale * dyaw) / kDeg;
      std::ostringstream os;
      os.precision(2);
      os << std::fixed << "moved " << name << " by " << scale * len << " m, turned by "
         << scale * dyaw / kDeg << " deg";
      notes.push_back(os.str());
    }
  }
}

/// The part of the taught path a person walks beside at `offset` (left > 0), every 5 cm, or
/// empty when it is not free: each point clear of the world by the person's 0.3 m and at least
/// 0.9 x |offset| from the whole path.
std::vector<Eigen::Vector2d> person_walk(const sim::World& world, const Polyline& pl, double s0,
                                         double s1, double offset) {
  std::vector<Eigen::Vector2d> walk;
  for (double s = s0; s <= s1 + 1e-9; s += 0.05) {
    const Eigen::Vector2d p = pl.at(s);
    // Direction smoothed over +-0.4 m: the walk rounds the outside of a corner.
    const Eigen::Vector2d ahead = pl.at(std::min(s + 0.4, pl.length_m()));
    const Eigen::Vector2d behind = pl.at(std::max(s - 0.4, 0.0));
    Eigen::Vector2d t = ahead - behind;
    if (t.norm() < 1e-9) continue;
    t.normalize();
    const Eigen::Vector2d q = p + offset * Eigen::Vector2d(-t.y(), t.x());
    // 0.3 m: the person's half-diagonal (0.45 x 0.3 m) plus a little. On the inside of a turn
    // the offset curve folds back across the path: every point must stay ~offset away from
    // the whole path, not only from its own foot point.
    if (world.collision(q, 0.3, 0.0)) return {};
    if (pl.project(q).distance_m < 0.9 * std::abs(offset)) return {};
    walk.push_back(q);
  }
  return walk.size() >= 2 ? walk : std::vector<Eigen::Vector2d>{};
}

/// Adds a person walking beside the taught path; returns false if no free place. Preferred:
/// the middle 25-65 % of the tour; where that is a corridor too narrow for a person beside the
/// robot (room_corridor_room), shorter stretches nearer the ends (the rooms).
bool add_person(YAML::Node root, const sim::World& world, const std::vector<Eigen::Vector2d>& path,
                const DisturbanceOptions& o, std::vector<std::string>& notes) {
  if (path.size() < 2) return false;
  const Polyline pl(path);
  const double len = pl.length_m();
  // The middle 40 %, then every 20 % stretch (5 % steps), nearest the middle first.
  std::vector<std::pair<double, double>> windows = {{0.25, 0.65}};
  std::vector<double> starts;
  for (int k = 0; k <= 16; ++k) starts.push_back(0.05 * k);
  std::stable_sort(starts.begin(), starts.end(), [](double a, double b) {
    return std::abs(a + 0.1 - 0.45) < std::abs(b + 0.1 - 0.45);
  });
  for (double a : starts) windows.emplace_back(a, a + 0.2);
  for (const auto& [f0, f1] : windows) {
    const double s0 = f0 * len, s1 = f1 * len;
    for (double offset : {o.person_offset_m, -o.person_offset_m, 0.85 * o.person_offset_m,
                          -0.85 * o.person_offset_m, 1.2 * o.person_offset_m,
                          -1.2 * o.person_offset_m}) {
      const std::vector<Eigen::Vector2d> walk = person_walk(world, pl, s0, s1, offset);
      if (walk.empty()) continue;
      // Every 5 cm sample is a vertex: coarser chords would cut the outside of a turn.
      YAML::Node pts(YAML::NodeType::Sequence);
      for (const auto& q : walk) pts.push_back(flow_pair(q.x(), q.y()));
      YAML::Node person;
      person["name"] = "evaluation_person";
      person["path"] = pts;
      person["speed_m_s"] = o.person_speed_m_s;
      person["texture"] = "evaluation_person";
      root["textures"]["evaluation_person"]["type"] = "noise";
      root["textures"]["evaluation_person"]["mean"] = 70;
      root["textures"]["evaluation_person"]["contrast"] = 30;
      root["textures"]["evaluation_person"]["feature_px"] = 24;
      root["textures"]["evaluation_person"]["seed"] = 4242;
      root["people"].push_back(person);
      std::ostringstream os;
      os.precision(2);
      os << std::fixed << "person walking " << (s1 - s0) << " m beside the path (from "
         << s0 << " m) at " << (offset > 0 ? "left " : "right ") << std::abs(offset) << " m, "
         << o.person_speed_m_s << " m/s";
      notes.push_back(os.str());
      return true;
    }
  }
  notes.push_back("no free side of the path for a walking person: not added");
  return false;
}


/// Unit normal (to the left) of the path at s, its direction smoothed over +-0.4 m.
Eigen::Vector2d path_normal(const Polyline& pl, double s) {
  Eigen::Vector2d t = pl.at(std::min(s + 0.4, pl.length_m())) - pl.at(std::max(s - 0.4, 0.0));
  if (t.norm() < 1e-9) return {0.0, 0.0};
  t.normalize();
  return {-t.y(), t.x()};
}

/// How far (<= max_m, 5 cm steps) a person can stand from the path point at s to one side
/// (side +1 left, -1 right) with nothing of the world within 0.3 m of it.
double room_beside(const sim::World& world, const Polyline& pl, double s, double side,
                   double max_m) {
  const Eigen::Vector2d p = pl.at(s);
  const Eigen::Vector2d n = path_normal(pl, s);
  double room = 0.0;
  for (double d = 0.05; d <= max_m + 1e-9; d += 0.05) {
    if (world.collision(p + side * d * n, 0.3, 0.0)) break;
    room = d;
  }
  return room;
}

/// One crowd walk: a zigzag over [s0, s0 + stretch] crossing the path `crossings` times,
/// starting on `side`; empty when a vertex has less than 0.35 m of room or a leg touches the
/// world (0.3 m clearance, every 5 cm).
std::vector<Eigen::Vector2d> crowd_walk(const sim::World& world, const Polyline& pl, double s0,
                                        double stretch, int crossings, double side,
                                        double offset_m) {
  constexpr double kMinRoom_m = 0.35;
  std::vector<Eigen::Vector2d> walk;
  for (int i = 0; i <= crossings; ++i) {
    const double s = s0 + stretch * i / crossings;
    const double sd = (i % 2 == 0) ? side : -side;
    const Eigen::Vector2d n = path_normal(pl, s);
    if (n.norm() < 0.5) return {};
    const double room = room_beside(world, pl, s, sd, offset_m);
    if (room < kMinRoom_m) return {};
    walk.push_back(pl.at(s) + sd * room * n);
  }
  for (size_t i = 1; i < walk.size(); ++i) {
    const Eigen::Vector2d a = walk[i - 1], b = walk[i];
    const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.05)));
    for (int k = 1; k < steps; ++k) {
      if (world.collision(a + (b - a) * k / steps, 0.3, 0.0)) return {};
    }
  }
  return walk;
}

/// Adds the crowd (DisturbanceOptions::crowd_*); `world` is the world the walks must stay
/// clear of (furniture already moved). Returns how many people were placed.
int add_crowd(YAML::Node root, const sim::World& world, const std::vector<Eigen::Vector2d>& path,
              const DisturbanceOptions& o, std::mt19937_64& rng,
              std::vector<std::string>& notes) {
  if (path.size() < 2 || o.crowd_people == 0) return 0;
  const Polyline pl(path);
  const double len = pl.length_m();
  const double stretch = std::min(o.crowd_stretch_m, 0.8 * len);
  const double s_lo = 0.1 * len, s_hi = len - stretch;
  if (s_hi < s_lo) {
    notes.push_back("the tour is too short for a crowd: not added");
    return 0;
  }
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const int n = o.crowd_people;
  int placed = 0;
  for (int k = 0; k < n; ++k) {
    // Draws first, so each person's draws do not depend on where the others found room.
    const double jitter = (u01(rng) - 0.5) * 0.5 * (s_hi - s_lo) / n;
    const double first_side = u01(rng) < 0.5 ? 1.0 : -1.0;
    const double speed = o.crowd_speed_min_m_s +
                         (o.crowd_speed_max_m_s - o.crowd_speed_min_m_s) * u01(rng);
    const double start_fraction = u01(rng);
    const double centre = s_lo + (s_hi - s_lo) * (k + 0.5) / n + jitter;
    std::vector<Eigen::Vector2d> walk;
    double s0 = centre;
    // Nearest free stretch to the planned one: 0.25 m steps either way, both first sides.
    for (int j = 0; j <= 2 * static_cast<int>(std::ceil((s_hi - s_lo) / 0.25)) && walk.empty();
         ++j) {
      const double shift = 0.25 * ((j + 1) / 2) * (j % 2 == 0 ? 1.0 : -1.0);
      s0 = centre + shift;
      if (s0 < s_lo - 1e-9 || s0 > s_hi + 1e-9) continue;
      for (const double side : {first_side, -first_side}) {
        walk = crowd_walk(world, pl, s0, stretch, o.crowd_crossings, side, o.crowd_offset_m);
        if (!walk.empty()) break;
      }
    }
    if (walk.empty()) {
      notes.push_back("crowd person " + std::to_string(k + 1) +
                      ": no room to cross the path anywhere: not added");
      continue;
    }
    double walk_len = 0.0;
    YAML::Node pts(YAML::NodeType::Sequence);
    for (size_t i = 0; i < walk.size(); ++i) {
      pts.push_back(flow_pair(walk[i].x(), walk[i].y()));
      if (i > 0) walk_len += (walk[i] - walk[i - 1]).norm();
    }
    const std::string name = "crowd_" + std::to_string(k + 1);
    YAML::Node texture = root["textures"][name];
    texture["type"] = "noise";
    texture["mean"] = 55 + 12 * (k % 5);  // clothes of different greys
    texture["contrast"] = 30;
    texture["feature_px"] = 24;
    texture["seed"] = 5000 + k;
    YAML::Node person;
    person["name"] = name;
    person["path"] = pts;
    person["speed_m_s"] = speed;
    person["start_offset_m"] = start_fraction * walk_len;
    person["keep_clear_m"] = o.crowd_keep_clear_m;
    person["texture"] = name;
    root["people"].push_back(person);
    ++placed;
    std::ostringstream os;
    os.precision(2);
    os << std::fixed << name << " crossing the path " << o.crowd_crossings << " times over "
       << stretch << " m from " << s0 << " m, " << speed << " m/s, keeping "
       << o.crowd_keep_clear_m << " m from the robot";
    notes.push_back(os.str());
  }
  return placed;
}

}  // namespace

const char* to_string(Disturbance d) {
  switch (d) {
    case Disturbance::kLight: return "light";
    case Disturbance::kFurniture: return "furniture";
    case Disturbance::kPerson: return "person";
    case Disturbance::kCrowd: return "crowd";
    case Disturbance::kDrops: return "drops";
    case Disturbance::kLatency: return "latency";
  }
  return "?";
}

std::string disturbance_label(const std::set<Disturbance>& disturbances) {
  std::string out;
  for (const Disturbance d : disturbances) {
    if (!out.empty()) out += '+';
    out += to_string(d);
  }
  return out.empty() ? "none" : out;
}

Disturbance parse_disturbance(const std::string& name) {
  for (Disturbance d : {Disturbance::kLight, Disturbance::kFurniture, Disturbance::kPerson,
                        Disturbance::kCrowd, Disturbance::kDrops, Disturbance::kLatency}) {
    if (name == to_string(d)) return d;
  }
  throw std::invalid_argument("unknown disturbance '" + name +
                              "' (light, furniture, person, crowd, drops, latency, none)");
}

std::vector<std::string> DisturbanceOptions::validate() const {
  std::vector<std::string> e;
  auto range = [&](const char* n, double v, double lo, double hi) {
    if (!(v >= lo && v <= hi)) {
      std::ostringstream os;
      os << "disturbance." << n << " = " << v << ": must be in [" << lo << ", " << hi << "]";
      e.push_back(os.str());
    }
  };
  if (light_factor != 0.0) range("light_factor", light_factor, 0.2, 3.0);
  range("light_factor_min", light_factor_min, 0.2, 3.0);
  range("light_factor_max", light_factor_max, light_factor_min, 3.0);
  range("furniture_shift_m", furniture_shift_m, 0.0, 2.0);
  range("furniture_yaw_deg", furniture_yaw_deg, 0.0, 90.0);
  range("min_path_clearance_m", min_path_clearance_m, 0.0, 2.0);
  range("person_offset_m", person_offset_m, 0.3, 3.0);
  range("person_speed_m_s", person_speed_m_s, 0.0, 2.0);
  if (!(crowd_people >= 0 && crowd_people <= 20)) {
    e.push_back("disturbance.crowd_people = " + std::to_string(crowd_people) +
                ": must be in [0, 20]");
  }
  if (!(crowd_crossings >= 1 && crowd_crossings <= 10)) {
    e.push_back("disturbance.crowd_crossings = " + std::to_string(crowd_crossings) +
                ": must be in [1, 10]");
  }
  range("crowd_stretch_m", crowd_stretch_m, 0.5, 20.0);
  range("crowd_offset_m", crowd_offset_m, 0.35, 3.0);
  range("crowd_speed_min_m_s", crowd_speed_min_m_s, 0.1, 2.0);
  range("crowd_speed_max_m_s", crowd_speed_max_m_s, crowd_speed_min_m_s, 2.0);
  range("crowd_keep_clear_m", crowd_keep_clear_m, 0.0, 3.0);
  range("drop_probability", drop_probability, 0.0, 0.9);
  range("latency_s", latency_s, 0.0, 2.0);
  return e;
}

const std::string& DisturbedWorld::lighting_of_run(int k) const {
  if (k >= 0 && static_cast<size_t>(k) < run_lighting.size()) return run_lighting[k];
  return lighting;
}

double DisturbedWorld::light_factor_of_run(int k) const {
  if (k >= 0 && static_cast<size_t>(k) < run_light_factors.size()) return run_light_factors[k];
  return light_factor;
}

namespace {

/// The world's declared window change between teach and replay (sun, blinds), 1 if none.
double window_change(const sim::World& world) {
  const sim::LightingCondition& teach = world.light("teach");
  const auto replay = world.lighting.find("replay");
  return replay != world.lighting.end() && teach.windows > 0.0
             ? replay->second.windows / teach.windows
             : 1.0;
}

}  // namespace

sim::LightingCondition scaled_lighting(const sim::World& world, double factor) {
  sim::LightingCondition l = world.light("teach");
  l.ambient *= factor;
  l.lamps *= factor;
  l.windows *= factor * window_change(world);
  return l;
}

DisturbedWorld make_disturbed_world(const std::shared_ptr<const sim::World>& world,
                                    const std::set<Disturbance>& disturbances,
                                    const DisturbanceOptions& options,
                                    const std::vector<Eigen::Vector2d>& taught_path_m,
                                    uint64_t seed, int runs) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument(errors.front());
  }
  DisturbedWorld out;
  out.world = world;
  const bool yaml_level = disturbances.count(Disturbance::kFurniture) ||
                          disturbances.count(Disturbance::kPerson) ||
                          disturbances.count(Disturbance::kCrowd);
  if (yaml_level) {
    if (world->source.empty()) {
      throw std::invalid_argument(
          "furniture/person/crowd disturbances need a world loaded from a file (World::source)");
    }
    YAML::Node root = YAML::LoadFile(world->source.string());
    std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 17);
    if (disturbances.count(Disturbance::kFurniture)) {
      move_furniture(root, sample_path(taught_path_m), options, rng, out.notes);
    }
    if (disturbances.count(Disturbance::kPerson)) {
      add_person(root, *world, taught_path_m, options, out.notes);
    }
    if (disturbances.count(Disturbance::kCrowd)) {
      // Its own generator: adding the crowd leaves the furniture's draws as they were.
      std::mt19937_64 crowd_rng(seed * 0x9E3779B97F4A7C15ull + 29);
      const bool moved = disturbances.count(Disturbance::kFurniture) > 0;
      std::optional<sim::World> furnished;  // the walks keep clear of the moved furniture
      if (moved) {
        YAML::Emitter em;
        em << root;
        furnished = sim::parse_world(em.c_str(), world->source.string() + " (moved furniture)",
                                     world->source.parent_path());
      }
      add_crowd(root, moved ? *furnished : *world, taught_path_m, options, crowd_rng, out.notes);
    }
    YAML::Emitter em;
    em << root;
    auto w = sim::parse_world(em.c_str(), world->source.string() + " (disturbed)",
                              world->source.parent_path());
    w.source = world->source;
    out.world = std::make_shared<const sim::World>(std::move(w));
  }
  if (disturbances.count(Disturbance::kLight)) {
    auto w = std::make_shared<sim::World>(*out.world);
    const double windows = window_change(*world);
    std::ostringstream os;
    if (options.light_factor != 0.0) {
      w->lighting["evaluation"] = scaled_lighting(*world, options.light_factor);
      out.lighting = "evaluation";
      out.light_factor = options.light_factor;
      os << "every light x" << options.light_factor;
    } else {
      const int n = std::max(runs, 1);
      for (int k = 0; k < n; ++k) {
        const double f = n == 1 ? options.light_factor_min
                                : options.light_factor_min +
                                      (options.light_factor_max - options.light_factor_min) * k /
                                          (n - 1);
        const std::string name = "evaluation_run_" + std::to_string(k + 1);
        w->lighting[name] = scaled_lighting(*world, f);
        out.run_lighting.push_back(name);
        out.run_light_factors.push_back(f);
      }
      os << "every light x" << options.light_factor_min << " to x" << options.light_factor_max
         << " over the " << n << " run(s), evenly spaced";
    }
    if (windows != 1.0) os << ", the world's window change x" << windows << " on top";
    out.notes.push_back(os.str());
    out.world = w;
  }
  if (disturbances.count(Disturbance::kDrops)) {
    std::ostringstream os;
    os << "WiFi frame drops p = " << options.drop_probability;
    out.notes.push_back(os.str());
  }
  if (disturbances.count(Disturbance::kLatency)) {
    std::ostringstream os;
    os << "command latency " << options.latency_s << " s";
    out.notes.push_back(os.str());
  }
  return out;
}

}  // namespace pepper::app::evaluation
