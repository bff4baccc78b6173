#pragma once
// World: a simulated indoor environment for the mock robot, loaded from a YAML file in worlds/
// (format in docs/mock_robot.md), and the scenario that goes with it (taught path, replay starts).
//
// Frames and units (docs/conventions.md): the `world` frame is fixed, z up, floor at z = 0;
// positions in metres, yaw in radians counter-clockwise from world x (degrees only in the YAML).
// Loading turns the description into render geometry (textured quads, world.quads) and a 2D
// collision model (segments for walls, oriented rectangles for furniture, moving boxes for people).
// Walls are polylines; features along a wall (openings, doors, windows, posters) are placed by the
// distance `at_m` of their centre from the polyline's first point. A wall polyline listed
// counter-clockwise around a room has the room on its left side.
//
// Failure: load_world()/parse_world() throw WorldError whose message names the file, the line and
// the key (e.g. "worlds/x.yaml:12: walls[1].height_m: expected a number"); validation failures
// (unknown texture, missing image, overlapping openings) are reported the same way.
// Thread-safety: a loaded World is immutable; share it as std::shared_ptr<const World>.

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/texture.hpp"

namespace pepper::sim {

/// A world file that cannot be read, parsed or validated. what() names file, line and key.
class WorldError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Which light a surface responds to: room light (ambient), daylight (windows), ceiling lamps.
enum class LightGroup : uint8_t { kAmbient = 0, kWindows = 1, kLamps = 2 };

/// Multipliers of each light group for one lighting condition (e.g. "teach", "replay").
struct LightingCondition {
  double ambient = 1.0;
  double windows = 1.0;
  double lamps = 1.0;
};

/// A planar textured rectangle: corners origin, origin + size_u * axis_u, ... (axes orthonormal).
/// Texture coordinates: one texture repetition every tile_u_m x tile_v_m metres; for a
/// non-repeating texture, tile = size (stretched once). v runs along axis_v (image rows go down
/// the texture, so walls use axis_v pointing down from their top edge).
struct Quad {
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_u = Eigen::Vector3d::UnitX();
  Eigen::Vector3d axis_v = Eigen::Vector3d::UnitY();
  double size_u_m = 1.0;
  double size_v_m = 1.0;
  int texture = 0;  ///< index into World::textures
  double tile_u_m = 1.0;
  double tile_v_m = 1.0;
  double offset_u_m = 0.0;  ///< texture shift, metres (so adjacent wall pieces line up)
  double offset_v_m = 0.0;
  double brightness = 1.0;  ///< albedo multiplier
  LightGroup light = LightGroup::kAmbient;
  double reflectivity = 0.0;  ///< > 0 only for a shiny floor: mirror image blended in
  bool is_floor = false;
};

/// 2D obstacle: a wall piece, the rectangle of the segment a-b widened by half_thickness_m on
/// each side. Its ends are flat, as the rendered wall's: an opening is as wide for collisions as
/// the world file says (a rounded end reached half_thickness_m into it).
struct WallObstacle {
  Eigen::Vector2d a_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d b_m = Eigen::Vector2d::Zero();
  double half_thickness_m = 0.05;
  std::string what;  ///< e.g. "walls[2] segment 1"
};

/// 2D obstacle: footprint of a box (furniture, door-frame jamb), an oriented rectangle.
struct BoxObstacle {
  Eigen::Vector2d center_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d half_size_m = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;
  std::string what;

  /// The footprint's four corners in the world frame, counter-clockwise (for drawing).
  std::array<Eigen::Vector2d, 4> corners_m() const;
};

/// A person-sized textured box walking a polyline at constant speed (ping-pong or loop).
/// People are kinematic: they walk their polyline whatever is in the way, unless keep_clear_m
/// > 0: then they step aside for the robot (pose_near), as people in a crowd do.
struct MovingObstacle {
  std::vector<Eigen::Vector2d> path_m;
  double speed_m_s = 0.8;
  Eigen::Vector3d size_m{0.45, 0.3, 1.7};  ///< along heading, across, height
  bool loop = false;                       ///< false: walk back and forth
  double start_offset_m = 0.0;             ///< distance along the path at t = 0
  int texture = 0;
  double brightness = 1.0;
  std::string what;
  /// > 0: the person never comes closer than this to the robot's base (rotation axis), metres:
  /// where its walk would, it stands this far from the robot on the ray from the robot through
  /// its walk's position (it steps aside, and walks on once the robot has passed). 0: kinematic.
  /// Keeping clear of a robot of radius r needs keep_clear_m > r + the footprint's half
  /// diagonal (0.3 + 0.27 m for Pepper and the default size).
  double keep_clear_m = 0.0;

  /// Centre (x, y) and heading (rad) of its walk at simulated time t_s (the robot ignored).
  Eigen::Vector3d pose_at(double t_s) const;
  /// Where it stands at t_s when the robot's base is at robot_m: pose_at(t_s), stepped aside
  /// to keep_clear_m from robot_m (see keep_clear_m; the heading is its walk's). Without a
  /// robot, or with keep_clear_m = 0, pose_at(t_s).
  Eigen::Vector3d pose_near(double t_s, const std::optional<Eigen::Vector2d>& robot_m) const;
};

/// What a ceiling fixture is (YAML `ceiling_items[i].kind`, ceiling_item_kind_from_string).
enum class CeilingItemKind {
  kVent,       ///< grille: a textured rectangle just under the ceiling
  kTile,       ///< one replaced, stained or missing ceiling tile: a rectangle under the ceiling
  kSprinkler,  ///< small square head (6 cm) a few cm proud of the ceiling
  kDetector,   ///< smoke detector: a larger square (12 cm) a few cm proud
  kBeam,       ///< a box hanging below the ceiling between two points (seen from below and side)
  kSign,       ///< exit sign: a thin box hanging on two rods (seen from the forward view too)
};

const char* to_string(CeilingItemKind kind);
/// Throws std::invalid_argument listing the valid names when `name` is unknown.
CeilingItemKind ceiling_item_kind_from_string(const std::string& name);

/// A ceiling fixture as placed (its render quads are in World::quads): an oriented box whose
/// footprint is centred on center_m, size_m.x() along yaw_rad and size_m.y() across it, from
/// z_bottom_m up to z_top_m (flat kinds: both a few millimetres under the ceiling).
struct CeilingItem {
  CeilingItemKind kind = CeilingItemKind::kVent;
  std::string what;  ///< name, or e.g. "ceiling_items[3]"
  Eigen::Vector2d center_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d size_m = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;
  double z_bottom_m = 0.0;
  double z_top_m = 0.0;
};

/// A 2D pose in the world frame.
struct Pose2D {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;  ///< counter-clockwise from world x
};

/// One constant-velocity piece of a scripted teach drive.
struct VelocityStep {
  double v_x_m_s = 0.0;
  double omega_rad_s = 0.0;
  double duration_s = 0.0;
};

/// The experiment that goes with a world: how the teach drive goes and where replays start.
struct Scenario {
  std::optional<Pose2D> teach_start;         ///< default: first waypoint, facing the second
  std::vector<Eigen::Vector2d> waypoints_m;  ///< taught path (followed by PathFollower)
  double teach_speed_m_s = 0.2;
  std::vector<VelocityStep> velocity_script;  ///< alternative to waypoints (open loop)
  std::vector<Pose2D> replay_starts;          ///< explicit replay start poses
  double perturb_lateral_m = 0.0;             ///< replay start perturbation ranges (+-)
  double perturb_along_m = 0.0;
  double perturb_yaw_rad = 0.0;

  /// Teach start pose (explicit, or derived from the first two waypoints).
  Pose2D start_pose() const;
  /// Length of the waypoint polyline, metres.
  double path_length_m() const;
  /// Start pose of replay run `k`: replay_starts[k % size] (the teach start when none are
  /// listed), shifted by uniform draws within +-perturb_along_m (along its heading),
  /// +-perturb_lateral_m (to its left) and +-perturb_yaw_rad. Deterministic in (k, seed); seed 0
  /// gives the unperturbed pose.
  Pose2D replay_start(size_t k, uint64_t seed) const;
};

struct World {
  std::filesystem::path source;  ///< file it was loaded from
  std::string name;
  std::string description;
  std::vector<Texture> textures;
  std::vector<Quad> quads;  ///< static render geometry
  std::vector<WallObstacle> walls;
  std::vector<BoxObstacle> boxes;
  std::vector<MovingObstacle> people;
  std::map<std::string, LightingCondition> lighting;  ///< always has "teach" and "replay"
  double key_light_rad = 0.5;  ///< direction of the light that shades walls by orientation
  Eigen::Vector2d min_m = Eigen::Vector2d::Zero();  ///< bounds of the floor
  Eigen::Vector2d max_m = Eigen::Vector2d::Zero();
  double ceiling_height_m = 2.6;
  bool has_ceiling = false;                ///< the file has a `ceiling:` (else nothing is drawn)
  std::vector<CeilingItem> ceiling_items;  ///< fixtures under the ceiling, in file order
  Scenario scenario;

  /// Lighting condition by name; throws WorldError listing the known names.
  const LightingCondition& light(const std::string& condition) const;

  /// What a disc of radius_m at p_m (at time t_s, for the moving obstacles) touches, or nullopt.
  /// The disc is the robot's: people who keep clear (MovingObstacle::keep_clear_m) step aside
  /// from p_m.
  std::optional<std::string> collision(const Eigen::Vector2d& p_m, double radius_m,
                                       double t_s) const;

  /// Render quads of the moving obstacles at time t_s (appended to `out`), with the robot's
  /// base at robot_m (people who keep clear step aside from it; MovingObstacle::pose_near).
  void moving_quads(double t_s, std::vector<Quad>& out,
                    const std::optional<Eigen::Vector2d>& robot_m = std::nullopt) const;
};

/// Loads, builds and validates a world file. Relative texture files resolve against its folder.
World load_world(const std::filesystem::path& file);

/// Same from YAML text; `source_name` is used in error messages, `base_dir` for texture files.
World parse_world(const std::string& yaml_text, const std::string& source_name,
                  const std::filesystem::path& base_dir);

/// A few lines describing the world (counts, bounds, lighting, scenario), for `world check`.
std::string summary(const World& world);

}  // namespace pepper::sim
