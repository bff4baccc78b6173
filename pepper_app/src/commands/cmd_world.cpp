// `pepper_app world check|render`: inspect the simulated worlds of the mock robot
// (sim/, docs/mock_robot.md).
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>

#include "commands/commands.hpp"
#include "sim/mock_robot.hpp"
#include "sim/world.hpp"

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
    std::cerr << "pepper_app world render: --size must be WIDTHxHEIGHT, got '" << a.size << "'\n";
    return 2;
  }
  auto world = std::make_shared<const sim::World>(sim::load_world(a.world));
  sim::Pose2D pose = world->scenario.start_pose();
  if (!a.pose.empty() && !parse_pose(a.pose, pose)) {
    std::cerr << "pepper_app world render: --pose must be x,y,yaw_deg, got '" << a.pose << "'\n";
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
    std::cerr << "pepper_app world render: cannot write '" << a.out << "'\n";
    return 1;
  }
  const auto gt = robot.ground_truth();
  std::cout << "rendered " << w << "x" << h << " from (" << gt.base.x_m << ", " << gt.base.y_m
            << ", " << gt.base.yaw_rad * 180.0 / M_PI << " deg) to " << a.out;
  if (gt.collision) std::cout << " (warning: the pose collides with " << gt.collision->what << ")";
  std::cout << "\n";
  return 0;
}

}  // namespace

void register_world_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "world",
      "Inspect a simulated world of the mock robot: check it, or render the view of the "
      "top head camera from a pose.");
  cmd->require_subcommand(1);
  auto args = std::make_shared<WorldArgs>();

  auto* check = cmd->add_subcommand("check", "Parse and validate a world file, print a summary.");
  check->add_option("--world", args->world, "World YAML file (worlds/*.yaml)")->required();
  check->footer("Example:\n  pepper_app world check --world worlds/robotics_room.yaml");
  check->callback([args] {
    try {
      exit_code() = run_check(*args);
    } catch (const std::exception& e) {
      std::cerr << "pepper_app world check: " << e.what() << "\n";
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
      std::cerr << "pepper_app world render: " << e.what() << "\n";
      exit_code() = 1;
    }
  });
}

}  // namespace pepper::app
