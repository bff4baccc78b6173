#pragma once
// World generator: a random but plausible indoor world for the mock robot, written in the world
// file format (docs/mock_robot.md, "Generated worlds"), with its scenario (a taught tour and its
// replay starts). It exists so that the navigator can be measured on worlds nobody tuned it for
// (issue 26) and on turns that face blank or low-texture walls (issue 29).
//
// Kinds: a furnished room with a tour of several turns; a corridor with bends and blank ends; a
// building (room -> doorway -> corridor -> doorway -> room). Turns are 45 to 180 degrees, either
// on the spot (a corner of the taught polyline, where the scripted teach drive turns in place)
// or on an arc (the polyline follows a circle). Textures, posters and furniture are drawn from a
// fixed pool: the procedural textures the shipped worlds use and the shipped photographs in
// worlds/textures/.
//
// Contract: pure and deterministic: the same options give the same YAML text, byte for byte, on
// one platform (own random generator, no std distributions, no clock, no file access). Every
// world it returns has been checked on its own geometry: the taught polyline keeps at least
// min_clearance_m from every wall, jamb and piece of furniture, the scripted teach drive (driven
// on the base kinematics, without rendering) keeps at least min_drive_clearance_m, and walls do
// not cross. An attempt that fails a check is thrown away and the next one is drawn from the same
// seed; generate_world() throws std::runtime_error if none of max_attempts passes.
// Units: metres and radians in the code, degrees only in the YAML and the report.

#include <cstdint>
#include <string>
#include <vector>

namespace pepper::sim {

enum class WorldKind { kRoom, kCorridor, kBuilding };

/// "room", "corridor" or "building".
const char* to_string(WorldKind kind);
/// Throws std::invalid_argument listing the valid names.
WorldKind world_kind_from_string(const std::string& name);

struct WorldGeneratorOptions {
  uint64_t seed = 1;
  WorldKind kind = WorldKind::kBuilding;
  /// Folder of the shipped photographs as written in the YAML, relative to the world file's
  /// folder (or absolute): the generator does not read it, `world generate` checks it.
  std::string texture_dir = "textures";
  /// Fraction of seeds whose every turn and the tour's end face a blank or low-texture wall
  /// (issue 29); in the other worlds each such view is blank with probability blank_view_prob.
  double poor_view_fraction = 0.4;
  double blank_view_prob = 0.25;
  double min_clearance_m = 0.6;        ///< taught polyline to walls, jambs, furniture
  double min_drive_clearance_m = 0.45; ///< scripted teach drive (robot centre) to the same
  int max_attempts = 400;
  /// Side of the procedural textures and longest side of the photographs, pixels. The default
  /// is the shipped worlds' (sharp at VGA); smaller loads much faster (tests over many seeds).
  int texture_size_px = 256;

  /// Messages naming each invalid field; empty when valid.
  std::vector<std::string> validate() const;
};

/// One turn of the taught tour, in the order driven.
struct GeneratedTurn {
  double angle_deg = 0.0;    ///< signed, > 0 turns left
  bool on_arc = false;       ///< false: on the spot
  double radius_m = 0.0;     ///< arc radius (0 on the spot)
  bool faces_blank = false;  ///< the view while approaching it has no poster, door or furniture
};

struct GeneratedWorld {
  std::string yaml;  ///< the world file
  WorldKind kind = WorldKind::kBuilding;
  uint64_t seed = 0;
  bool poor_view = false;  ///< every turn and the end face blank walls
  double path_length_m = 0.0;
  std::vector<GeneratedTurn> turns;
  int attempts = 0;  ///< attempts drawn before one passed the checks
  double min_clearance_m = 0.0;        ///< measured on the taught polyline
  double min_drive_clearance_m = 0.0;  ///< measured on the simulated teach drive

  /// One line: kind, seed, length, turns (angle, spot/arc, blank), clearances.
  std::string summary() const;
};

/// The world for `options` (see the contract above). Throws std::invalid_argument for invalid
/// options, std::runtime_error when no attempt passes the checks.
GeneratedWorld generate_world(const WorldGeneratorOptions& options);

}  // namespace pepper::sim
