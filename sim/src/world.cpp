// World file parsing, validation and geometry building (see world.hpp; format in
// docs/mock_robot.md).
#include "sim/world.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace pepper::sim {

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kPosterOffsetM = 0.012;  // posters and skirting stand off the wall plane
constexpr double kRobotHeightM = 1.2;     // boxes higher above the floor do not collide

// ---------------------------------------------------------------------------------------------
// YAML access with errors that name file, line and key.

struct Src {
  std::string file;
};

[[noreturn]] void fail_at(const Src& src, const YAML::Node& node, const std::string& path,
                          const std::string& msg) {
  std::ostringstream os;
  os << src.file;
  if (node.IsDefined() && node.Mark().line >= 0) os << ":" << node.Mark().line + 1;
  os << ": " << path << ": " << msg;
  throw WorldError(os.str());
}

class Map {
 public:
  Map(const Src& src, const YAML::Node& node, std::string path)
      : src_(src), node_(node), path_(std::move(path)) {
    if (!node.IsMap()) fail_at(src_, node_, path_, "expected a mapping (key: value)");
  }

  const std::string& path() const { return path_; }
  std::string sub(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  bool has(const std::string& key) const { return static_cast<bool>(node_[key]); }

  YAML::Node get(const std::string& key) {
    used_.insert(key);
    return node_[key];
  }
  YAML::Node required(const std::string& key) {
    YAML::Node n = get(key);
    if (!n) fail_at(src_, node_, sub(key), "missing required key");
    return n;
  }
  [[noreturn]] void fail(const std::string& key, const std::string& msg) const {
    const YAML::Node n = node_[key];
    fail_at(src_, n ? n : node_, sub(key), msg);
  }

  double num(const std::string& key, double def) {
    YAML::Node n = get(key);
    return n ? as_num(n, sub(key)) : def;
  }
  double num_req(const std::string& key) { return as_num(required(key), sub(key)); }
  double positive(const std::string& key, double def) {
    const double v = num(key, def);
    if (!(v > 0.0)) fail(key, "must be > 0 (got " + std::to_string(v) + ")");
    return v;
  }
  double nonneg(const std::string& key, double def) {
    const double v = num(key, def);
    if (!(v >= 0.0)) fail(key, "must be >= 0 (got " + std::to_string(v) + ")");
    return v;
  }
  int integer(const std::string& key, int def) {
    YAML::Node n = get(key);
    if (!n) return def;
    try {
      return n.as<int>();
    } catch (const YAML::Exception&) {
      fail_at(src_, n, sub(key), "expected an integer");
    }
  }
  bool boolean(const std::string& key, bool def) {
    YAML::Node n = get(key);
    if (!n) return def;
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail_at(src_, n, sub(key), "expected true or false");
    }
  }
  std::string str(const std::string& key, const std::string& def) {
    YAML::Node n = get(key);
    if (!n) return def;
    if (!n.IsScalar()) fail_at(src_, n, sub(key), "expected a string");
    return n.as<std::string>();
  }
  std::string str_req(const std::string& key) {
    YAML::Node n = required(key);
    if (!n.IsScalar()) fail_at(src_, n, sub(key), "expected a string");
    return n.as<std::string>();
  }
  std::vector<double> nums(const std::string& key, size_t count, bool req) {
    YAML::Node n = req ? required(key) : get(key);
    if (!n) return {};
    return as_nums(n, sub(key), count);
  }
  Eigen::Vector2d vec2(const std::string& key, const Eigen::Vector2d& def) {
    const auto v = nums(key, 2, false);
    return v.empty() ? def : Eigen::Vector2d(v[0], v[1]);
  }
  Eigen::Vector2d vec2_req(const std::string& key) {
    const auto v = nums(key, 2, true);
    return {v[0], v[1]};
  }
  std::vector<Eigen::Vector2d> points(const std::string& key, size_t min_count) {
    YAML::Node n = required(key);
    if (!n.IsSequence() || n.size() < min_count)
      fail_at(src_, n, sub(key),
              "expected a list of at least " + std::to_string(min_count) + " [x, y] points");
    std::vector<Eigen::Vector2d> out;
    for (size_t i = 0; i < n.size(); ++i) {
      const auto v = as_nums(n[i], sub(key) + "[" + std::to_string(i) + "]", 2);
      out.emplace_back(v[0], v[1]);
    }
    return out;
  }
  // Sequence of mappings under `key` (empty when absent).
  std::vector<Map> list(const std::string& key) {
    YAML::Node n = get(key);
    std::vector<Map> out;
    if (!n) return out;
    if (!n.IsSequence()) fail_at(src_, n, sub(key), "expected a list");
    for (size_t i = 0; i < n.size(); ++i)
      out.emplace_back(src_, n[i], sub(key) + "[" + std::to_string(i) + "]");
    return out;
  }
  std::optional<Map> map(const std::string& key) {
    YAML::Node n = get(key);
    if (!n) return std::nullopt;
    return Map(src_, n, sub(key));
  }

  // Every key not read is a typo or an unsupported option: refuse it.
  void done() const {
    for (const auto& kv : node_) {
      const std::string key = kv.first.as<std::string>();
      if (!used_.count(key)) {
        std::string known;
        for (const auto& k : used_) known += (known.empty() ? "" : ", ") + k;
        fail_at(src_, kv.first, sub(key), "unknown key (known here: " + known + ")");
      }
    }
  }

  const Src& src() const { return src_; }
  const YAML::Node& node() const { return node_; }

 private:
  double as_num(const YAML::Node& n, const std::string& path) const {
    try {
      const double v = n.as<double>();
      if (!std::isfinite(v)) fail_at(src_, n, path, "must be finite");
      return v;
    } catch (const YAML::Exception&) {
      fail_at(src_, n, path, "expected a number");
    }
  }
  std::vector<double> as_nums(const YAML::Node& n, const std::string& path, size_t count) const {
    if (!n.IsSequence() || n.size() != count)
      fail_at(src_, n, path, "expected a list of " + std::to_string(count) + " numbers");
    std::vector<double> v;
    for (size_t i = 0; i < count; ++i) v.push_back(as_num(n[i], path));
    return v;
  }

  Src src_;
  YAML::Node node_;
  std::string path_;
  std::set<std::string> used_;
};

// ---------------------------------------------------------------------------------------------
// Geometry building.

struct Style {
  int texture = 0;
  Eigen::Vector2d tile_m{1.0, 1.0};
  double brightness = 1.0;
};

class Builder {
 public:
  Builder(World& world, std::map<std::string, int> textures)
      : w_(world), textures_(std::move(textures)) {}

  Style style(Map& m, const Eigen::Vector2d& default_tile,
              const std::string& default_texture = "") {
    Style s;
    const std::string name =
        default_texture.empty() ? m.str_req("texture") : m.str("texture", default_texture);
    const auto it = textures_.find(name);
    if (it == textures_.end()) {
      std::string known;
      for (const auto& [k, v] : textures_) known += (known.empty() ? "" : ", ") + k;
      m.fail("texture", "unknown texture '" + name + "' (defined: " + known + ")");
    }
    s.texture = it->second;
    s.tile_m = m.vec2("tile_m", default_tile);
    if (!(s.tile_m.x() > 0 && s.tile_m.y() > 0)) m.fail("tile_m", "must be > 0");
    s.brightness = m.nonneg("brightness", 1.0);
    return s;
  }

  Quad quad(const Eigen::Vector3d& origin, const Eigen::Vector3d& au, const Eigen::Vector3d& av,
            double su, double sv, const Style& s, bool stretch, double off_u = 0.0,
            double off_v = 0.0) {
    Quad q;
    q.origin_m = origin;
    q.axis_u = au;
    q.axis_v = av;
    q.size_u_m = su;
    q.size_v_m = sv;
    q.texture = s.texture;
    q.tile_u_m = stretch ? su : s.tile_m.x();
    q.tile_v_m = stretch ? sv : s.tile_m.y();
    q.offset_u_m = off_u;
    q.offset_v_m = off_v;
    q.brightness = s.brightness;
    return q;
  }

  void add(const Quad& q) {
    if (q.size_u_m > 1e-6 && q.size_v_m > 1e-6) w_.quads.push_back(q);
  }

  // Axis-aligned (in its own yaw) box: 4 sides, top, and bottom when raised.
  void box(const Eigen::Vector2d& c, const Eigen::Vector3d& size, double yaw, double z0,
           const Style& side, const Style& top, const std::optional<Style>& front) {
    const Eigen::Vector2d ex(std::cos(yaw), std::sin(yaw));
    const Eigen::Vector2d ey(-ex.y(), ex.x());
    const double z1 = z0 + size.z();
    const Eigen::Vector3d down(0, 0, -1);
    // Outward normals (local +x, +y, -x, -y) and the half extents along normal / right.
    const std::array<std::pair<Eigen::Vector2d, Eigen::Vector2d>, 4> faces{
        {{ex, ey}, {ey, -ex}, {-ex, -ey}, {-ey, ex}}};
    const std::array<double, 4> half_n{size.x() / 2, size.y() / 2, size.x() / 2, size.y() / 2};
    const std::array<double, 4> half_r{size.y() / 2, size.x() / 2, size.y() / 2, size.x() / 2};
    for (int i = 0; i < 4; ++i) {
      const auto& [n, right] = faces[i];
      const Eigen::Vector2d o = c + n * half_n[i] - right * half_r[i];
      const bool is_front = i == 0 && front.has_value();
      add(quad({o.x(), o.y(), z1}, {right.x(), right.y(), 0}, down, 2 * half_r[i], size.z(),
               is_front ? *front : side, is_front));
    }
    const Eigen::Vector2d o = c - ex * size.x() / 2 + ey * size.y() / 2;
    add(quad({o.x(), o.y(), z1}, {ex.x(), ex.y(), 0}, {-ey.x(), -ey.y(), 0}, size.x(), size.y(),
             top, false));
    if (z0 > 0.01)
      add(quad({o.x(), o.y(), z0}, {ex.x(), ex.y(), 0}, {-ey.x(), -ey.y(), 0}, size.x(), size.y(),
               side, false));
  }

  void obstacle(const Eigen::Vector2d& c, const Eigen::Vector2d& size, double yaw,
                const std::string& what) {
    w_.boxes.push_back({c, size / 2, yaw, what});
  }

  World& w_;
  std::map<std::string, int> textures_;
};

struct Hole {
  double s0, s1, z0, z1;
  bool passable;  // openings: removed from the collision segment
};

void parse_frame(Builder& b, Map& f, const Eigen::Vector2d& a, const Eigen::Vector2d& e,
                 double thickness, const Hole& h, bool sill, const std::string& what) {
  const Style st = b.style(f, {0.5, 0.5});
  const double fw = f.positive("width_m", 0.07);
  f.done();
  const double depth = thickness + 0.04;
  const double yaw = std::atan2(e.y(), e.x());
  auto frame_box = [&](double s_c, double len, double z0, double z1) {
    const Eigen::Vector2d c = a + e * s_c;
    b.box(c, {len, depth, z1 - z0}, yaw, z0, st, st, std::nullopt);
  };
  frame_box(h.s0 - fw / 2, fw, 0.0, h.z1 + fw);  // jambs from the floor (windows too)
  frame_box(h.s1 + fw / 2, fw, 0.0, h.z1 + fw);
  b.obstacle(a + e * (h.s0 - fw / 2), {fw, depth}, yaw, what + ".frame");
  b.obstacle(a + e * (h.s1 + fw / 2), {fw, depth}, yaw, what + ".frame");
  frame_box(0.5 * (h.s0 + h.s1), h.s1 - h.s0, h.z1, h.z1 + fw);  // lintel
  if (sill && h.z0 > fw) frame_box(0.5 * (h.s0 + h.s1), h.s1 - h.s0, h.z0 - fw, h.z0);
}

void parse_wall(Builder& b, Map& m, double ceiling_h) {
  World& w = b.w_;
  const auto pts_in = m.points("points", 2);
  const bool closed = m.boolean("closed", false);
  const double H = m.positive("height_m", ceiling_h);
  const double thick = m.positive("thickness_m", 0.1);
  const Style st = b.style(m, {2.0, H});
  std::optional<Style> skirt_style;
  double skirt_h = 0.0;
  if (auto sk = m.map("skirting")) {
    skirt_style = b.style(*sk, {1.0, 0.1});
    skirt_h = sk->positive("height_m", 0.1);
    sk->done();
  }
  std::vector<Eigen::Vector2d> pts = pts_in;
  if (closed) pts.push_back(pts.front());
  std::vector<double> cum{0.0};
  for (size_t i = 1; i < pts.size(); ++i) {
    const double len = (pts[i] - pts[i - 1]).norm();
    if (len < 1e-6)
      m.fail("points", "two consecutive points coincide (index " + std::to_string(i) + ")");
    cum.push_back(cum.back() + len);
  }
  const size_t nseg = pts.size() - 1;
  std::vector<std::vector<Hole>> holes(nseg);

  struct Feature {
    Map* map;
    size_t seg;
    Hole hole;
  };
  auto locate = [&](Map& f, double width) {
    const double at = f.num_req("at_m");
    for (size_t i = 0; i < nseg; ++i) {
      if (at >= cum[i] && at <= cum[i + 1]) {
        const double s0 = at - cum[i] - width / 2, s1 = at - cum[i] + width / 2;
        if (s0 < 0.0 || s1 > cum[i + 1] - cum[i])
          f.fail("at_m", "feature of width " + std::to_string(width) +
                             " m does not fit in one straight piece of the wall (piece " +
                             std::to_string(i) + " spans " + std::to_string(cum[i]) + ".." +
                             std::to_string(cum[i + 1]) + " m)");
        return std::make_pair(i, std::make_pair(s0, s1));
      }
    }
    f.fail("at_m", "beyond the wall's length " + std::to_string(cum.back()) + " m");
  };
  auto seg_geom = [&](size_t i) {
    const Eigen::Vector2d a = pts[i];
    const Eigen::Vector2d e = (pts[i + 1] - pts[i]).normalized();
    return std::make_pair(a, e);
  };

  // Openings, doors and windows cut holes.
  const std::string path = m.path();
  auto cut = [&](Map& f, const std::string& what, double def_w, double def_h, double def_z0,
                 bool passable) {
    const double width = f.positive("width_m", def_w);
    const auto [seg, s] = locate(f, width);
    const double z0 = def_z0 > 0.0 ? f.nonneg("sill_m", def_z0) : 0.0;
    const double z1 = z0 + f.positive("height_m", def_h);
    if (z1 > H) f.fail("height_m", "reaches above the wall (" + std::to_string(H) + " m)");
    const Hole h{s.first, s.second, z0, z1, passable};
    for (const Hole& o : holes[seg])
      if (h.s0 < o.s1 + 0.15 && o.s0 < h.s1 + 0.15)
        f.fail("at_m", "overlaps (or leaves < 0.15 m for the frame to) another opening");
    holes[seg].push_back(h);
    const auto [a, e] = seg_geom(seg);
    if (auto fr = f.map("frame")) parse_frame(b, *fr, a, e, thick, h, z0 > 0.0, what);
    return std::make_tuple(seg, h, a, e);
  };
  auto openings = m.list("openings");
  for (Map& f : openings) {
    cut(f, f.path(), 0.9, 2.05, 0.0, true);
    f.done();
  }
  auto doors = m.list("doors");
  for (Map& f : doors) {
    const Style ds = b.style(f, {1, 1});
    const auto [seg, h, a, e] = cut(f, f.path(), 0.9, 2.05, 0.0, false);
    const Eigen::Vector2d o = a + e * h.s0;
    b.add(b.quad({o.x(), o.y(), h.z1}, {e.x(), e.y(), 0}, {0, 0, -1}, h.s1 - h.s0, h.z1 - h.z0, ds,
                 true));
    f.done();
  }
  auto windows = m.list("windows");
  for (Map& f : windows) {
    const Style ws = b.style(f, {1, 1});
    const auto [seg, h, a, e] = cut(f, f.path(), 1.2, 1.3, 0.9, false);
    const Eigen::Vector2d o = a + e * h.s0;
    Quad q = b.quad({o.x(), o.y(), h.z1}, {e.x(), e.y(), 0}, {0, 0, -1}, h.s1 - h.s0, h.z1 - h.z0,
                    ws, true);
    q.light = LightGroup::kWindows;
    b.add(q);
    f.done();
  }

  // Wall pieces around the holes, skirting below, collision segments.
  for (size_t i = 0; i < nseg; ++i) {
    auto [a, e] = seg_geom(i);
    const double L = cum[i + 1] - cum[i];
    const Eigen::Vector2d nl(-e.y(), e.x());
    auto& hs = holes[i];
    std::sort(hs.begin(), hs.end(), [](const Hole& x, const Hole& y) { return x.s0 < y.s0; });
    auto rect = [&](double s0, double s1, double z0, double z1) {
      const Eigen::Vector2d o = a + e * s0;
      b.add(b.quad({o.x(), o.y(), z1}, {e.x(), e.y(), 0}, {0, 0, -1}, s1 - s0, z1 - z0, st, false,
                   cum[i] + s0, H - z1));
    };
    auto skirt = [&](double s0, double s1) {
      if (!skirt_style || s1 - s0 < 1e-6) return;
      for (double side : {1.0, -1.0}) {
        const Eigen::Vector2d o = a + e * s0 + side * kPosterOffsetM * nl;
        b.add(b.quad({o.x(), o.y(), skirt_h}, {e.x(), e.y(), 0}, {0, 0, -1}, s1 - s0, skirt_h,
                     *skirt_style, false, cum[i] + s0, 0.0));
      }
    };
    auto collide = [&](double s0, double s1) {
      if (s1 - s0 < 1e-6) return;
      w.walls.push_back({a + e * s0, a + e * s1, thick / 2, path + " piece " + std::to_string(i)});
    };
    double cursor = 0.0, skirt_cursor = 0.0, col_cursor = 0.0;
    for (const Hole& h : hs) {
      rect(cursor, h.s0, 0.0, H);
      if (h.z0 > 0.0) rect(h.s0, h.s1, 0.0, h.z0);
      if (h.z1 < H) rect(h.s0, h.s1, h.z1, H);
      cursor = h.s1;
      if (h.z0 < skirt_h + 1e-9) {
        skirt(skirt_cursor, h.s0);
        skirt_cursor = h.s1;
      }
      if (h.passable) {
        collide(col_cursor, h.s0);
        col_cursor = h.s1;
      }
    }
    rect(cursor, L, 0.0, H);
    skirt(skirt_cursor, L);
    collide(col_cursor, L);
  }

  // Posters on either side.
  for (Map& f : m.list("posters")) {
    const Style ps = b.style(f, {1, 1});
    const double width = f.positive("width_m", 0.6);
    const double height = f.positive("height_m", 0.8);
    const double zc = f.positive("center_m", 1.5);
    const std::string side = f.str("side", "left");
    if (side != "left" && side != "right") f.fail("side", "must be 'left' or 'right'");
    const auto [seg, s] = locate(f, width);
    const auto [a, e] = seg_geom(seg);
    const Eigen::Vector2d nl(-e.y(), e.x());
    const bool left = side == "left";
    // Seen from its side, the image's u axis points to the viewer's right.
    const Eigen::Vector2d right = left ? Eigen::Vector2d(-e) : e;
    const Eigen::Vector2d centre =
        a + e * 0.5 * (s.first + s.second) + (left ? 1.0 : -1.0) * kPosterOffsetM * 1.5 * nl;
    const Eigen::Vector2d o = centre - right * width / 2;
    if (zc + height / 2 > H || zc - height / 2 < 0) f.fail("center_m", "poster leaves the wall");
    b.add(b.quad({o.x(), o.y(), zc + height / 2}, {right.x(), right.y(), 0}, {0, 0, -1}, width,
                 height, ps, true));
    f.done();
  }
  m.done();
}

// Ceiling fixtures (docs/mock_robot.md "Ceiling items"). Flat kinds are drawn a few millimetres
// under the ceiling, each kind at its own offset so that a vent laid over a replaced tile wins the
// depth test everywhere (lamps are at 5 mm): tile 2 mm, vent 4 mm.
constexpr double kTileOffsetM = 0.002;
constexpr double kVentOffsetM = 0.004;
constexpr double kSignThicknessM = 0.04;
constexpr double kSignRodM = 0.012;  // side of the two square rods a sign hangs from
// Nothing under the ceiling has a collision model: whatever hangs must stay above a person's head
// and the door tops (2.05 m in the shipped worlds), far above the robot (kRobotHeightM).
constexpr double kMinHangingHeightM = 2.0;

struct CeilingKindName {
  CeilingItemKind kind;
  const char* name;
};
constexpr std::array<CeilingKindName, 6> kCeilingKinds{{
    {CeilingItemKind::kVent, "vent"},
    {CeilingItemKind::kTile, "tile"},
    {CeilingItemKind::kSprinkler, "sprinkler"},
    {CeilingItemKind::kDetector, "detector"},
    {CeilingItemKind::kBeam, "beam"},
    {CeilingItemKind::kSign, "sign"},
}};

void parse_ceiling_item(Builder& b, Map& m, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
                        double H) {
  CeilingItem item;
  try {
    item.kind = ceiling_item_kind_from_string(m.str_req("kind"));
  } catch (const std::invalid_argument& e) {
    m.fail("kind", e.what());
  }
  item.what = m.str("name", m.path());
  // The key whose value sets the footprint (named when it leaves the ceiling) and the one that
  // sets how low the item hangs (named when it hangs too low).
  std::string where_key = "center";
  std::string drop_key;
  double drop_m = 0.0;  // ceiling to the item's lowest point
  auto rotated_quad = [&](const Style& st, double offset_m) {
    const Eigen::Vector2d ex(std::cos(item.yaw_rad), std::sin(item.yaw_rad));
    const Eigen::Vector2d ey(-ex.y(), ex.x());
    // Seen from below: axis_u along yaw, axis_v = -ey keeps the quad's normal pointing down
    // (image rows run across the item, as a poster's rows run down a wall).
    const Eigen::Vector2d o = item.center_m - ex * item.size_m.x() / 2 + ey * item.size_m.y() / 2;
    b.add(b.quad({o.x(), o.y(), H - offset_m}, {ex.x(), ex.y(), 0}, {-ey.x(), -ey.y(), 0},
                 item.size_m.x(), item.size_m.y(), st, false));
    item.z_bottom_m = item.z_top_m = H - offset_m;
  };
  auto positive_size2 = [&](const Eigen::Vector2d& def) {
    const Eigen::Vector2d sz = m.vec2("size_m", def);
    if (!(sz.x() > 0.0 && sz.y() > 0.0)) m.fail("size_m", "sizes must be > 0");
    return sz;
  };
  switch (item.kind) {
    case CeilingItemKind::kVent:
    case CeilingItemKind::kTile: {
      const bool vent = item.kind == CeilingItemKind::kVent;
      item.center_m = m.vec2_req("center");
      item.size_m = positive_size2({0.6, 0.6});
      item.yaw_rad = m.num("yaw_deg", 0.0) * kDeg;
      // Default: the texture stretched once over the item (a grille, one tile).
      const Style st = b.style(m, item.size_m);
      m.done();
      rotated_quad(st, vent ? kVentOffsetM : kTileOffsetM);
      break;
    }
    case CeilingItemKind::kSprinkler:
    case CeilingItemKind::kDetector: {
      const bool sprinkler = item.kind == CeilingItemKind::kSprinkler;
      item.center_m = m.vec2_req("center");
      const double width = m.positive("width_m", sprinkler ? 0.06 : 0.12);
      drop_m = m.positive("drop_m", sprinkler ? 0.03 : 0.04);
      drop_key = "drop_m";
      item.size_m = {width, width};
      item.yaw_rad = m.num("yaw_deg", 0.0) * kDeg;
      const Style st = b.style(m, {width, width});
      m.done();
      item.z_top_m = H;
      item.z_bottom_m = H - drop_m;
      b.box(item.center_m, {width, width, drop_m}, item.yaw_rad, item.z_bottom_m, st, st,
            std::nullopt);
      break;
    }
    case CeilingItemKind::kBeam: {
      const Eigen::Vector2d from = m.vec2_req("from");
      const Eigen::Vector2d to = m.vec2_req("to");
      const double len = (to - from).norm();
      if (len < 0.05) m.fail("to", "a beam needs 'from' and 'to' at least 0.05 m apart");
      const double width = m.positive("width_m", 0.3);
      drop_m = m.positive("depth_m", 0.25);
      drop_key = "depth_m";
      where_key = "from";
      item.center_m = 0.5 * (from + to);
      item.size_m = {len, width};
      item.yaw_rad = std::atan2(to.y() - from.y(), to.x() - from.x());
      const Style st = b.style(m, {1.0, 1.0});
      m.done();
      item.z_top_m = H;
      item.z_bottom_m = H - drop_m;
      b.box(item.center_m, {len, width, drop_m}, item.yaw_rad, item.z_bottom_m, st, st,
            std::nullopt);
      break;
    }
    case CeilingItemKind::kSign: {
      item.center_m = m.vec2_req("center");
      // yaw_deg: where the sign's face looks (its normal), as a box's front.
      item.yaw_rad = m.num("yaw_deg", 0.0) * kDeg;
      const Eigen::Vector2d face = positive_size2({0.4, 0.2});  // width, height
      const double rods_m = m.positive("drop_m", 0.15);  // ceiling to the sign's top edge
      drop_m = rods_m + face.y();
      drop_key = "drop_m";
      // The face texture once over each large face (tile = the face), both sides.
      const Style st = b.style(m, face);
      m.done();
      item.size_m = {kSignThicknessM, face.x()};
      item.z_top_m = H;
      item.z_bottom_m = H - drop_m;
      b.box(item.center_m, {kSignThicknessM, face.x(), face.y()}, item.yaw_rad, item.z_bottom_m,
            st, st, std::nullopt);
      const Eigen::Vector2d across(-std::sin(item.yaw_rad), std::cos(item.yaw_rad));
      Style rod = st;
      rod.tile_m = {kSignRodM, rods_m};
      rod.brightness = 0.4 * st.brightness;  // dark metal rods, whatever the face shows
      for (double side : {-1.0, 1.0})
        b.box(item.center_m + side * across * face.x() / 3, {kSignRodM, kSignRodM, rods_m},
              item.yaw_rad, H - rods_m, rod, rod, std::nullopt);
      break;
    }
  }
  // The footprint's corners must lie under the ceiling (the floor's extent).
  const Eigen::Vector2d ex(std::cos(item.yaw_rad), std::sin(item.yaw_rad));
  const Eigen::Vector2d ey(-ex.y(), ex.x());
  for (double sx : {-0.5, 0.5})
    for (double sy : {-0.5, 0.5}) {
      const Eigen::Vector2d c = item.center_m + sx * item.size_m.x() * ex + sy * item.size_m.y() * ey;
      if (c.x() < lo.x() - 1e-9 || c.x() > hi.x() + 1e-9 || c.y() < lo.y() - 1e-9 ||
          c.y() > hi.y() + 1e-9) {
        std::ostringstream os;
        os << "reaches outside the ceiling ([" << lo.x() << ", " << lo.y() << "] .. [" << hi.x()
           << ", " << hi.y() << "] m): corner (" << c.x() << ", " << c.y() << ")";
        m.fail(where_key, os.str());
      }
    }
  if (!drop_key.empty() && H - drop_m < kMinHangingHeightM - 1e-9) {
    std::ostringstream os;
    os << "hangs down to " << H - drop_m << " m above the floor, below the lowest allowed "
       << kMinHangingHeightM << " m (ceiling " << H
       << " m; ceiling items have no collision model)";
    m.fail(drop_key, os.str());
  }
  b.w_.ceiling_items.push_back(item);
}

Pose2D parse_pose(Map& m, const std::string& key) {
  const auto v = m.nums(key, 3, true);
  return {v[0], v[1], v[2] * kDeg};
}

}  // namespace

// ---------------------------------------------------------------------------------------------

const char* to_string(CeilingItemKind kind) {
  for (const CeilingKindName& k : kCeilingKinds)
    if (k.kind == kind) return k.name;
  return "?";
}

CeilingItemKind ceiling_item_kind_from_string(const std::string& name) {
  std::string known;
  for (const CeilingKindName& k : kCeilingKinds) {
    if (name == k.name) return k.kind;
    known += (known.empty() ? "" : ", ") + std::string(k.name);
  }
  throw std::invalid_argument("unknown ceiling item kind '" + name + "' (known: " + known + ")");
}

std::array<Eigen::Vector2d, 4> BoxObstacle::corners_m() const {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  std::array<Eigen::Vector2d, 4> out;
  const double sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
  for (int k = 0; k < 4; ++k) {
    const double lx = sx[k] * half_size_m.x(), ly = sy[k] * half_size_m.y();
    out[static_cast<size_t>(k)] = center_m + Eigen::Vector2d(c * lx - s * ly, s * lx + c * ly);
  }
  return out;
}

Eigen::Vector3d MovingObstacle::pose_at(double t_s) const {
  if (path_m.size() < 2) return {path_m.front().x(), path_m.front().y(), 0.0};
  std::vector<double> cum{0.0};
  for (size_t i = 1; i < path_m.size(); ++i)
    cum.push_back(cum.back() + (path_m[i] - path_m[i - 1]).norm());
  const double P = cum.back();
  double d = start_offset_m + speed_m_s * t_s;
  bool back = false;
  if (loop) {
    d = std::fmod(d, P);
    if (d < 0) d += P;
  } else {
    d = std::fmod(d, 2 * P);
    if (d < 0) d += 2 * P;
    if (d > P) {
      d = 2 * P - d;
      back = true;
    }
  }
  size_t i = 1;
  while (i + 1 < cum.size() && cum[i] < d) ++i;
  const Eigen::Vector2d a = path_m[i - 1], b = path_m[i];
  const double seg = cum[i] - cum[i - 1];
  const double f = seg > 0 ? (d - cum[i - 1]) / seg : 0.0;
  const Eigen::Vector2d p = a + f * (b - a);
  double heading = std::atan2(b.y() - a.y(), b.x() - a.x());
  if (back) heading += M_PI;
  return {p.x(), p.y(), heading};
}

Eigen::Vector3d MovingObstacle::pose_near(double t_s,
                                          const std::optional<Eigen::Vector2d>& robot_m) const {
  Eigen::Vector3d pose = pose_at(t_s);
  if (!robot_m || !(keep_clear_m > 0.0)) return pose;
  Eigen::Vector2d away = pose.head<2>() - *robot_m;
  const double d = away.norm();
  if (d >= keep_clear_m) return pose;
  // On the robot itself (a measure-zero case) the person steps to the side of its heading.
  away = d > 1e-9 ? Eigen::Vector2d(away / d)
                  : Eigen::Vector2d(-std::sin(pose.z()), std::cos(pose.z()));
  pose.head<2>() = *robot_m + keep_clear_m * away;
  return pose;
}

Pose2D Scenario::start_pose() const {
  if (teach_start) return *teach_start;
  if (waypoints_m.size() >= 2) {
    const Eigen::Vector2d d = waypoints_m[1] - waypoints_m[0];
    return {waypoints_m[0].x(), waypoints_m[0].y(), std::atan2(d.y(), d.x())};
  }
  if (waypoints_m.size() == 1) return {waypoints_m[0].x(), waypoints_m[0].y(), 0.0};
  return {};
}

double Scenario::path_length_m() const {
  double len = 0.0;
  for (size_t i = 1; i < waypoints_m.size(); ++i)
    len += (waypoints_m[i] - waypoints_m[i - 1]).norm();
  return len;
}

Pose2D Scenario::replay_start(size_t k, uint64_t seed) const {
  Pose2D p = replay_starts.empty() ? start_pose() : replay_starts[k % replay_starts.size()];
  if (seed == 0) return p;
  uint64_t state =
      seed * 0x9E3779B97F4A7C15ULL ^ (static_cast<uint64_t>(k) + 1) * 0xD1B54A32D192ED03ULL;
  auto uniform_pm1 = [&state] {
    uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return 2.0 * (static_cast<double>(z >> 11) * 0x1.0p-53) - 1.0;
  };
  const double along = perturb_along_m * uniform_pm1();
  const double lateral = perturb_lateral_m * uniform_pm1();
  const double dyaw = perturb_yaw_rad * uniform_pm1();
  const double c = std::cos(p.yaw_rad), s = std::sin(p.yaw_rad);
  p.x_m += c * along - s * lateral;
  p.y_m += s * along + c * lateral;
  p.yaw_rad += dyaw;
  return p;
}

const LightingCondition& World::light(const std::string& condition) const {
  const auto it = lighting.find(condition);
  if (it != lighting.end()) return it->second;
  std::string known;
  for (const auto& [k, v] : lighting) known += (known.empty() ? "" : ", ") + k;
  throw WorldError(source.string() + ": unknown lighting condition '" + condition +
                   "' (known: " + known + ")");
}

namespace {

double dist_point_rect(const Eigen::Vector2d& p, const Eigen::Vector2d& c,
                       const Eigen::Vector2d& half, double yaw) {
  const Eigen::Vector2d d = p - c;
  const double cs = std::cos(yaw), sn = std::sin(yaw);
  const Eigen::Vector2d local(cs * d.x() + sn * d.y(), -sn * d.x() + cs * d.y());
  const Eigen::Vector2d q = local.cwiseAbs() - half;
  return q.cwiseMax(0.0).norm();  // 0 inside
}

}  // namespace

std::optional<std::string> World::collision(const Eigen::Vector2d& p_m, double radius_m,
                                            double t_s) const {
  for (const WallObstacle& w : walls) {
    const Eigen::Vector2d d = w.b_m - w.a_m;
    const Eigen::Vector2d half(0.5 * d.norm(), w.half_thickness_m);
    if (dist_point_rect(p_m, 0.5 * (w.a_m + w.b_m), half, std::atan2(d.y(), d.x())) < radius_m)
      return w.what;
  }
  for (const BoxObstacle& b : boxes)
    if (dist_point_rect(p_m, b.center_m, b.half_size_m, b.yaw_rad) < radius_m) return b.what;
  for (const MovingObstacle& m : people) {
    const Eigen::Vector3d pose = m.pose_near(t_s, p_m);
    if (dist_point_rect(p_m, pose.head<2>(), m.size_m.head<2>() / 2, pose.z()) < radius_m)
      return m.what;
  }
  return std::nullopt;
}

void World::moving_quads(double t_s, std::vector<Quad>& out,
                         const std::optional<Eigen::Vector2d>& robot_m) const {
  if (people.empty()) return;
  World tmp;  // borrow the builder's box code; only its quads are used
  Builder b(tmp, {});
  for (const MovingObstacle& m : people) {
    const Eigen::Vector3d pose = m.pose_near(t_s, robot_m);
    Style s;
    s.texture = m.texture;
    s.tile_m = {m.size_m.y(), m.size_m.z()};
    s.brightness = m.brightness;
    b.box(pose.head<2>(), m.size_m, pose.z(), 0.0, s, s, std::nullopt);
  }
  out.insert(out.end(), tmp.quads.begin(), tmp.quads.end());
}

World parse_world(const std::string& yaml_text, const std::string& source_name,
                  const std::filesystem::path& base_dir) {
  const Src src{source_name};
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw WorldError(source_name + ":" + std::to_string(e.mark.line + 1) +
                     ": YAML syntax error: " + e.msg);
  }
  if (!root || !root.IsMap())
    throw WorldError(source_name + ": expected a YAML mapping at the top");
  Map top(src, root, "");

  World w;
  w.source = source_name;
  w.name = top.str("name", std::filesystem::path(source_name).stem().string());
  w.description = top.str("description", "");
  w.key_light_rad = top.num("key_light_deg", 30.0) * kDeg;

  // Lighting conditions.
  w.lighting["teach"] = {};
  if (auto lm = top.map("lighting")) {
    for (const auto& kv : lm->node()) {
      const std::string cname = kv.first.as<std::string>();
      Map c = Map(src, lm->get(cname), lm->sub(cname));
      LightingCondition l;
      l.ambient = c.nonneg("ambient", 1.0);
      l.windows = c.nonneg("windows", 1.0);
      l.lamps = c.nonneg("lamps", 1.0);
      c.done();
      w.lighting[cname] = l;
    }
    lm->done();
  }
  if (!w.lighting.count("replay")) w.lighting["replay"] = w.lighting["teach"];

  // Textures.
  std::map<std::string, int> tex_index;
  {
    Map tm(src, top.required("textures"), "textures");
    for (const auto& kv : tm.node()) {
      const std::string tname = kv.first.as<std::string>();
      Map t(src, tm.get(tname), tm.sub(tname));
      TextureSpec s;
      s.name = tname;
      try {
        s.kind = texture_kind_from_string(t.str_req("type"));
      } catch (const std::invalid_argument& e) {
        t.fail("type", e.what());
      }
      s.mean = t.num("mean", s.mean);
      s.contrast = t.num("contrast", s.contrast);
      s.cells = t.integer("cells", s.cells);
      s.rows = t.integer("rows", s.rows);
      s.feature_px = t.num("feature_px", s.feature_px);
      s.octaves = t.integer("octaves", s.octaves);
      s.seed = static_cast<uint32_t>(t.integer("seed", static_cast<int>(s.seed)));
      s.size_px = t.integer("size_px", s.size_px);
      s.file = t.str("file", "");
      s.max_size_px = t.integer("max_size_px", s.max_size_px);
      s.repeat = t.boolean("repeat", s.kind != TextureKind::kImage);
      t.done();
      const auto errors = validate(s, base_dir, t.path());
      if (!errors.empty()) fail_at(src, t.node(), t.path(), errors.front());
      try {
        w.textures.push_back(make_texture(s, base_dir));
      } catch (const std::exception& e) {
        fail_at(src, t.node(), t.path(), e.what());
      }
      tex_index[tname] = static_cast<int>(w.textures.size()) - 1;
    }
    tm.done();
  }
  Builder b(w, tex_index);

  // Ceiling height first: walls default to it.
  std::optional<Map> ceiling = top.map("ceiling");
  w.ceiling_height_m = ceiling ? ceiling->positive("height_m", 2.6) : 2.6;

  for (Map& m : top.list("walls")) parse_wall(b, m, w.ceiling_height_m);
  if (w.walls.empty()) top.fail("walls", "a world needs at least one wall");

  // Floor extent: explicit, or the bounds of the walls plus a margin.
  Eigen::Vector2d lo = w.walls.front().a_m, hi = lo;
  for (const WallObstacle& s : w.walls) {
    lo = lo.cwiseMin(s.a_m).cwiseMin(s.b_m);
    hi = hi.cwiseMax(s.a_m).cwiseMax(s.b_m);
  }
  lo -= Eigen::Vector2d(0.5, 0.5);
  hi += Eigen::Vector2d(0.5, 0.5);
  {
    Map f(src, top.required("floor"), "floor");
    if (f.has("extent")) {
      const auto pts = f.points("extent", 2);
      lo = pts[0].cwiseMin(pts[1]);
      hi = pts[0].cwiseMax(pts[1]);
    }
    const Style fs = b.style(f, {1.0, 1.0});
    const double refl = f.nonneg("reflectivity", 0.0);
    if (refl >= 1.0) f.fail("reflectivity", "must be in [0, 1)");
    f.done();
    Quad q = b.quad({lo.x(), hi.y(), 0.0}, Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitY(),
                    hi.x() - lo.x(), hi.y() - lo.y(), fs, false, lo.x(), -hi.y());
    q.is_floor = true;
    q.reflectivity = refl;
    b.add(q);
  }
  w.min_m = lo;
  w.max_m = hi;
  if (ceiling) {
    const Style cs = b.style(*ceiling, {0.6, 0.6});
    ceiling->done();
    b.add(b.quad({lo.x(), lo.y(), w.ceiling_height_m}, Eigen::Vector3d::UnitX(),
                 Eigen::Vector3d::UnitY(), hi.x() - lo.x(), hi.y() - lo.y(), cs, false, lo.x(),
                 lo.y()));
    w.has_ceiling = true;
  }
  {
    auto items = top.list("ceiling_items");
    if (!items.empty() && !ceiling)
      top.fail("ceiling_items", "ceiling items need a `ceiling:` to hang from");
    for (Map& m : items) parse_ceiling_item(b, m, lo, hi, w.ceiling_height_m);
  }

  for (Map& m : top.list("boxes")) {
    const Eigen::Vector2d c = m.vec2_req("center");
    const auto sz = m.nums("size_m", 3, true);
    if (!(sz[0] > 0 && sz[1] > 0 && sz[2] > 0)) m.fail("size_m", "sizes must be > 0");
    const double yaw = m.num("yaw_deg", 0.0) * kDeg;
    const double z0 = m.nonneg("z_m", 0.0);
    const Style side = b.style(m, {1.0, 1.0});
    Style top_style = side;
    if (auto t = m.map("top")) {
      top_style = b.style(*t, {1.0, 1.0});
      t->done();
    }
    std::optional<Style> front;
    if (auto f = m.map("front")) {
      front = b.style(*f, {1.0, 1.0});
      f->done();
    }
    const bool collide = m.boolean("collide", true);
    const std::string what = m.str("name", m.path());
    m.done();
    b.box(c, {sz[0], sz[1], sz[2]}, yaw, z0, side, top_style, front);
    if (collide && z0 < kRobotHeightM) b.obstacle(c, {sz[0], sz[1]}, yaw, what);
  }

  for (Map& m : top.list("tables")) {
    const Eigen::Vector2d c = m.vec2_req("center");
    const Eigen::Vector2d sz = m.vec2_req("size_m");
    const double h = m.positive("height_m", 0.74);
    const double yaw = m.num("yaw_deg", 0.0) * kDeg;
    const Style st = b.style(m, {1.0, 1.0});
    Style leg = st;
    if (auto l = m.map("legs")) {
      leg = b.style(*l, {0.5, 0.5});
      l->done();
    }
    const std::string what = m.str("name", m.path());
    m.done();
    constexpr double kTop = 0.04, kLeg = 0.05;
    b.box(c, {sz.x(), sz.y(), kTop}, yaw, h - kTop, st, st, std::nullopt);
    const Eigen::Vector2d ex(std::cos(yaw), std::sin(yaw)), ey(-ex.y(), ex.x());
    for (double sx : {-1.0, 1.0})
      for (double sy : {-1.0, 1.0}) {
        const Eigen::Vector2d lc =
            c + ex * sx * (sz.x() / 2 - kLeg) + ey * sy * (sz.y() / 2 - kLeg);
        b.box(lc, {kLeg, kLeg, h - kTop}, yaw, 0.0, leg, leg, std::nullopt);
      }
    b.obstacle(c, sz, yaw, what);
  }

  for (Map& m : top.list("lamps")) {
    const Eigen::Vector2d c = m.vec2_req("center");
    const Eigen::Vector2d sz = m.vec2("size_m", {1.2, 0.3});
    const Style st = b.style(m, {1.0, 1.0});
    m.done();
    Quad q = b.quad({c.x() - sz.x() / 2, c.y() - sz.y() / 2, w.ceiling_height_m - 0.005},
                    Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), sz.x(), sz.y(), st, true);
    q.light = LightGroup::kLamps;
    b.add(q);
  }

  for (Map& m : top.list("people")) {
    MovingObstacle p;
    p.path_m = m.points("path", 1);
    p.speed_m_s = m.nonneg("speed_m_s", 0.8);
    const auto sz = m.nums("size_m", 3, false);
    if (!sz.empty()) p.size_m = {sz[0], sz[1], sz[2]};
    p.loop = m.boolean("loop", false);
    p.start_offset_m = m.num("start_offset_m", 0.0);
    p.keep_clear_m = m.nonneg("keep_clear_m", 0.0);
    const Style st = b.style(m, {1.0, 1.0});
    p.texture = st.texture;
    p.brightness = st.brightness;
    p.what = m.str("name", m.path());
    m.done();
    w.people.push_back(p);
  }

  // Scenario.
  if (auto t = top.map("teach")) {
    if (t->has("start")) w.scenario.teach_start = parse_pose(*t, "start");
    if (t->has("waypoints")) w.scenario.waypoints_m = t->points("waypoints", 2);
    w.scenario.teach_speed_m_s = t->positive("speed_m_s", 0.2);
    if (w.scenario.teach_speed_m_s > 0.55) t->fail("speed_m_s", "above Pepper's 0.55 m/s");
    for (Map& s : t->list("script")) {
      VelocityStep step;
      step.v_x_m_s = s.num("v_m_s", 0.0);
      step.omega_rad_s = s.num("omega_deg_s", 0.0) * kDeg;
      step.duration_s = s.positive("duration_s", 1.0);
      s.done();
      w.scenario.velocity_script.push_back(step);
    }
    t->done();
  }
  if (auto r = top.map("replay")) {
    YAML::Node starts = r->get("starts");
    if (starts) {
      if (!starts.IsSequence())
        fail_at(src, starts, "replay.starts", "expected a list of [x, y, yaw_deg]");
      for (size_t i = 0; i < starts.size(); ++i) {
        if (!starts[i].IsSequence() || starts[i].size() != 3)
          fail_at(src, starts[i], "replay.starts[" + std::to_string(i) + "]",
                  "expected [x, y, yaw_deg]");
        try {
          w.scenario.replay_starts.push_back({starts[i][0].as<double>(), starts[i][1].as<double>(),
                                              starts[i][2].as<double>() * kDeg});
        } catch (const YAML::Exception&) {
          fail_at(src, starts[i], "replay.starts[" + std::to_string(i) + "]",
                  "expected three numbers [x, y, yaw_deg]");
        }
      }
    }
    if (auto p = r->map("perturbation")) {
      w.scenario.perturb_lateral_m = p->nonneg("lateral_m", 0.0);
      w.scenario.perturb_along_m = p->nonneg("along_m", 0.0);
      w.scenario.perturb_yaw_rad = p->nonneg("yaw_deg", 0.0) * kDeg;
      p->done();
    }
    r->done();
  }
  top.done();

  // Validation of the scenario against the geometry: the taught path must be drivable.
  const Pose2D start = w.scenario.start_pose();
  if (!w.scenario.waypoints_m.empty() || w.scenario.teach_start) {
    if (auto hit = w.collision({start.x_m, start.y_m}, 0.3, 0.0))
      throw WorldError(source_name + ": teach: start pose collides with " + *hit);
  }
  for (size_t i = 0; i < w.scenario.replay_starts.size(); ++i) {
    const Pose2D& p = w.scenario.replay_starts[i];
    if (auto hit = w.collision({p.x_m, p.y_m}, 0.3, 0.0))
      throw WorldError(source_name + ": replay.starts[" + std::to_string(i) + "]: collides with " +
                       *hit);
  }
  return w;
}

World load_world(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw WorldError(file.string() + ": cannot open world file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_world(ss.str(), file.string(), file.parent_path());
}

std::string summary(const World& w) {
  std::ostringstream os;
  os << "world '" << w.name << "' (" << w.source.string() << ")\n";
  if (!w.description.empty()) os << "  " << w.description << "\n";
  os << "  bounds: [" << w.min_m.x() << ", " << w.min_m.y() << "] .. [" << w.max_m.x() << ", "
     << w.max_m.y() << "] m, ceiling " << w.ceiling_height_m << " m\n";
  os << "  " << w.quads.size() << " quads, " << w.textures.size() << " textures, " << w.walls.size()
     << " wall segments, " << w.boxes.size() << " box obstacles, " << w.people.size()
     << " moving obstacles";
  if (!w.ceiling_items.empty()) {
    std::map<std::string, int> count;
    for (const CeilingItem& c : w.ceiling_items) ++count[to_string(c.kind)];
    os << ", ceiling items:";
    for (const auto& [kind, n] : count) os << " " << n << " " << kind;
  }
  os << "\n";
  for (const auto& [name, l] : w.lighting)
    os << "  lighting '" << name << "': ambient " << l.ambient << ", windows " << l.windows
       << ", lamps " << l.lamps << "\n";
  const Scenario& s = w.scenario;
  const Pose2D st = s.start_pose();
  os << "  teach: start (" << st.x_m << ", " << st.y_m << ", " << st.yaw_rad * 180.0 / M_PI
     << " deg), " << s.waypoints_m.size() << " waypoints, " << s.path_length_m() << " m at "
     << s.teach_speed_m_s << " m/s";
  if (!s.velocity_script.empty()) os << ", script of " << s.velocity_script.size() << " steps";
  os << "\n  replay: " << s.replay_starts.size() << " starts, perturbation +-"
     << s.perturb_lateral_m << " m lateral, +-" << s.perturb_along_m << " m along, +-"
     << s.perturb_yaw_rad * 180.0 / M_PI << " deg\n";
  return os.str();
}

}  // namespace pepper::sim
