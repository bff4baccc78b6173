// `pepper_app world check|render|generate`: inspect the simulated worlds of the mock robot, or
// write a generated one (sim/, docs/mock_robot.md).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>

#include "commands/commands.hpp"
#include "commands/error_advice.hpp"
#include "sim/mock_robot.hpp"
#include "sim/world.hpp"
#include "sim/world_generator.hpp"

namespace pepper::app {

namespace {

struct WorldArgs {
  std::string world;
  std::string pose;  // "x,y,yaw_deg"
  std::string size = "640x480";
  std::string lighting = "teach";
  double head_pitch_deg = 0.0;
  double head_yaw_deg = 0.0;
  double noise_sigma = 1.5;
  uint64_t seed = 1;
  std::string out;
  // generate
  std::string kind = "building";
  std::string textures = std::string(PEPPER_WORLDS_DIR) + "/textures";
  double poor_view_fraction = sim::WorldGeneratorOptions{}.poor_view_fraction;
  double blank_view_prob = sim::WorldGeneratorOptions{}.blank_view_prob;
};

bool parse_pose(const std::string& s, sim::Pose2D& pose) {
  double x, y, yaw_deg;
  char c1, c2;
  std::istringstream is(s);
  if (!(is >> x >> c1 >> y >> c2 >> yaw_deg) || c1 != ',' || c2 != ',') return false;
  pose = {x, y, yaw_deg * M_PI / 180.0};
  return true;
}

bool parse_size(const std::string& s, int& w, int& h) {
  return std::sscanf(s.c_str(), "%dx%d", &w, &h) == 2 && w > 0 && h > 0 && w <= 4096 && h <= 4096;
}

int run_check(const WorldArgs& a) {
  const sim::World w = sim::load_world(a.world);
  std::cout << sim::summary(w);
  std::cout << "OK\n";
  return 0;
}

int run_render(const WorldArgs& a) {
  int w = 0, h = 0;
  if (!parse_size(a.size, w, h)) {
    std::cerr << "pepper_app world render: --size must be WIDTHxHEIGHT, got '" << a.size
              << "': give e.g. 640x480 or 320x240\n";
    return 2;
  }
  auto world = std::make_shared<const sim::World>(sim::load_world(a.world));
  sim::Pose2D pose = world->scenario.start_pose();
  if (!a.pose.empty() && !parse_pose(a.pose, pose)) {
    std::cerr << "pepper_app world render: --pose must be x,y,yaw_deg, got '" << a.pose
              << "': give e.g. 2,1.8,0 (metres, metres, degrees in the world frame)\n";
    return 2;
  }
  sim::MockRobotOptions options;
  options.lighting = a.lighting;
  options.render.noise_sigma_grey = a.noise_sigma;
  options.render.noise_seed = a.seed;
  sim::MockRobot robot(world, options);
  robot.place(pose);
  robot.set_joint_angles({"HeadYaw", "HeadPitch"},
                         {a.head_yaw_deg * M_PI / 180.0, a.head_pitch_deg * M_PI / 180.0});
  const core::Frame frame = robot.capture(w, h);
  if (!cv::imwrite(a.out, frame.gray)) {
    std::cerr << "pepper_app world render: cannot write '" << a.out
              << "': check that its folder exists and is writable\n";
    return 1;
  }
  const auto gt = robot.ground_truth();
  std::cout << "rendered " << w << "x" << h << " from (" << gt.base.x_m << ", " << gt.base.y_m
            << ", " << gt.base.yaw_rad * 180.0 / M_PI << " deg) to " << a.out;
  if (gt.collision) std::cout << " (warning: the pose collides with " << gt.collision->what << ")";
  std::cout << "\n";
  return 0;
}

// Writes the generated world, then loads it back as any world file (textures, validation), so
// that a file this command writes always loads.
int run_generate(const WorldArgs& a) {
  namespace fs = std::filesystem;
  sim::WorldGeneratorOptions o;
  o.seed = a.seed;
  try {
    o.kind = sim::world_kind_from_string(a.kind);
  } catch (const std::invalid_argument& e) {
    std::cerr << "pepper_app world generate: --kind: " << message_with_next_step(e)
              << ": pick one of them\n";
    return 2;
  }
  o.poor_view_fraction = a.poor_view_fraction;
  o.blank_view_prob = a.blank_view_prob;
  const fs::path out = fs::absolute(a.out);
  const fs::path textures = fs::absolute(a.textures);
  if (!fs::exists(textures / "pepper_office_a.jpg")) {
    std::cerr << "pepper_app world generate: --textures: '" << a.textures
              << "' does not hold the shipped photographs (worlds/textures/pepper_office_a.jpg "
                 "...): give the checkout's worlds/textures folder\n";
    return 2;
  }
  // Relative to the world file's folder, as the shipped worlds write them, when both are in one
  // tree (their first two components agree, e.g. a checkout under /work); absolute otherwise
  // (e.g. a world in /tmp).
  const auto head = [](const fs::path& p) {
    const fs::path n = p.lexically_normal();
    fs::path r;
    int k = 0;
    for (const fs::path& part : n) {
      if (k++ == 2) break;
      r /= part;
    }
    return r;
  };
  o.texture_dir = head(out.parent_path()) == head(textures)
                      ? textures.lexically_relative(out.parent_path()).generic_string()
                      : textures.lexically_normal().generic_string();
  if (o.texture_dir.empty()) o.texture_dir = textures.generic_string();
  const auto errors = o.validate();
  if (!errors.empty()) {
    std::cerr << "pepper_app world generate: " << errors.front() << "\n";
    return 2;
  }
  const sim::GeneratedWorld g = sim::generate_world(o);
  if (!out.parent_path().empty()) fs::create_directories(out.parent_path());
  {
    std::ofstream f(out);
    if (!(f << g.yaml)) {
      std::cerr << "pepper_app world generate: cannot write '" << a.out
                << "': check that its folder is writable\n";
      return 1;
    }
  }
  const sim::World w = sim::load_world(out);
  std::cout << "wrote " << a.out << ": " << g.summary() << "\n";
  std::cout << "  " << w.quads.size() << " quads, " << w.walls.size() << " wall segments, "
            << w.boxes.size() << " box obstacles\n";
  return 0;
}

}  // namespace

void register_world_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "world",
      "Inspect a simulated world of the mock robot: check it, render the view of the "
      "top head camera from a pose, or generate a random one.");
  cmd->require_subcommand(1);
  auto args = std::make_shared<WorldArgs>();

  auto* check = cmd->add_subcommand("check", "Parse and validate a world file, print a summary.");
  check->add_option("--world", args->world, "World YAML file (worlds/*.yaml)")->required();
  check->footer("Example:\n  pepper_app world check --world worlds/robotics_room.yaml");
  check->callback([args] {
    try {
      exit_code() = run_check(*args);
    } catch (const std::exception& e) {
      std::cerr << "pepper_app world check: " << message_with_next_step(e) << "\n";
      exit_code() = 1;
    }
  });

  auto* render =
      cmd->add_subcommand("render", "Render the top camera's view from a pose to a PNG.");
  render->add_option("--world", args->world, "World YAML file (worlds/*.yaml)")->required();
  render->add_option("--pose", args->pose,
                     "Base pose x,y,yaw_deg in the world frame (default: teach start)");
  render->add_option("--size", args->size, "Image size WIDTHxHEIGHT")->capture_default_str();
  render->add_option("--lighting", args->lighting, "Lighting condition (teach, replay, ...)")
      ->capture_default_str();
  render
      ->add_option("--head-pitch-deg", args->head_pitch_deg, "HeadPitch, degrees (> 0 looks down)")
      ->capture_default_str();
  render->add_option("--head-yaw-deg", args->head_yaw_deg, "HeadYaw, degrees (> 0 looks left)")
      ->capture_default_str();
  render->add_option("--noise", args->noise_sigma, "Sensor noise sigma, grey levels")
      ->capture_default_str();
  render->add_option("--seed", args->seed, "Noise seed")->capture_default_str();
  render->add_option("--out", args->out, "Output PNG")->required();
  render->footer(
      "Example:\n  pepper_app world render --world worlds/robotics_room.yaml --pose 2,1.8,0 "
      "--size 640x480 --out view.png");
  render->callback([args] {
    try {
      exit_code() = run_render(*args);
    } catch (const std::exception& e) {
      std::cerr << "pepper_app world render: " << message_with_next_step(e) << "\n";
      exit_code() = 1;
    }
  });

  auto* gen = cmd->add_subcommand(
      "generate",
      "Write a random but plausible indoor world (rooms, corridors, doors, turns of 45 to 180 "
      "degrees on the spot and on arcs, furniture, posters, lamps, blank walls at some turns) "
      "with its taught tour and replay starts. The same seed and kind give the same file.");
  gen->add_option("--seed", args->seed, "World seed (any integer)")->required();
  gen->add_option("--kind", args->kind, "room, corridor or building")->capture_default_str();
  gen->add_option("--out", args->out, "Output world file (.yaml)")->required();
  gen->add_option("--textures", args->textures,
                  "Folder of the shipped photographs (default: this build's checkout; written "
                  "relative to the output's folder when both are in one tree)")
      ->capture_default_str();
  gen->add_option("--poor-view-fraction", args->poor_view_fraction,
                  "Fraction of seeds whose every turn and end face blank walls (issue 29)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  gen->add_option("--blank-view-prob", args->blank_view_prob,
                  "In the other worlds, chance that one turn's view is blank")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  gen->footer(
      "Example:\n  pepper_app world generate --seed 7 --kind corridor --out gen/c7.yaml\n"
      "then, e.g.: pepper_app evaluate --world gen/c7.yaml --starts 2 --size 320x240\n"
      "Format, pool and knobs: docs/mock_robot.md (Generated worlds).");
  gen->callback([args] {
    try {
      exit_code() = run_generate(*args);
    } catch (const std::exception& e) {
      std::cerr << "pepper_app world generate: " << message_with_next_step(e) << "\n";
      exit_code() = 1;
    }
  });
}

}  // namespace pepper::app
