// Random plausible worlds (see world_generator.hpp; format in docs/mock_robot.md).
//
// How a world is drawn: first the taught tour, as a "turtle" path of straight legs and turns
// (on the spot: a polyline corner; on an arc: points every 15 degrees of a circle); then the
// space around it (a room rectangle, a corridor whose walls are the tour's centre line offset by
// half the width with mitred corners, or both joined by doorways); then the view at every turn
// and at the end is found by casting a ray from where the turn starts along the incoming heading:
// the wall piece it hits is kept blank (no poster, door, window or furniture around the hit, and
// a low-texture paint where the blank part is most of the piece) or, otherwise, gets a poster.
// Then windows, doors, posters, furniture and lamps fill the remaining free places, each accepted
// only if it keeps the tour clear. Finally the whole attempt is checked (walls do not cross, the
// polyline and the simulated teach drive keep their clearance) and written as YAML.
#include "sim/world_generator.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/base_velocity.hpp"
#include "sim/kinematics.hpp"
#include "sim/teach_driver.hpp"
#include "sim/world.hpp"

namespace pepper::sim {

namespace {

using Vec2 = Eigen::Vector2d;
constexpr double kDeg = M_PI / 180.0;
constexpr double kWallHalfThicknessM = 0.05;  // world files' default thickness_m 0.1
constexpr double kFrameWidthM = 0.08;
constexpr double kFrameHalfDepthM = 0.07;  // frame depth = wall thickness + 0.04
constexpr double kDoorwayWidthM = 1.3;     // where the tour crosses a wall: 0.65 m each side
constexpr double kArcStepRad = 15.0 * kDeg;
constexpr double kTeachSpeedMS = 0.25;
// Replay start perturbation: `pepper_app evaluate` draws +-0.3 m lateral by default and the
// world's along range; every perturbed start must keep a 0.3 m robot clear (checked).
constexpr double kPerturbLateralM = 0.3;
constexpr double kPerturbAlongM = 0.3;
constexpr double kRobotRadiusM = 0.3;

// An attempt that fails a check; the next attempt is drawn.
struct Reject {
  std::string why;
};

// SplitMix64: fixed output on every platform (std distributions are not specified exactly).
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(next() >> 11) * 0x1.0p-53);
  }
  int integer(int lo, int hi) {  // inclusive
    return lo + static_cast<int>(next() % static_cast<uint64_t>(hi - lo + 1));
  }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }
  double sign() { return chance(0.5) ? 1.0 : -1.0; }
  template <class T>
  const T& pick(const std::vector<T>& v) {
    return v[static_cast<size_t>(integer(0, static_cast<int>(v.size()) - 1))];
  }

 private:
  uint64_t state_;
};

Vec2 dir(double heading_rad) { return {std::cos(heading_rad), std::sin(heading_rad)}; }
Vec2 left_of(const Vec2& d) { return {-d.y(), d.x()}; }

double dist_point_segment(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 d = b - a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (a + t * d - p).norm();
}

double dist_point_box(const Vec2& p, const Vec2& c, const Vec2& half, double yaw) {
  const Vec2 d = p - c;
  const double cs = std::cos(yaw), sn = std::sin(yaw);
  const Vec2 local(cs * d.x() + sn * d.y(), -sn * d.x() + cs * d.y());
  return (local.cwiseAbs() - half).cwiseMax(0.0).norm();
}

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Proper crossing of two segments (touching at an end, or T-junctions, do not count).
bool segments_cross(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  constexpr double kEps = 1e-6;
  const double d1 = cross2(b - a, c - a), d2 = cross2(b - a, d - a);
  const double d3 = cross2(d - c, a - c), d4 = cross2(d - c, b - c);
  return ((d1 > kEps && d2 < -kEps) || (d1 < -kEps && d2 > kEps)) &&
         ((d3 > kEps && d4 < -kEps) || (d3 < -kEps && d4 > kEps));
}

// Ray from p along unit d against segment a-b: distance along the ray, or nullopt.
std::optional<double> ray_hit(const Vec2& p, const Vec2& d, const Vec2& a, const Vec2& b) {
  const Vec2 e = b - a;
  const double den = cross2(d, e);
  if (std::abs(den) < 1e-12) return std::nullopt;
  const double t = cross2(a - p, e) / den;
  const double u = cross2(a - p, d) / den;
  if (t > 1e-6 && u >= 0.0 && u <= 1.0) return t;
  return std::nullopt;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  std::string s = buf;
  if (s == "-0.000") s = "0.000";
  return s;
}
std::string pt(const Vec2& p) { return "[" + num(p.x()) + ", " + num(p.y()) + "]"; }

// ---------------------------------------------------------------------------------------------
// The draft of one attempt.

enum class FeatureKind { kOpening, kDoor, kWindow, kPoster };

struct Feature {
  FeatureKind kind = FeatureKind::kPoster;
  double at_m = 0.0;
  double width_m = 1.0;
  double height_m = 1.0;
  double sill_m = 0.0;    // windows
  double center_m = 1.5;  // posters
  std::string texture;
};

struct Interval {
  double s0, s1;
};

struct Wall {
  std::vector<Vec2> pts;
  std::string texture = "paint";
  bool space_left = true;  // which side the walkable space is on, seen along the polyline
  bool cap = false;        // a corridor end
  bool in_room = false;    // one of a room's four walls (else a corridor's)
  std::vector<Feature> features;
  std::vector<Interval> busy;   // features and tall furniture
  std::vector<Interval> blank;  // views at turns kept blank
  std::vector<Interval> shown;  // views at turns that get a poster

  bool straight() const { return pts.size() == 2; }
  double length() const {
    double len = 0.0;
    for (size_t i = 1; i < pts.size(); ++i) len += (pts[i] - pts[i - 1]).norm();
    return len;
  }
  Vec2 along() const { return (pts.back() - pts.front()).normalized(); }
  Vec2 inward() const { return space_left ? left_of(along()) : Vec2(-left_of(along())); }
  Vec2 point_at(double s) const { return pts.front() + s * along(); }
  bool free(double s0, double s1, double gap) const {
    if (s0 < 0.0 || s1 > length()) return false;
    for (const auto* list : {&busy, &blank})
      for (const Interval& i : *list)
        if (s0 < i.s1 + gap && i.s0 < s1 + gap) return false;
    return true;
  }
};

struct Box {
  std::string name;
  Vec2 c = Vec2::Zero();
  Eigen::Vector3d size_m = Eigen::Vector3d::Ones();  // along yaw, across, height
  double yaw_rad = 0.0;
  std::string texture, front, top;
  bool table = false;
  double tile_m = 1.0;
};

struct Lamp {
  Vec2 c;
  Vec2 size_m;
};

// A rectangle room in its own frame: origin + u * dir(yaw) + v * left, u0 <= u <= u1, ...
struct Room {
  Vec2 origin;
  double yaw_rad;
  double u0, u1, v0, v1;
  Vec2 to_world(double u, double v) const {
    return origin + u * dir(yaw_rad) + v * left_of(dir(yaw_rad));
  }
  Vec2 to_local(const Vec2& p) const {
    const Vec2 d = p - origin;
    return {d.dot(dir(yaw_rad)), d.dot(left_of(dir(yaw_rad)))};
  }
  bool inside(const Vec2& p, double margin) const {
    const Vec2 l = to_local(p);
    return l.x() >= u0 + margin && l.x() <= u1 - margin && l.y() >= v0 + margin &&
           l.y() <= v1 - margin;
  }
};

struct View {
  Vec2 from;
  double heading_rad;
  int turn;  // index into turns, or kEndView, kStartView
};
constexpr int kEndView = -1;
constexpr int kStartView = -2;

// The tour: straight legs and turns; segment i joins pts[i] and pts[i + 1].
struct Turtle {
  std::vector<Vec2> pts;
  std::vector<int> group;  // per segment: one id per leg, one per arc
  double heading_rad = 0.0;
  int next_group = 0;
  std::vector<GeneratedTurn> turns;
  std::vector<View> views;

  void start(const Vec2& p, double heading) {
    pts = {p};
    heading_rad = heading;
  }
  void straight(double len_m) {
    pts.push_back(pts.back() + len_m * dir(heading_rad));
    group.push_back(next_group++);
  }
  void turn(double angle_rad, bool arc, double radius_m) {
    views.push_back({pts.back(), heading_rad, static_cast<int>(turns.size())});
    turns.push_back({angle_rad / kDeg, arc, arc ? radius_m : 0.0, false});
    if (!arc) {
      heading_rad += angle_rad;
      return;
    }
    const double s = angle_rad > 0 ? 1.0 : -1.0;
    const Vec2 c = pts.back() + s * radius_m * left_of(dir(heading_rad));
    const int n = std::max(2, static_cast<int>(std::ceil(std::abs(angle_rad) / kArcStepRad)));
    const int g = next_group++;
    for (int k = 1; k <= n; ++k) {
      const double h = heading_rad + angle_rad * k / n;
      pts.push_back(c - s * radius_m * left_of(dir(h)));
      group.push_back(g);
      // Half way round an arc the camera sees a different wall: a second view.
      if (2 * k == n || (n % 2 == 1 && 2 * k == n + 1))
        views.push_back({pts.back(), h, static_cast<int>(turns.size()) - 1});
    }
    heading_rad += angle_rad;
  }
  double length() const {
    double len = 0.0;
    for (size_t i = 1; i < pts.size(); ++i) len += (pts[i] - pts[i - 1]).norm();
    return len;
  }
};

struct Draft {
  std::vector<Wall> walls;
  std::vector<Box> boxes;
  std::vector<Lamp> lamps;
  std::vector<Room> rooms;
  std::vector<Vec2> path;
  std::vector<GeneratedTurn> turns;
  std::vector<View> views;
  double ceiling_m = 2.6;
  double corridor_width_m = 0.0;
  bool poor_view = false;
  bool end_blank = false;
  std::vector<std::pair<Vec2, double>> doorways;  // centre, heading of the tour through it
  std::vector<std::string> ceiling_items;         // YAML flow mappings, one per fixture
};

// ---------------------------------------------------------------------------------------------
// Clearance model: the same obstacles as World::collision (wall pieces without the openings,
// frame jambs, furniture footprints), from the draft.

struct Obstacles {
  struct Seg {
    Vec2 a, b;
  };
  struct Rect {
    Vec2 c, half;
    double yaw;
  };
  std::vector<Seg> segs;
  std::vector<Rect> rects;

  double clearance(const Vec2& p) const {
    double d = 1e9;
    for (const Seg& s : segs) d = std::min(d, dist_point_segment(p, s.a, s.b) - kWallHalfThicknessM);
    for (const Rect& r : rects) d = std::min(d, dist_point_box(p, r.c, r.half, r.yaw));
    return d;
  }
};

Obstacles obstacles_of(const Draft& d, bool with_boxes) {
  Obstacles o;
  for (const Wall& w : d.walls) {
    if (!w.straight()) {
      for (size_t i = 1; i < w.pts.size(); ++i) o.segs.push_back({w.pts[i - 1], w.pts[i]});
      continue;
    }
    const Vec2 e = w.along();
    std::vector<Interval> holes;
    for (const Feature& f : w.features) {
      if (f.kind == FeatureKind::kPoster) continue;
      const double s0 = f.at_m - f.width_m / 2, s1 = f.at_m + f.width_m / 2;
      if (f.kind == FeatureKind::kOpening) holes.push_back({s0, s1});
      const double yaw = std::atan2(e.y(), e.x());
      for (double sc : {s0 - kFrameWidthM / 2, s1 + kFrameWidthM / 2})
        o.rects.push_back({w.point_at(sc), {kFrameWidthM / 2, kFrameHalfDepthM}, yaw});
    }
    std::sort(holes.begin(), holes.end(), [](auto& a, auto& b) { return a.s0 < b.s0; });
    double cursor = 0.0;
    for (const Interval& h : holes) {
      if (h.s0 > cursor) o.segs.push_back({w.point_at(cursor), w.point_at(h.s0)});
      cursor = h.s1;
    }
    if (w.length() > cursor) o.segs.push_back({w.point_at(cursor), w.pts.back()});
  }
  if (with_boxes)
    for (const Box& b : d.boxes)
      o.rects.push_back({b.c, {b.size_m.x() / 2, b.size_m.y() / 2}, b.yaw_rad});
  return o;
}

std::vector<Vec2> samples(const std::vector<Vec2>& path, double step_m) {
  std::vector<Vec2> out{path.front()};
  for (size_t i = 1; i < path.size(); ++i) {
    const double len = (path[i] - path[i - 1]).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / step_m)));
    for (int k = 1; k <= n; ++k) out.push_back(path[i - 1] + (path[i] - path[i - 1]) * k / n);
  }
  return out;
}

double path_clearance(const Obstacles& o, const std::vector<Vec2>& pts) {
  double d = 1e9;
  for (const Vec2& p : pts) d = std::min(d, o.clearance(p));
  return d;
}

// ---------------------------------------------------------------------------------------------
// Space around the tour.

// The four walls of a room, counter-clockwise (space on their left). `front` is the wall at
// u = u0 (index 3 below: from (u0, v1) to (u0, v0)); `back` the wall at u = u1.
void add_room_walls(Draft& d, const Room& r, const std::string& texture) {
  const Vec2 a = r.to_world(r.u0, r.v0), b = r.to_world(r.u1, r.v0), c = r.to_world(r.u1, r.v1),
             e = r.to_world(r.u0, r.v1);
  for (const auto& [p, q] : std::vector<std::pair<Vec2, Vec2>>{{a, b}, {b, c}, {c, e}, {e, a}}) {
    Wall w;
    w.pts = {p, q};
    w.texture = texture;
    w.space_left = true;
    w.in_room = true;
    d.walls.push_back(w);
  }
  d.rooms.push_back(r);
}

// Walls of a corridor along pts[first..last] of the turtle (half width w/2 each side, mitred).
void add_corridor_walls(Draft& d, const Turtle& t, size_t first, size_t last, double width_m,
                        bool cap_start, bool cap_end) {
  const double h = width_m / 2;
  std::vector<Vec2> L, R;
  for (size_t i = first; i <= last; ++i) {
    Vec2 n;
    double scale = 1.0;
    if (i == first) {
      n = left_of((t.pts[i + 1] - t.pts[i]).normalized());
    } else if (i == last) {
      n = left_of((t.pts[i] - t.pts[i - 1]).normalized());
    } else {
      const Vec2 n0 = left_of((t.pts[i] - t.pts[i - 1]).normalized());
      const Vec2 n1 = left_of((t.pts[i + 1] - t.pts[i]).normalized());
      n = n0 + n1;
      if (n.norm() < 1e-6) throw Reject{"a corridor turns back on the spot"};
      n.normalize();
      scale = 1.0 / n.dot(n0);
      if (scale > 3.0) throw Reject{"corridor corner too sharp for a mitre"};
    }
    L.push_back(t.pts[i] + h * scale * n);
    R.push_back(t.pts[i] - h * scale * n);
  }
  for (size_t k = 0; k + 1 < L.size(); ++k) {
    const Vec2 c = t.pts[first + k + 1] - t.pts[first + k];
    if ((L[k + 1] - L[k]).dot(c) <= 0.05 * c.norm() || (R[k + 1] - R[k]).dot(c) <= 0.05 * c.norm())
      throw Reject{"corridor leg shorter than its corners"};
  }
  // One wall entry per leg and per arc on each side.
  size_t k = 0;
  while (k + 1 < L.size()) {
    size_t m = k + 1;
    const int g = t.group[first + k];
    while (m + 1 < L.size() && t.group[first + m] == g) ++m;
    Wall wl, wr;
    wl.pts.assign(L.begin() + static_cast<long>(k), L.begin() + static_cast<long>(m) + 1);
    wr.pts.assign(R.begin() + static_cast<long>(k), R.begin() + static_cast<long>(m) + 1);
    wl.texture = wr.texture = "paint_corridor";
    wl.space_left = false;
    wr.space_left = true;
    d.walls.push_back(wl);
    d.walls.push_back(wr);
    k = m;
  }
  if (cap_start) {
    Wall w;
    w.pts = {L.front(), R.front()};
    w.space_left = true;
    w.cap = true;
    w.texture = "paint_corridor";
    d.walls.push_back(w);
  }
  if (cap_end) {
    Wall w;
    w.pts = {R.back(), L.back()};
    w.space_left = true;
    w.cap = true;
    w.texture = "paint_corridor";
    d.walls.push_back(w);
  }
}

// No part of a corridor comes near another part of it (beyond its own bends).
void check_corridor_separation(const Turtle& t, size_t first, size_t last, double width_m) {
  std::vector<Vec2> c(t.pts.begin() + static_cast<long>(first),
                      t.pts.begin() + static_cast<long>(last) + 1);
  const auto s = samples(c, 0.1);
  const double window = 2.7 * (width_m + 0.3);
  for (size_t i = 0; i < s.size(); ++i)
    for (size_t j = i + static_cast<size_t>(window / 0.1); j < s.size(); ++j)
      if ((s[i] - s[j]).norm() < width_m + 0.28) throw Reject{"corridor runs into itself"};
}

void check_walls_do_not_cross(const Draft& d) {
  std::vector<std::pair<Vec2, Vec2>> segs;
  for (const Wall& w : d.walls)
    for (size_t i = 1; i < w.pts.size(); ++i) segs.emplace_back(w.pts[i - 1], w.pts[i]);
  for (size_t i = 0; i < segs.size(); ++i)
    for (size_t j = i + 1; j < segs.size(); ++j)
      if (segments_cross(segs[i].first, segs[i].second, segs[j].first, segs[j].second))
        throw Reject{"walls cross"};
}

// A doorway where the tour crosses a room wall: the wall piece (a straight one) that the tour
// crosses gets an opening of kDoorwayWidthM centred on the crossing.
void add_doorway(Draft& d, size_t wall_index, const Vec2& at, double heading) {
  Wall& w = d.walls[wall_index];
  const double s = (at - w.pts.front()).dot(w.along());
  Feature f;
  f.kind = FeatureKind::kOpening;
  f.at_m = s;
  f.width_m = kDoorwayWidthM;
  f.height_m = 2.1;
  w.features.push_back(f);
  w.busy.push_back({s - kDoorwayWidthM / 2 - kFrameWidthM, s + kDoorwayWidthM / 2 + kFrameWidthM});
  d.doorways.emplace_back(at, heading);
}

// ---------------------------------------------------------------------------------------------
// The tour of each kind.

double draw_turn_deg(Rng& rng, bool allow_180) {
  static const std::vector<double> kAngles{45, 60, 90, 90, 120, 135, 180};
  double a;
  do a = rng.pick(kAngles);
  while (!allow_180 && a > 179);
  return a;
}

// Room kind: one room, a walk of 5 to 7 legs with turns inside it, >= 1.1 m from the walls (room
// for furniture along them).
void build_room_kind(Draft& d, Rng& rng) {
  const Room room{{0, 0}, 0.0, 0.0, rng.uniform(6.5, 11.0), 0.0, rng.uniform(5.5, 9.0)};
  add_room_walls(d, room, "paint");
  const double m = 1.1;
  for (int tries = 0; tries < 50; ++tries) {
    Turtle t;
    t.start(room.to_world(rng.uniform(m, room.u1 - m), rng.uniform(m, room.v1 - m)),
            rng.integer(0, 23) * 15.0 * kDeg);
    const int legs = rng.integer(5, 7);
    bool ok = true;
    for (int leg = 0; leg < legs && ok; ++leg) {
      bool placed = false;
      for (int k = 0; k < 40 && !placed; ++k) {
        Turtle c = t;
        if (leg > 0) {
          const double a = draw_turn_deg(rng, true) * kDeg * rng.sign();
          const bool arc = rng.chance(0.5);
          c.turn(a, arc, rng.uniform(0.5, 1.0));
        }
        c.straight(rng.uniform(1.2, 3.5));
        placed = std::all_of(c.pts.begin(), c.pts.end(),
                             [&](const Vec2& p) { return room.inside(p, m); });
        if (placed) t = c;
      }
      ok = placed;
    }
    if (!ok || t.length() < 10.0) continue;
    d.path = t.pts;
    d.turns = t.turns;
    d.views = t.views;
    d.views.push_back({t.pts.back(), t.heading_rad, kEndView});
    return;
  }
  throw Reject{"no walk fits the room"};
}

struct CorridorPlan {
  double width_m;
  std::vector<double> turn_rad;
  std::vector<bool> arc;
  std::vector<double> radius_m;
  std::vector<double> leg_m;
};

// Turns and legs of a corridor: on-the-spot turns up to 135 degrees, arcs of 45 to 180 degrees
// (a 180-degree bend goes round the end of a partition into the parallel corridor). Each leg is
// long enough for the mitred corners at both ends.
CorridorPlan plan_corridor(Rng& rng, int turns, double min_leg_m, double max_leg_m) {
  CorridorPlan p;
  p.width_m = rng.uniform(1.6, 2.4);
  const double h = p.width_m / 2;
  std::vector<double> trim{0.0};
  for (int i = 0; i < turns; ++i) {
    const double a = draw_turn_deg(rng, true);
    const bool arc = a > 179 || rng.chance(0.4);
    const double r = a > 179 ? h + rng.uniform(0.15, 0.3) : h + rng.uniform(0.3, 1.5);
    p.turn_rad.push_back(a * kDeg * rng.sign());
    p.arc.push_back(arc);
    p.radius_m.push_back(r);
    trim.push_back(arc ? 0.0 : h * std::tan(a * kDeg / 2));
  }
  trim.push_back(0.0);
  for (int i = 0; i <= turns; ++i)
    p.leg_m.push_back(std::max(rng.uniform(min_leg_m, max_leg_m), trim[i] + trim[i + 1] + 1.5));
  return p;
}

// Corridor kind: a corridor of 3 or 4 legs with closed ends; the tour starts and ends 1 m from
// the end walls.
void build_corridor_kind(Draft& d, Rng& rng) {
  const CorridorPlan p = plan_corridor(rng, rng.integer(2, 3), 4.0, 8.0);
  d.corridor_width_m = p.width_m;
  Turtle t;
  t.start({0.0, 0.0}, rng.integer(0, 7) * 45.0 * kDeg);
  for (size_t i = 0; i < p.leg_m.size(); ++i) {
    t.straight(p.leg_m[i]);
    if (i < p.turn_rad.size()) t.turn(p.turn_rad[i], p.arc[i], p.radius_m[i]);
  }
  check_corridor_separation(t, 0, t.pts.size() - 1, p.width_m);
  add_corridor_walls(d, t, 0, t.pts.size() - 1, p.width_m, true, true);
  // The tour: the centre line without the metre next to each end wall.
  d.path = t.pts;
  const Vec2 d0 = (d.path[1] - d.path[0]).normalized();
  const size_t n = d.path.size();
  const Vec2 d1 = (d.path[n - 1] - d.path[n - 2]).normalized();
  d.path.front() += 1.0 * d0;
  d.path.back() -= 1.0 * d1;
  d.turns = t.turns;
  d.views = t.views;
  d.views.push_back({d.path.back(), t.heading_rad, kEndView});
}

// Building kind: room A, a doorway, a corridor of 2 or 3 legs, a doorway, room B. Each room is
// aligned with the corridor leg it opens on; the tour starts in room A with a turn towards the
// doorway and ends in room B after one or two turns.
void build_building_kind(Draft& d, Rng& rng) {
  const CorridorPlan p = plan_corridor(rng, rng.integer(1, 2), 4.0, 7.0);
  d.corridor_width_m = p.width_m;
  const double h = p.width_m / 2;
  const double h0 = rng.integer(0, 3) * 90.0 * kDeg;

  // Room A behind the corridor's start C0 = (0, 0): u in [-depth, 0], the doorway at v = 0.
  const double wa = rng.uniform(std::max(5.0, p.width_m + 2.0), 9.0);
  const double va = rng.uniform(h + 0.5, wa - h - 0.5);
  const Room ra{{0, 0}, h0, -rng.uniform(4.5, 7.0), 0.0, -va, wa - va};
  // Its first turn: drawn from the origin, then moved so that it ends on the doorway's axis.
  const double qa = rng.uniform(1.5, -ra.u0 - 1.2);
  const double a0 = draw_turn_deg(rng, false) * kDeg * rng.sign();
  const bool arc0 = rng.chance(0.5);
  const double r0 = rng.uniform(0.5, 1.0);
  const double l0 = rng.uniform(1.5, 3.0);
  Turtle dry;
  dry.start({0, 0}, h0 - a0);
  dry.straight(l0);
  dry.turn(a0, arc0, r0);
  const Vec2 q = ra.to_world(-qa, 0.0);
  Turtle t;
  t.start(q - dry.pts.back(), h0 - a0);
  t.straight(l0);
  t.turn(a0, arc0, r0);
  for (const Vec2& pt : t.pts)
    if (!ra.inside(pt, 1.0)) throw Reject{"room A's first leg leaves the room"};
  t.straight(qa);
  const size_t c0 = t.pts.size() - 1;
  for (size_t i = 0; i < p.leg_m.size(); ++i) {
    t.straight(p.leg_m[i]);
    if (i < p.turn_rad.size()) t.turn(p.turn_rad[i], p.arc[i], p.radius_m[i]);
  }
  const size_t c1 = t.pts.size() - 1;
  const double hn = t.heading_rad;
  const Vec2 e = t.pts[c1];
  check_corridor_separation(t, c0, c1, p.width_m);

  // Room B beyond the corridor's end E: u in [0, depth] along the last leg.
  const double wb = rng.uniform(std::max(5.0, p.width_m + 2.0), 9.0);
  const double vb = rng.uniform(h + 0.5, wb - h - 0.5);
  const Room rb{e, hn, 0.0, rng.uniform(4.5, 7.0), -vb, wb - vb};
  t.straight(rng.uniform(1.5, rb.u1 - 1.2));
  const int room_turns = rng.integer(1, 2);
  for (int k = 0; k < room_turns; ++k) {
    bool placed = false;
    for (int tries = 0; tries < 40 && !placed; ++tries) {
      Turtle c = t;
      c.turn(draw_turn_deg(rng, k > 0) * kDeg * rng.sign(), rng.chance(0.5), rng.uniform(0.5, 1.0));
      c.straight(rng.uniform(1.2, 3.0));
      placed = std::all_of(c.pts.begin() + static_cast<long>(c1) + 1, c.pts.end(),
                           [&](const Vec2& pt) { return rb.inside(pt, 1.0); });
      if (placed) t = c;
    }
    if (!placed) {
      if (k == 0) throw Reject{"no turn fits room B"};
      break;
    }
  }

  // Rooms do not overlap each other or the corridor.
  for (const Room* r : {&ra, &rb}) {
    std::vector<Vec2> c(t.pts.begin() + static_cast<long>(c0), t.pts.begin() + static_cast<long>(c1) + 1);
    for (const Vec2& s : samples(c, 0.1)) {
      const Vec2 l = r->to_local(s);
      const double du = std::max({r->u0 - l.x(), l.x() - r->u1, 0.0});
      const double dv = std::max({r->v0 - l.y(), l.y() - r->v1, 0.0});
      const bool at_door = (s - t.pts[c0]).norm() < h + 0.3 || (s - e).norm() < h + 0.3;
      if (!at_door && std::hypot(du, dv) < h + 0.3) throw Reject{"corridor runs into a room"};
    }
  }
  for (const Vec2& pt : {ra.to_world(ra.u0, ra.v0), ra.to_world(ra.u1, ra.v0),
                         ra.to_world(ra.u1, ra.v1), ra.to_world(ra.u0, ra.v1)})
    if (rb.inside(pt, -0.3)) throw Reject{"rooms overlap"};
  for (const Vec2& pt : {rb.to_world(rb.u0, rb.v0), rb.to_world(rb.u1, rb.v0),
                         rb.to_world(rb.u1, rb.v1), rb.to_world(rb.u0, rb.v1)})
    if (ra.inside(pt, -0.3)) throw Reject{"rooms overlap"};

  add_room_walls(d, ra, "paint");
  add_doorway(d, d.walls.size() - 3, t.pts[c0], h0);  // wall at u = u1 = 0
  add_room_walls(d, rb, "paint_b");
  add_doorway(d, d.walls.size() - 1, e, hn);  // wall at u = u0 = 0
  add_corridor_walls(d, t, c0, c1, p.width_m, false, false);
  d.path = t.pts;
  d.turns = t.turns;
  d.views = t.views;
  d.views.push_back({t.pts.back(), t.heading_rad, kEndView});
}

// ---------------------------------------------------------------------------------------------
// Views, features, furniture, lamps.

struct PosterKind {
  const char* texture;
  double aspect;  // height / width
};
const std::vector<PosterKind> kPosters{{"pepper_a", 0.75}, {"pepper_b", 0.75}, {"pepper_c", 0.75},
                                       {"pepper_d", 0.75}, {"pepper_e", 0.75}, {"klimt", 1.0},
                                       {"solvay", 0.68},   {"grid", 0.75},     {"board", 1.3},
                                       {"notices", 1.4}};

bool add_poster(Wall& w, Rng& rng, double at_m, double gap) {
  const PosterKind& k = rng.pick(kPosters);
  const double width = rng.uniform(0.6, 1.3);
  const double height = std::min(1.0, width * k.aspect);
  if (!w.free(at_m - width / 2, at_m + width / 2, gap)) return false;
  Feature f;
  f.kind = FeatureKind::kPoster;
  f.at_m = at_m;
  f.width_m = width;
  f.height_m = height;
  f.center_m = rng.uniform(1.4, 1.65);
  f.texture = k.texture;
  w.features.push_back(f);
  w.busy.push_back({at_m - width / 2, at_m + width / 2});
  return true;
}

// The wall each view faces: blank around the hit, or a poster on it.
void shape_views(Draft& d, Rng& rng, double blank_prob) {
  for (View& v : d.views) {
    const Vec2 dv = dir(v.heading_rad);
    double best = 1e9;
    int wi = -1;
    size_t seg = 0;
    for (size_t i = 0; i < d.walls.size(); ++i)
      for (size_t k = 1; k < d.walls[i].pts.size(); ++k)
        if (auto t = ray_hit(v.from, dv, d.walls[i].pts[k - 1], d.walls[i].pts[k]);
            t && *t < best) {
          best = *t;
          wi = static_cast<int>(i);
          seg = k;
        }
    if (wi < 0) throw Reject{"a view sees no wall"};
    Wall& w = d.walls[static_cast<size_t>(wi)];
    double s_hit = 0.0;
    for (size_t k = 1; k < seg; ++k) s_hit += (w.pts[k] - w.pts[k - 1]).norm();
    s_hit += (v.from + best * dv - w.pts[seg - 1]).norm();
    // What the top camera (about 57 degrees wide) sees of that wall from about a metre before
    // the turn; capped so that a far wall in a room is not emptied as a whole.
    const double half = std::min(2.0, 0.55 * best + 0.5);
    const Interval zone{s_hit - half, s_hit + half};
    if (v.turn == kStartView) {
      // The first view of the tour is never blank (a replay must be able to start): a poster
      // goes up at once, before any blank zone can exclude it. (A corridor's start looks along
      // the corridor, whose side walls are in view: its far wall stays free to be blank.)
      if (!w.straight() || d.rooms.empty()) continue;
      const double c = std::clamp(s_hit, 0.8, std::max(0.8, w.length() - 0.8));
      for (double off : {0.0, -0.5, 0.5, -1.0, 1.0})
        if (add_poster(w, rng, c + off, 0.3)) break;
      continue;
    }
    bool blank = d.poor_view || rng.chance(blank_prob);
    for (const Feature& f : w.features)  // what is already there stays in view
      blank = blank && !(f.at_m - f.width_m / 2 < zone.s1 && zone.s0 < f.at_m + f.width_m / 2);
    if (v.turn >= 0) d.turns[static_cast<size_t>(v.turn)].faces_blank |= blank;
    if (v.turn == kEndView && blank) d.end_blank = true;
    if (blank) {
      w.blank.push_back(zone);
      // Corridor ends, bends and short walls across a corner: the whole piece in flat paint.
      if (!w.straight() || w.cap || (w.length() < 5.0 && zone.s1 - zone.s0 > 0.7 * w.length()))
        w.texture = "blank";
    } else {
      w.shown.push_back(zone);
    }
  }
  // A turn whose view is blank at the start and shown half way round is still called blank;
  // posters go up only after every blank zone is known.
  for (Wall& w : d.walls) {
    if (!w.straight()) continue;
    for (const Interval& z : w.shown) {
      const double c = std::clamp(0.5 * (z.s0 + z.s1), 0.8, std::max(0.8, w.length() - 0.8));
      for (double off : {0.0, -0.5, 0.5, -1.0, 1.0})
        if (add_poster(w, rng, c + off, 0.3)) break;
    }
  }
}

void add_wall_features(Draft& d, Rng& rng) {
  for (Wall& w : d.walls) {
    if (!w.straight()) continue;
    const double len = w.length();
    const bool room_wall = w.in_room;
    // Windows on room walls, sometimes on a corridor's wall (daylight, a bright blank).
    if (len > 3.0 && rng.chance(room_wall ? 0.45 : 0.15)) {
      const int n = rng.integer(1, std::max(1, static_cast<int>(len / 3.5)));
      for (int i = 0; i < n; ++i) {
        const double width = rng.uniform(1.2, 1.8);
        const double at = rng.uniform(width / 2 + 0.4, len - width / 2 - 0.4);
        if (!w.free(at - width / 2 - kFrameWidthM, at + width / 2 + kFrameWidthM, 0.3)) continue;
        Feature f;
        f.kind = FeatureKind::kWindow;
        f.at_m = at;
        f.width_m = width;
        f.sill_m = 0.9;
        f.height_m = rng.uniform(1.1, 1.4);
        f.texture = "window";
        w.features.push_back(f);
        w.busy.push_back({at - width / 2 - kFrameWidthM, at + width / 2 + kFrameWidthM});
      }
    }
    // Closed doors: offices along a corridor, one or two per room.
    if (len > 2.0 && rng.chance(room_wall ? 0.3 : 0.6)) {
      const int n = room_wall ? 1 : rng.integer(1, std::max(1, static_cast<int>(len / 4.0)));
      for (int i = 0; i < n; ++i) {
        const double at = rng.uniform(0.9, len - 0.9);
        if (!w.free(at - 0.45 - kFrameWidthM, at + 0.45 + kFrameWidthM, 0.3)) continue;
        Feature f;
        f.kind = FeatureKind::kDoor;
        f.at_m = at;
        f.width_m = 0.9;
        f.height_m = 2.05;
        f.texture = rng.chance(0.5) ? "door" : "door_light";
        w.features.push_back(f);
        w.busy.push_back({at - 0.45 - kFrameWidthM, at + 0.45 + kFrameWidthM});
      }
    }
    // Posters: about one every 3 m.
    const int n = static_cast<int>(len / 3.0) + (rng.chance(0.5) ? 1 : 0);
    for (int i = 0; i < n; ++i) add_poster(w, rng, rng.uniform(0.6, len - 0.6), 0.4);
  }
}

struct FurnitureKind {
  const char* name;
  double depth_lo, depth_hi, len_lo, len_hi, h_lo, h_hi;
  const char* texture;
  const char* front;
  const char* top;
  bool tall;  // hides the wall behind (no poster there)
};
const std::vector<FurnitureKind> kRoomFurniture{
    {"shelf", 0.35, 0.45, 0.9, 1.8, 1.8, 2.0, "shelf", "books", "shelf", true},
    {"cabinet", 0.45, 0.55, 0.8, 1.3, 1.0, 1.25, "metal", "cabinet", "desk", false},
    {"crate", 0.5, 0.8, 0.5, 0.8, 0.5, 0.8, "desk", "", "", false},
    {"plant", 0.45, 0.55, 0.45, 0.55, 1.0, 1.4, "foliage", "", "", false},
    {"rack", 0.45, 0.55, 1.2, 1.8, 1.4, 1.7, "metal", "stripes", "metal", true}};
const std::vector<FurnitureKind> kCorridorFurniture{
    {"bench", 0.4, 0.45, 1.2, 1.6, 0.45, 0.45, "stripes", "", "", false},
    {"bin", 0.35, 0.35, 0.35, 0.35, 0.8, 0.8, "cabinet", "", "", false},
    {"plant", 0.45, 0.5, 0.45, 0.5, 1.0, 1.3, "foliage", "", "", false}};

bool boxes_overlap(const Box& a, const Box& b, double gap) {
  // Separating axis test of two oriented rectangles, each grown by gap / 2.
  auto corners = [gap](const Box& x) {
    const Vec2 ex = dir(x.yaw_rad), ey = left_of(ex);
    const double hx = x.size_m.x() / 2 + gap / 2, hy = x.size_m.y() / 2 + gap / 2;
    return std::vector<Vec2>{x.c + hx * ex + hy * ey, x.c - hx * ex + hy * ey,
                             x.c - hx * ex - hy * ey, x.c + hx * ex - hy * ey};
  };
  const auto ca = corners(a), cb = corners(b);
  for (const Box* x : {&a, &b})
    for (const Vec2& axis : {dir(x->yaw_rad), left_of(dir(x->yaw_rad))}) {
      double a0 = 1e9, a1 = -1e9, b0 = 1e9, b1 = -1e9;
      for (const Vec2& p : ca) a0 = std::min(a0, p.dot(axis)), a1 = std::max(a1, p.dot(axis));
      for (const Vec2& p : cb) b0 = std::min(b0, p.dot(axis)), b1 = std::max(b1, p.dot(axis));
      if (a1 < b0 || b1 < a0) return false;
    }
  return true;
}

bool box_clear_of_tour(const Draft& d, const Box& b, const std::vector<Vec2>& tour,
                       double clearance_m) {
  for (const Vec2& p : tour)
    if (dist_point_box(p, b.c, b.size_m.head<2>() / 2, b.yaw_rad) < clearance_m) return false;
  for (const auto& [c, h] : d.doorways)  // keep the approach to a doorway free
    if (dist_point_box(c, b.c, b.size_m.head<2>() / 2, b.yaw_rad) < 1.2) return false;
  for (const Box& o : d.boxes)
    if (boxes_overlap(b, o, 0.1)) return false;
  return true;
}

void add_furniture(Draft& d, Rng& rng, const std::vector<Vec2>& tour, double clearance_m) {
  int count = 0;
  for (Wall& w : d.walls) {
    if (!w.straight() || w.cap) continue;
    const bool room_wall = w.in_room;
    const auto& pool = room_wall ? kRoomFurniture : kCorridorFurniture;
    const int tries = static_cast<int>(w.length() / (room_wall ? 1.5 : 3.0));
    for (int i = 0; i < tries; ++i) {
      const FurnitureKind& k = rng.pick(pool);
      Box b;
      b.name = std::string(k.name) + "_" + std::to_string(count);
      b.size_m = {rng.uniform(k.depth_lo, k.depth_hi), rng.uniform(k.len_lo, k.len_hi),
                  rng.uniform(k.h_lo, k.h_hi)};
      const double len = w.length();
      const double margin = b.size_m.y() / 2 + b.size_m.x() + 0.15;  // clear of the corners
      if (len < 2 * margin) continue;
      const double at = rng.uniform(margin, len - margin);
      const double s0 = at - b.size_m.y() / 2, s1 = at + b.size_m.y() / 2;
      // Never in front of a door, window or doorway, nor in a view kept blank; a tall piece
      // not in front of a poster either.
      bool ok = w.free(s0, s1, 0.2) || (!k.tall && [&] {
        for (const Interval& z : w.blank)
          if (s0 < z.s1 && z.s0 < s1) return false;
        for (const Feature& f : w.features)
          if (f.kind != FeatureKind::kPoster && s0 < f.at_m + f.width_m / 2 + 0.2 &&
              f.at_m - f.width_m / 2 - 0.2 < s1)
            return false;
        return true;
      }());
      if (!ok) continue;
      const Vec2 n = w.inward();
      b.yaw_rad = std::atan2(n.y(), n.x());
      b.c = w.point_at(at) + n * (b.size_m.x() / 2 + kWallHalfThicknessM + 0.02);
      b.texture = k.texture;
      b.front = k.front;
      b.top = k.top;
      b.tile_m = std::max(0.4, b.size_m.z());
      if (!box_clear_of_tour(d, b, tour, clearance_m)) continue;
      d.boxes.push_back(b);
      if (k.tall) w.busy.push_back({s0, s1});
      ++count;
    }
  }
  // Tables in the open part of the rooms (kept out of a blank view's line of sight).
  for (const Room& r : d.rooms) {
    const int n = rng.integer(0, 3);
    for (int i = 0; i < n; ++i) {
      Box b;
      b.table = true;
      b.name = "table_" + std::to_string(count);
      b.size_m = {rng.uniform(1.2, 1.8), rng.uniform(0.7, 0.9), 0.74};
      b.yaw_rad = r.yaw_rad + (rng.chance(0.5) ? 0.0 : 90.0 * kDeg);
      b.c = r.to_world(rng.uniform(r.u0, r.u1), rng.uniform(r.v0, r.v1));
      b.texture = "desk";
      const double reach = b.size_m.head<2>().norm() / 2;
      if (!r.inside(b.c, reach + 0.3)) continue;
      bool in_view = false;
      for (const View& v : d.views) {
        if (v.turn >= 0 && !d.turns[static_cast<size_t>(v.turn)].faces_blank) continue;
        if (v.turn == kEndView && !d.end_blank) continue;
        if (v.turn == kStartView) continue;
        if (dist_point_segment(b.c, v.from, v.from + 6.0 * dir(v.heading_rad)) < reach + 0.8)
          in_view = true;
      }
      if (in_view || !box_clear_of_tour(d, b, tour, clearance_m)) continue;
      d.boxes.push_back(b);
      ++count;
    }
  }
}

void add_lamps(Draft& d) {
  for (const Room& r : d.rooms) {
    const bool along_u = std::abs(std::cos(r.yaw_rad)) > 0.5;
    for (double u = r.u0 + 1.5; u < r.u1 - 1.0; u += 2.5)
      for (double v = r.v0 + 1.5; v < r.v1 - 1.0; v += 2.5)
        d.lamps.push_back({r.to_world(u, v), along_u ? Vec2(1.2, 0.3) : Vec2(0.3, 1.2)});
  }
  if (d.corridor_width_m > 0.0) {
    // Along the tour's straight parts that lie in the corridor (outside the rooms).
    double since = 1.5;
    for (size_t i = 1; i < d.path.size(); ++i) {
      const Vec2 a = d.path[i - 1], b = d.path[i];
      const Vec2 e = (b - a).normalized();
      const double len = (b - a).norm();
      for (double s = 0.0; s < len; s += 0.25) {
        since += 0.25;
        const Vec2 p = a + s * e;
        bool in_room = false;
        for (const Room& r : d.rooms) in_room |= r.inside(p, -0.2);
        if (in_room || since < 3.0) continue;
        since = 0.0;
        const bool diag = std::abs(std::abs(e.x()) - std::abs(e.y())) < 0.4;
        d.lamps.push_back({p, diag ? Vec2(0.6, 0.6)
                                   : (std::abs(e.x()) > std::abs(e.y()) ? Vec2(1.2, 0.3)
                                                                        : Vec2(0.3, 1.2))});
      }
    }
  }
}

// Ceiling fixtures (docs/mock_robot.md "Ceiling items"): what makes a ceiling something a
// pitched-up camera can localise on (issue 24). Drawn with their own generator after the attempt
// passed its checks, so the rest of a seed's world is what it was before they existed; nothing
// here changes the tour or its clearances (whatever hangs stays above 2 m).
constexpr double kCeilingTileM = 0.6;  // the ceiling texture's tile (its grid starts at 0, 0)
// Places drawn per fixture before giving it up: a narrow corridor has little room beside its lamps.
constexpr int kCeilingTries = 20;

double wall_distance(const Draft& d, const Vec2& p) {
  double dist = 1e9;
  for (const Wall& w : d.walls)
    for (size_t i = 1; i < w.pts.size(); ++i)
      dist = std::min(dist, dist_point_segment(p, w.pts[i - 1], w.pts[i]));
  return dist;
}

// Centre of the ceiling tile that holds p.
Vec2 tile_centre(const Vec2& p) {
  return {(std::floor(p.x() / kCeilingTileM) + 0.5) * kCeilingTileM,
          (std::floor(p.y() / kCeilingTileM) + 0.5) * kCeilingTileM};
}

void add_ceiling_items(Draft& d, Rng& rng) {
  struct Disc {
    Vec2 c;
    double r;
  };
  std::vector<Disc> taken;  // flat fixtures and lamps must not overlap (one would hide the other)
  for (const Lamp& l : d.lamps) taken.push_back({l.c, 0.5 * l.size_m.norm()});
  auto free_at = [&](const Vec2& c, double r) {
    if (wall_distance(d, c) < r + 0.05) return false;
    for (const Disc& t : taken)
      if ((t.c - c).norm() < t.r + r + 0.05) return false;
    return true;
  };
  const double H = d.ceiling_m;
  auto flat = [&](const char* kind, const Vec2& c, const Vec2& size, double yaw_deg,
                  const std::string& texture) {
    const double r = 0.5 * size.norm();
    if (!free_at(c, r)) return false;
    taken.push_back({c, r});
    d.ceiling_items.push_back(std::string("{kind: ") + kind + ", center: " + pt(c) +
                              ", size_m: " + pt(size) + ", yaw_deg: " + num(yaw_deg) +
                              ", texture: " + texture + "}");
    return true;
  };
  auto small = [&](const char* kind, const Vec2& c, const std::string& texture) {
    const double r = std::string(kind) == "sprinkler" ? 0.05 : 0.09;
    if (!free_at(c, r)) return false;
    taken.push_back({c, r});
    d.ceiling_items.push_back(std::string("{kind: ") + kind + ", center: " + pt(c) +
                              ", texture: " + texture + "}");
    return true;
  };
  static const std::vector<std::string> kTileTextures{"ceiling_plenum", "ceiling_stained",
                                                      "ceiling_new"};
  // Sprinklers about one per 3 m^2, a detector per 12 m^2, a vent per 8 m^2, an odd tile per
  // 6 m^2: drawn where they fit, at random places, so no two stretches of ceiling look alike.
  auto fill = [&](const std::function<Vec2()>& draw, double area_m2) {
    for (int i = 0, n = static_cast<int>(area_m2 / 3.0) + 1; i < n; ++i)
      for (int tries = 0; tries < kCeilingTries && !small("sprinkler", draw(), "ceiling_metal"); ++tries) {}
    for (int i = 0, n = static_cast<int>(area_m2 / 12.0) + 1; i < n; ++i)
      for (int tries = 0; tries < kCeilingTries && !small("detector", draw(), "ceiling_white"); ++tries) {}
    for (int i = 0, n = static_cast<int>(area_m2 / 8.0) + 1; i < n; ++i) {
      const bool square = rng.chance(0.5);
      const Vec2 size = square ? Vec2(0.6, 0.6) : Vec2(rng.uniform(0.6, 1.2), 0.3);
      const double yaw = rng.chance(0.5) ? 0.0 : 90.0;
      for (int tries = 0; tries < kCeilingTries; ++tries)
        if (flat("vent", draw(), size, yaw, square ? "ceiling_grille" : "ceiling_vent")) break;
    }
    for (int i = 0, n = static_cast<int>(area_m2 / 6.0) + 1; i < n; ++i) {
      const std::string& tex = rng.pick(kTileTextures);
      for (int tries = 0; tries < kCeilingTries; ++tries)
        if (flat("tile", tile_centre(draw()), {kCeilingTileM, kCeilingTileM}, 0.0, tex)) break;
    }
  };
  for (const Room& r : d.rooms) {
    // Half of the rooms have a beam across their shorter side, between two rows of lamps.
    const bool along_v = r.u1 - r.u0 > r.v1 - r.v0;
    if (rng.chance(0.5)) {
      const double lo = along_v ? r.u0 : r.v0, hi = along_v ? r.u1 : r.v1;
      const double at = std::clamp(lo + 2.75 + 2.5 * rng.integer(0, 2), lo + 1.0, hi - 1.0);
      const Vec2 a = along_v ? r.to_world(at, r.v0) : r.to_world(r.u0, at);
      const Vec2 b = along_v ? r.to_world(at, r.v1) : r.to_world(r.u1, at);
      const double width = rng.uniform(0.2, 0.35);
      d.ceiling_items.push_back("{kind: beam, from: " + pt(a) + ", to: " + pt(b) +
                                ", width_m: " + num(width) + ", depth_m: " +
                                num(rng.uniform(0.15, 0.3)) + ", texture: ceiling_beam}");
      for (double s = 0.0; s <= 1.0; s += 0.05) taken.push_back({a + s * (b - a), width / 2});
    }
    fill([&] { return r.to_world(rng.uniform(r.u0 + 0.3, r.u1 - 0.3),
                                 rng.uniform(r.v0 + 0.3, r.v1 - 0.3)); },
         (r.u1 - r.u0) * (r.v1 - r.v0));
  }
  if (d.corridor_width_m > 0.0) {
    // Along the tour's parts in the corridor, within its width.
    std::vector<Vec2> corridor;
    for (const Vec2& p : samples(d.path, 0.25)) {
      bool in_room = false;
      for (const Room& r : d.rooms) in_room |= r.inside(p, -0.2);
      if (!in_room) corridor.push_back(p);
    }
    if (!corridor.empty()) {
      // A point near a centre-line sample, kept only within the half width (less 0.2 m) of the
      // centre line: beyond it lies a wall, a partition or the space outside.
      const double half = d.corridor_width_m / 2 - 0.2;
      auto draw = [&] {
        const int last = static_cast<int>(corridor.size()) - 1;
        for (;;) {
          const Vec2 p = corridor[static_cast<size_t>(rng.integer(0, last))] +
                         Vec2(rng.uniform(-half, half), rng.uniform(-half, half));
          double to_centre = 1e9;
          for (const Vec2& q : corridor) to_centre = std::min(to_centre, (q - p).norm());
          if (to_centre <= half) return p;
        }
      };
      fill(draw, 0.25 * static_cast<double>(corridor.size()) * d.corridor_width_m);
    }
  }
  // An exit sign over each doorway, on the side the tour comes from, facing it: the forward view
  // sees it on the way in.
  for (const auto& [c, heading] : d.doorways) {
    const Vec2 at = c - 0.3 * dir(heading);
    const double drop = rng.uniform(0.1, 0.2);
    if (H - drop - 0.2 < 2.05) continue;
    d.ceiling_items.push_back("{kind: sign, center: " + pt(at) + ", yaw_deg: " +
                              num(heading / kDeg + 180.0) + ", size_m: [0.4, 0.2], drop_m: " +
                              num(drop) + ", texture: ceiling_sign}");
  }
}

// The replay starts (teach start, +-0.1 m to the side) keep a perturbed 0.3 m robot clear; the
// tour does not pass near its own end before it gets there (the teach drive would stop early).
void check_tour_and_starts(const Draft& d, const Obstacles& o) {
  const Vec2 e = (d.path[1] - d.path[0]).normalized();
  const Vec2 n = left_of(e);
  for (double side : {0.0, 0.1, -0.1})
    for (double lat : {-kPerturbLateralM, 0.0, kPerturbLateralM})
      for (double along : {-kPerturbAlongM, 0.0, kPerturbAlongM})
        if (o.clearance(d.path[0] + (0.1 + along) * e + (side + lat) * n) < kRobotRadiusM + 0.05)
          throw Reject{"a perturbed replay start is too close to an obstacle"};
  const auto s = samples(d.path, 0.05);
  for (size_t i = 0; i + 20 < s.size(); ++i)
    if ((s[i] - s.back()).norm() < 0.4) throw Reject{"the tour passes its own end"};
}

// The scripted teach drive on the base kinematics (no rendering): its closest approach to the
// obstacles, or a Reject when it does not reach the end.
double drive_clearance(const Draft& d, const Obstacles& o) {
  Scenario s;
  s.waypoints_m = d.path;
  s.teach_speed_m_s = kTeachSpeedMS;
  TeachDriver driver(s);
  BaseKinematics base;
  const Pose2D start = s.start_pose();
  base.reset(start, 0);
  double clearance = o.clearance({start.x_m, start.y_m});
  const double dt = 1.0 / 15.0;
  const double limit_s = 3.0 * s.path_length_m() / kTeachSpeedMS + 120.0;
  double t = 0.0;
  while (!driver.done()) {
    if (t > limit_s) throw Reject{"the teach drive does not reach the end"};
    base.command(driver.command(base.pose(), t), base.now_ns());
    t += dt;
    base.advance_to(static_cast<int64_t>(t * 1e9));
    clearance = std::min(clearance, o.clearance({base.pose().x_m, base.pose().y_m}));
  }
  return clearance;
}

// ---------------------------------------------------------------------------------------------
// YAML.

std::string textures_yaml(Rng& rng, const std::string& dir, int size_px) {
  std::ostringstream os;
  auto seed = [&rng] { return std::to_string(rng.integer(1, 100000)); };
  os << "textures:\n";
  if (rng.chance(0.5))
    os << "  floor: {type: tiles, cells: 4, mean: " << num(rng.uniform(135, 165))
       << ", contrast: " << num(rng.uniform(18, 30)) << ", seed: " << seed() << "}\n";
  else
    os << "  floor: {type: noise, mean: " << num(rng.uniform(110, 145))
       << ", contrast: " << num(rng.uniform(14, 22)) << ", feature_px: 20, seed: " << seed()
       << "}\n";
  // 16 x 16 tiles of 0.6 m per repetition (ceiling tile_m 9.6), each its own grey: not periodic
  // along a room (ceiling mode), four times the other textures' side for the tile's detail.
  os << "  ceiling: {type: tiles, cells: 16, mean: " << num(rng.uniform(198, 215))
     << ", contrast: 26, seed: " << seed()
     << ", size_px: " << std::min(1024, 4 * size_px) << "}\n";
  os << "  paint: {type: noise, mean: " << num(rng.uniform(170, 200))
     << ", contrast: " << num(rng.uniform(6, 12)) << ", feature_px: 40, seed: " << seed() << "}\n";
  os << "  paint_b: {type: noise, mean: " << num(rng.uniform(160, 195))
     << ", contrast: " << num(rng.uniform(6, 12)) << ", feature_px: 36, seed: " << seed()
     << "}\n";
  os << "  paint_corridor: {type: noise, mean: " << num(rng.uniform(160, 190))
     << ", contrast: " << num(rng.uniform(5, 10)) << ", feature_px: 48, seed: " << seed()
     << "}\n";
  // The blank walls of issue 29: flat paint, or paint with barely any texture.
  if (rng.chance(0.5))
    os << "  blank: {type: uniform, mean: " << num(rng.uniform(175, 205)) << "}\n";
  else
    os << "  blank: {type: noise, mean: " << num(rng.uniform(175, 205))
       << ", contrast: 3, feature_px: 64, seed: " << seed() << "}\n";
  os << "  skirting: {type: uniform, mean: 55}\n";
  os << "  door: {type: door, mean: 112, contrast: 26, seed: " << seed() << "}\n";
  os << "  door_light: {type: door, mean: 165, contrast: 22, seed: " << seed() << "}\n";
  os << "  frame: {type: wood, mean: 90, contrast: 12, cells: 1, seed: " << seed() << "}\n";
  os << "  window: {type: window, cells: 3, rows: 2, mean: 230, contrast: 14, seed: " << seed()
     << "}\n";
  os << "  books: {type: books, rows: 5, mean: 118, contrast: 55, seed: " << seed() << "}\n";
  os << "  shelf: {type: wood, mean: 148, contrast: 20, cells: 2, seed: " << seed() << "}\n";
  os << "  desk: {type: wood, mean: 162, contrast: 22, cells: 5, seed: " << seed() << "}\n";
  os << "  metal: {type: uniform, mean: 72}\n";
  os << "  cabinet: {type: tiles, cells: 2, mean: 138, contrast: 34, seed: " << seed() << "}\n";
  os << "  stripes: {type: stripes, cells: 24, mean: 120, contrast: 50, seed: " << seed() << "}\n";
  os << "  foliage: {type: noise, mean: 85, contrast: 45, feature_px: 8, seed: " << seed()
     << "}\n";
  os << "  board: {type: checker, cells: 6, mean: 150, contrast: 25}\n";
  os << "  notices: {type: books, rows: 4, mean: 170, contrast: 40, seed: " << seed() << "}\n";
  os << "  lamp: {type: uniform, mean: 250}\n";
  // Ceiling fixtures: fixed looks (their places are what is drawn), so the other textures' draws
  // are what they were before the fixtures existed.
  os << "  ceiling_vent: {type: stripes, mean: 120, contrast: 45, cells: 14, seed: 4}\n";
  os << "  ceiling_grille: {type: checker, mean: 150, contrast: 40, cells: 6}\n";
  os << "  ceiling_stained: {type: noise, mean: 160, contrast: 35, feature_px: 48, seed: 6}\n";
  os << "  ceiling_new: {type: noise, mean: 232, contrast: 6, feature_px: 40, seed: 7}\n";
  os << "  ceiling_plenum: {type: noise, mean: 45, contrast: 20, feature_px: 24, seed: 8}\n";
  os << "  ceiling_metal: {type: uniform, mean: 80}\n";
  os << "  ceiling_white: {type: uniform, mean: 240}\n";
  os << "  ceiling_beam: {type: noise, mean: 170, contrast: 18, feature_px: 24, seed: 9}\n";
  os << "  ceiling_sign: {type: checker, mean: 130, contrast: 95, cells: 2}\n";
  const std::string base = dir.empty() || dir.back() == '/' ? dir : dir + "/";
  for (const auto& [name, file] : std::vector<std::pair<const char*, const char*>>{
           {"pepper_a", "pepper_office_a.jpg"},
           {"pepper_b", "pepper_office_b.jpg"},
           {"pepper_c", "pepper_office_c.jpg"},
           {"pepper_d", "pepper_office_d.jpg"},
           {"pepper_e", "pepper_office_e.jpg"},
           {"klimt", "klimt.jpg"},
           {"solvay", "solvay_1927.jpg"},
           {"grid", "calibration_grid.jpg"}})
    os << "  " << name << ": {type: image, file: " << base << file << "}\n";
  if (size_px == TextureSpec{}.size_px) return os.str();
  // Smaller textures: the same entries with their size appended (procedural side, image side).
  std::istringstream in(os.str());
  std::ostringstream out;
  for (std::string line; std::getline(in, line);) {
    if (line.size() > 2 && line.back() == '}' && line.find("size_px") == std::string::npos) {
      line.pop_back();
      const bool image = line.find("type: image") != std::string::npos;
      line += (image ? ", max_size_px: " : ", size_px: ") + std::to_string(size_px) + "}";
    }
    out << line << "\n";
  }
  return out.str();
}

std::string to_yaml(const Draft& d, const GeneratedWorld& g, const std::string& textures) {
  std::ostringstream os;
  os << "# Generated by `pepper_app world generate --seed " << g.seed << " --kind "
     << to_string(g.kind) << "` (sim/src/world_generator.cpp): do not edit, generate again.\n"
     << "# " << g.summary() << "\n"
     << "# Format: docs/mock_robot.md.\n";
  os << "name: gen_" << to_string(g.kind) << "_" << g.seed << "\n";
  os << "description: Generated " << to_string(g.kind) << ", seed " << g.seed << ", "
     << num(g.path_length_m) << " m tour with " << g.turns.size() << " turns"
     << (g.poor_view ? ", every turn facing a blank wall" : "") << "\n";
  os << "key_light_deg: " << num(std::fmod(static_cast<double>(g.seed) * 37.0, 90.0)) << "\n\n";
  os << "lighting:\n  teach: {ambient: 1.0, windows: 1.0, lamps: 1.0}\n"
     << "  replay: {ambient: 0.95, windows: 1.1, lamps: 1.0}\n\n";
  os << textures << "\n";
  os << "floor: {texture: floor, tile_m: [2.0, 2.0]}\n";
  os << "ceiling: {height_m: " << num(d.ceiling_m) << ", texture: ceiling, tile_m: ["
     << num(16 * kCeilingTileM) << ", " << num(16 * kCeilingTileM) << "]}\n\n";
  os << "walls:\n";
  for (const Wall& w : d.walls) {
    os << "  - points: [";
    for (size_t i = 0; i < w.pts.size(); ++i) os << (i ? ", " : "") << pt(w.pts[i]);
    os << "]\n    texture: " << w.texture << "\n    tile_m: [2.0, " << num(d.ceiling_m) << "]\n";
    os << "    skirting: {texture: skirting, height_m: 0.1}\n";  // blank walls too: a real one has it
    const std::string side = w.space_left ? "left" : "right";
    for (FeatureKind kind :
         {FeatureKind::kOpening, FeatureKind::kDoor, FeatureKind::kWindow, FeatureKind::kPoster}) {
      std::vector<const Feature*> fs;
      for (const Feature& f : w.features)
        if (f.kind == kind) fs.push_back(&f);
      if (fs.empty()) continue;
      static const char* kKey[] = {"openings", "doors", "windows", "posters"};
      os << "    " << kKey[static_cast<int>(kind)] << ":\n";
      std::sort(fs.begin(), fs.end(), [](auto* a, auto* b) { return a->at_m < b->at_m; });
      for (const Feature* f : fs) {
        os << "      - {at_m: " << num(f->at_m) << ", width_m: " << num(f->width_m);
        switch (kind) {
          case FeatureKind::kOpening:
            os << ", height_m: " << num(f->height_m) << ", frame: {texture: frame, width_m: "
               << num(kFrameWidthM) << "}";
            break;
          case FeatureKind::kDoor:
            os << ", height_m: " << num(f->height_m) << ", texture: " << f->texture
               << ", frame: {texture: frame, width_m: " << num(kFrameWidthM) << "}";
            break;
          case FeatureKind::kWindow:
            os << ", sill_m: " << num(f->sill_m) << ", height_m: " << num(f->height_m)
               << ", texture: " << f->texture << ", frame: {texture: frame, width_m: "
               << num(kFrameWidthM) << "}";
            break;
          case FeatureKind::kPoster:
            os << ", height_m: " << num(f->height_m) << ", center_m: " << num(f->center_m)
               << ", texture: " << f->texture << ", side: " << side;
            break;
        }
        os << "}\n";
      }
    }
  }
  bool any_box = false, any_table = false;
  for (const Box& b : d.boxes) (b.table ? any_table : any_box) = true;
  if (any_box) {
    os << "\nboxes:\n";
    for (const Box& b : d.boxes) {
      if (b.table) continue;
      os << "  - {name: " << b.name << ", center: " << pt(b.c) << ", size_m: ["
         << num(b.size_m.x()) << ", " << num(b.size_m.y()) << ", " << num(b.size_m.z())
         << "], yaw_deg: " << num(b.yaw_rad / kDeg) << ", texture: " << b.texture
         << ", tile_m: [" << num(b.tile_m) << ", " << num(b.tile_m) << "]";
      if (!b.front.empty()) os << ", front: {texture: " << b.front << "}";
      if (!b.top.empty()) os << ", top: {texture: " << b.top << "}";
      os << "}\n";
    }
  }
  if (any_table) {
    os << "\ntables:\n";
    for (const Box& b : d.boxes)
      if (b.table)
        os << "  - {name: " << b.name << ", center: " << pt(b.c) << ", size_m: ["
           << num(b.size_m.x()) << ", " << num(b.size_m.y()) << "], yaw_deg: "
           << num(b.yaw_rad / kDeg) << ", texture: desk, legs: {texture: metal}}\n";
  }
  if (!d.lamps.empty()) {
    os << "\nlamps:\n";
    for (const Lamp& l : d.lamps)
      os << "  - {center: " << pt(l.c) << ", size_m: " << pt(l.size_m) << ", texture: lamp}\n";
  }
  if (!d.ceiling_items.empty()) {
    os << "\nceiling_items:\n";
    for (const std::string& item : d.ceiling_items) os << "  - " << item << "\n";
  }
  os << "\nteach:\n  waypoints: [";
  for (size_t i = 0; i < d.path.size(); ++i) os << (i ? ", " : "") << pt(d.path[i]);
  os << "]\n  speed_m_s: " << num(kTeachSpeedMS) << "\n";
  // Replay starts: the teach start and two shifted, turned copies (as the shipped worlds).
  const Vec2 p0 = d.path[0];
  const Vec2 e = (d.path[1] - d.path[0]).normalized();
  const double yaw = std::atan2(e.y(), e.x()) / kDeg;
  const Vec2 s1 = p0 + 0.1 * e + 0.1 * left_of(e), s2 = p0 + 0.05 * e - 0.1 * left_of(e);
  os << "\nreplay:\n  starts: [[" << num(p0.x()) << ", " << num(p0.y()) << ", " << num(yaw)
     << "], [" << num(s1.x()) << ", " << num(s1.y()) << ", " << num(yaw + 5.0) << "], ["
     << num(s2.x()) << ", " << num(s2.y()) << ", " << num(yaw - 6.0) << "]]\n"
     << "  perturbation: {lateral_m: " << num(kPerturbLateralM) << ", along_m: "
     << num(kPerturbAlongM) << ", yaw_deg: 6}\n";
  return os.str();
}

}  // namespace

// ---------------------------------------------------------------------------------------------

const char* to_string(WorldKind kind) {
  switch (kind) {
    case WorldKind::kRoom:
      return "room";
    case WorldKind::kCorridor:
      return "corridor";
    case WorldKind::kBuilding:
      return "building";
  }
  return "?";
}

WorldKind world_kind_from_string(const std::string& name) {
  for (WorldKind k : {WorldKind::kRoom, WorldKind::kCorridor, WorldKind::kBuilding})
    if (name == to_string(k)) return k;
  throw std::invalid_argument("unknown world kind '" + name + "' (room, corridor, building)");
}

std::vector<std::string> WorldGeneratorOptions::validate() const {
  std::vector<std::string> errors;
  if (!(poor_view_fraction >= 0.0 && poor_view_fraction <= 1.0))
    errors.push_back("poor_view_fraction must be in [0, 1]");
  if (!(blank_view_prob >= 0.0 && blank_view_prob <= 1.0))
    errors.push_back("blank_view_prob must be in [0, 1]");
  if (!(min_clearance_m >= 0.35 && min_clearance_m <= 0.8))
    errors.push_back("min_clearance_m must be in [0.35, 0.8] (a 0.3 m robot, corridors >= 1.6 m)");
  if (!(min_drive_clearance_m >= 0.3 && min_drive_clearance_m <= min_clearance_m))
    errors.push_back("min_drive_clearance_m must be in [0.3, min_clearance_m]");
  if (max_attempts < 1) errors.push_back("max_attempts must be >= 1");
  if (!(texture_size_px >= 16 && texture_size_px <= 1024 &&
        (texture_size_px & (texture_size_px - 1)) == 0))
    errors.push_back("texture_size_px must be a power of two in [16, 1024]");
  return errors;
}

std::string GeneratedWorld::summary() const {
  std::ostringstream os;
  os << to_string(kind) << " seed " << seed << ": " << num(path_length_m) << " m, "
     << turns.size() << " turns (";
  for (size_t i = 0; i < turns.size(); ++i) {
    const GeneratedTurn& t = turns[i];
    os << (i ? ", " : "") << (t.angle_deg > 0 ? "L" : "R") << std::lround(std::abs(t.angle_deg))
       << (t.on_arc ? " arc r " + num(t.radius_m) : " spot") << (t.faces_blank ? " blank" : "");
  }
  os << ")" << (poor_view ? ", poor view" : "") << ", clearance " << num(min_clearance_m)
     << " m (drive " << num(min_drive_clearance_m) << " m), attempt " << attempts;
  return os.str();
}

GeneratedWorld generate_world(const WorldGeneratorOptions& options) {
  const auto errors = options.validate();
  if (!errors.empty()) throw std::invalid_argument("WorldGeneratorOptions: " + errors.front());
  std::string last_reason;
  for (int attempt = 1; attempt <= options.max_attempts; ++attempt) {
    Rng rng(options.seed * 0x2545F4914F6CDD1DULL + static_cast<uint64_t>(attempt) * 0x9E3779B9ULL +
            static_cast<uint64_t>(options.kind));
    try {
      Draft d;
      d.ceiling_m = rng.uniform(2.5, 3.0);
      // Decided from the seed alone, so that a seed keeps its class whatever the attempt.
      d.poor_view = Rng(options.seed * 0xD1B54A32D192ED03ULL + 7).uniform(0.0, 1.0) <
                    options.poor_view_fraction;
      switch (options.kind) {
        case WorldKind::kRoom:
          build_room_kind(d, rng);
          break;
        case WorldKind::kCorridor:
          build_corridor_kind(d, rng);
          break;
        case WorldKind::kBuilding:
          build_building_kind(d, rng);
          break;
      }
      check_walls_do_not_cross(d);
      d.views.insert(d.views.begin(),
                     View{d.path[0], std::atan2(d.path[1].y() - d.path[0].y(),
                                                d.path[1].x() - d.path[0].x()),
                          kStartView});
      shape_views(d, rng, options.blank_view_prob);
      add_wall_features(d, rng);
      const auto tour = samples(d.path, 0.05);
      // The walls alone must leave the polyline its clearance before furniture is tried.
      if (path_clearance(obstacles_of(d, false), tour) < options.min_clearance_m)
        throw Reject{"the tour passes too close to a wall"};
      add_furniture(d, rng, tour, options.min_clearance_m);
      add_lamps(d);
      const Obstacles all = obstacles_of(d, true);
      GeneratedWorld g;
      g.kind = options.kind;
      g.seed = options.seed;
      g.poor_view = d.poor_view;
      g.turns = d.turns;
      g.attempts = attempt;
      g.min_clearance_m = path_clearance(all, tour);
      if (g.min_clearance_m < options.min_clearance_m) throw Reject{"tour too close"};
      check_tour_and_starts(d, all);
      g.min_drive_clearance_m = drive_clearance(d, all);
      if (g.min_drive_clearance_m < options.min_drive_clearance_m)
        throw Reject{"the teach drive passes too close"};
      for (size_t i = 1; i < d.path.size(); ++i) g.path_length_m += (d.path[i] - d.path[i - 1]).norm();
      const std::string textures = textures_yaml(rng, options.texture_dir, options.texture_size_px);
      Rng ceiling_rng(options.seed * 0x94D049BB133111EBULL + static_cast<uint64_t>(attempt));
      add_ceiling_items(d, ceiling_rng);
      g.yaml = to_yaml(d, g, textures);
      return g;
    } catch (const Reject& r) {
      last_reason = r.why;
    }
  }
  throw std::runtime_error("world generator: no plausible " + std::string(to_string(options.kind)) +
                           " for seed " + std::to_string(options.seed) + " in " +
                           std::to_string(options.max_attempts) + " attempts (last: " +
                           last_reason + ")");
}

}  // namespace pepper::sim
