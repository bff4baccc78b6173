#pragma once
// Disturbances applied between teach and replay in the closed-loop evaluation
// (docs/evaluation.md): a light change, moved furniture, a walking person, a crowd crossing the
// path, WiFi frame drops and command latency. The first four change the world the replay sees;
// the last two change the robot (MockBridge WiFi options, kinematics latency).
//
// A World is immutable and shared; a disturbed world is a new World built from the same YAML
// file with the changes applied to the YAML tree (boxes and tables moved, a person added) and
// re-parsed by sim::parse_world, or a copy with one more lighting condition. Furniture moves
// and the person's walk are checked against the taught path so that they never block it: an
// item whose move would bring it closer than `min_path_clearance_m` to the path (and closer than
// it was) is moved less (half, then not at all). The crowd's walks cross the path on purpose;
// its people keep clear of the robot instead (sim::MovingObstacle::keep_clear_m: they step
// aside), so the path stays passable and the forward view is what they disturb.
// Deterministic in the seed. Failure: a world without a source file cannot take YAML-level
// disturbances (std::invalid_argument); YAML or world errors propagate (sim::WorldError).

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "sim/world.hpp"

namespace pepper::app::evaluation {

enum class Disturbance { kLight, kFurniture, kPerson, kCrowd, kDrops, kLatency };

const char* to_string(Disturbance d);
/// "light", "furniture", "person", "crowd", "drops", "latency"; throws std::invalid_argument
/// otherwise.
Disturbance parse_disturbance(const std::string& name);
/// A set of disturbances as one name: "none", "light", "light+person", ... (enum order).
std::string disturbance_label(const std::set<Disturbance>& disturbances);

struct DisturbanceOptions {
  /// Light: every light group of the "teach" condition is multiplied by a factor, and the
  /// windows also by the world's own replay change (replay.windows / teach.windows). 0: the
  /// factor spans [light_factor_min, light_factor_max] over the runs (run k of N:
  /// min + (max - min) k / (N - 1); one run: min), so every evaluation covers the range the
  /// targets name (x0.6 to x1.4); otherwise this one factor for every run, in [0.2, 3].
  double light_factor = 0.0;
  double light_factor_min = 0.6;
  double light_factor_max = 1.4;
  /// Furniture: each box and table moves by a seeded random vector of length in
  /// [0.5, 1] x furniture_shift_m and turns by up to +-furniture_yaw_deg. >= 0.
  double furniture_shift_m = 0.25;
  double furniture_yaw_deg = 10.0;
  /// Clearance kept between moved furniture (footprint) and the taught path, m, >= 0.
  /// 0.3 m robot radius + 0.15 m margin for replay deviations.
  double min_path_clearance_m = 0.45;
  /// Person: walks back and forth beside the middle part of the taught path (from 25 % to 65 %
  /// of its length; where that is not free, shorter stretches nearer the ends),
  /// person_offset_m to its side (the first side/offset that is free), m/s.
  double person_offset_m = 0.8;
  double person_speed_m_s = 0.6;
  /// Crowd: crowd_people people, each walking back and forth on a zigzag that crosses the
  /// taught path crowd_crossings times over a stretch of crowd_stretch_m of the tour (so it
  /// also walks along the path), reaching crowd_offset_m to each side (less where a wall or
  /// furniture is nearer, at least 0.35 m: the walk spans the robot's width). The stretches
  /// are spread evenly over the tour (seeded jitter, moved where there is no room); each
  /// person's speed is seeded in [crowd_speed_min_m_s, crowd_speed_max_m_s], its start point
  /// on its walk too. People keep crowd_keep_clear_m from the robot's base (they step aside:
  /// sim::MovingObstacle::keep_clear_m; 0.7 m = 0.3 m robot radius + 0.27 m a person's
  /// half-diagonal + 0.13 m), so they cross in front of the robot but never into it.
  int crowd_people = 5;
  int crowd_crossings = 2;
  double crowd_stretch_m = 3.0;
  double crowd_offset_m = 1.2;
  double crowd_speed_min_m_s = 0.5;
  double crowd_speed_max_m_s = 1.0;
  double crowd_keep_clear_m = 0.7;
  /// Frame drops: probability that a captured frame is lost on the WiFi link, [0, 0.9].
  double drop_probability = 0.15;
  /// Latency: command reception to actuation, s, [0, 2].
  double latency_s = 0.2;

  std::vector<std::string> validate() const;
};

/// What was changed, for the report.
struct DisturbedWorld {
  std::shared_ptr<const sim::World> world;
  std::string lighting = "teach";  ///< condition the replay robot must use
  /// Light range: one condition (and its factor) per run, overriding `lighting`.
  std::vector<std::string> run_lighting;
  std::vector<double> run_light_factors;
  std::vector<std::string> notes;  ///< one line per change ("moved table_1 by 0.21 m", ...)

  /// The lighting condition of run k (0-based).
  const std::string& lighting_of_run(int k) const;
  /// The light factor of run k: 0 without a light disturbance.
  double light_factor_of_run(int k) const;
  double light_factor = 0.0;  ///< fixed factor (or 0)
};

/// The teach lighting times `factor`, with the world's own replay window change on top.
sim::LightingCondition scaled_lighting(const sim::World& world, double factor);

/// The world the replay sees. `taught_path_m` is the path to keep clear (ground truth of the
/// teach drive, or the waypoints; the crowd crosses it). Only kLight, kFurniture, kPerson and
/// kCrowd change the world.
/// `runs`: how many replay runs share it (the light range is spread over them).
DisturbedWorld make_disturbed_world(const std::shared_ptr<const sim::World>& world,
                                    const std::set<Disturbance>& disturbances,
                                    const DisturbanceOptions& options,
                                    const std::vector<Eigen::Vector2d>& taught_path_m,
                                    uint64_t seed, int runs = 1);

}  // namespace pepper::app::evaluation
