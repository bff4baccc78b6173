#include "evaluation/closed_loop.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

#include "core/mapping/drive_odometer.hpp"
#include "core/mapping/teacher.hpp"
#include "evaluation/metrics.hpp"
#include "session/telemetry_json.hpp"
#include "naoqi_bridge/mock/mock_bridge.hpp"
#include "naoqi_bridge/mock/mock_robot.hpp"
#include "naoqi_bridge/mock/teach_driver.hpp"

namespace pepper::app::evaluation {
namespace {

namespace mock = naoqi_bridge::mock;
namespace nav = core::navigator;
using Clock = std::chrono::steady_clock;
constexpr double kDeg = M_PI / 180.0;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Speed used to bound a run's duration: the navigator's turning speed (METHOD.md: 0.08 m/s).
constexpr double kSlowSpeedMS = 0.08;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

}  // namespace

const char* feature_label(core::control::FeatureMode mode) {
  switch (mode) {
    case core::control::FeatureMode::kLinesAndPoints: return "lines+points";
    case core::control::FeatureMode::kLinesOnly: return "lines";
    case core::control::FeatureMode::kPointsOnly: return "points";
  }
  return "?";
}

std::string single_modality_tag(core::control::FeatureMode mode, const std::string& prefix,
                                const std::string& suffix) {
  if (mode == core::control::FeatureMode::kLinesAndPoints) return "";
  return prefix + feature_label(mode) + suffix;
}

std::vector<std::string> EvaluationOptions::validate() const {
  std::vector<std::string> e;
  auto check = [&](bool ok, const std::string& msg) {
    if (!ok) e.push_back(msg);
  };
  check(starts >= 1 && starts <= 1000, "starts = " + std::to_string(starts) + ": must be in [1, 1000]");
  for (int r : only_runs) {
    check(r >= 1 && r <= starts, "run " + std::to_string(r) + ": must be in [1, starts = " +
                                     std::to_string(starts) + "]");
  }
  check(width_px >= 64 && height_px >= 48 && width_px <= 4096 && height_px <= 4096,
        "size " + std::to_string(width_px) + "x" + std::to_string(height_px) +
            ": must be within 64x48 .. 4096x4096");
  check(perturb_lateral_m >= 0 && perturb_lateral_m <= 1.0, "perturb_lateral_m: must be in [0, 1]");
  check(perturb_yaw_deg >= 0 && perturb_yaw_deg <= 45, "perturb_yaw_deg: must be in [0, 45]");
  check(perturb_along_m <= 5.0, "perturb_along_m: must be <= 5 (negative: the world's range)");
  check(converged_after_m >= 0, "converged_after_m: must be >= 0");
  check(converged_below_m >= 0, "converged_below_m: must be >= 0 (0: distance rule alone)");
  check(end_tolerance_m > 0, "end_tolerance_m: must be > 0");
  check(lost_timeout_s > 0, "lost_timeout_s: must be > 0");
  check(divergence_m > 0, "divergence_m: must be > 0");
  check(time_limit_factor >= 1.0, "time_limit_factor: must be >= 1");
  for (const auto& m : disturbance.validate()) e.push_back(m);
  for (const auto& m : navigator.validate()) e.push_back("navigator." + m);
  return e;
}

TeachResult teach_tour(const std::shared_ptr<const mock::World>& world,
                       const EvaluationOptions& options, const ProgressFn& progress) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument("EvaluationOptions: " + errors.front());
  }
  const auto t0 = Clock::now();
  mock::MockRobotOptions ro;
  ro.lighting = "teach";
  ro.render.noise_seed = options.seed;
  mock::MockRobot robot(world, ro);
  mock::MockBridge bridge(robot);
  bridge.connect();
  const core::CameraIntrinsics camera =
      bridge.start_camera({0, options.width_px, options.height_px, 15});
  mock::TeachDriver driver(world->scenario);
  core::mapping::TeachOptions to;
  to.selector = options.key_images;
  to.extractor = options.navigator.extractor;
  // A single-modality evaluation teaches with that modality too (the paper's "lines only" and
  // "points only" are whole systems): key images are chosen from its counts alone.
  to.matcher = core::navigator::matcher_for(options.features, options.navigator.matcher);
  core::mapping::Teacher teacher(camera, to);

  TeachResult out;
  out.world_name = world->name;
  const double dt = 1.0 / ro.frame_rate_hz;
  // Safety bound: the path at a tenth of the teach speed.
  const double max_t_s = 60.0 + 10.0 * world->scenario.path_length_m() /
                                    std::max(world->scenario.teach_speed_m_s, 0.05);
  double t_s = 0.0;
  // The map keeps the distance commanded during teach (as the teach session does on a robot).
  core::mapping::DriveOdometer odometer;
  double v_in_force_m_s = 0.0;
  for (; !driver.done() && t_s < max_t_s; t_s += dt) {
    auto frame = bridge.next_frame(std::chrono::milliseconds(100));
    const mock::GroundTruth gt = robot.ground_truth();
    if (robot.collided()) {
      throw std::runtime_error("teach drive collided with " + gt.collision->what);
    }
    if (frame) {
      const core::mapping::TeachStep st =
          teacher.add_frame(*frame, odometer.on_frame(frame->t_ns, v_in_force_m_s));
      if (st.new_key_frame) out.key_frames.push_back(*st.new_key_frame);
      out.path_m.emplace_back(gt.base.x_m, gt.base.y_m);
      ++out.frames;
    }
    const naoqi_bridge::BaseVelocity cmd = driver.command(gt.base, t_s);
    bridge.move(cmd);
    v_in_force_m_s = cmd.v_x_m_s;
  }
  bridge.stop();
  if (!driver.done()) throw std::runtime_error("teach drive did not finish in time");

  std::ostringstream params;
  params << R"({"evaluation":{"world":")" << world->name << R"(","width_px":)" << options.width_px
         << R"(,"height_px":)" << options.height_px << "}}";
  core::memory::VisualMemory map = teacher.finish(params.str());
  // Frame 0 and the final frame are key images too (the selector reports the ones between).
  out.key_frames.insert(out.key_frames.begin(), 0);
  if (map.key_images.size() == out.key_frames.size() + 1) out.key_frames.push_back(out.frames - 1);
  out.map_dir = options.map_dir.empty()
                    ? std::filesystem::temp_directory_path() /
                          ("pepper_eval_map_" + world->name + "_" +
                           std::to_string(options.width_px) + "x" +
                           std::to_string(options.height_px) +
                           single_modality_tag(options.features, "_") + "_" +
                           std::to_string(::getpid()))
                    : options.map_dir;
  core::memory::save_map(map, out.map_dir);
  out.map = core::memory::load_map(out.map_dir);
  out.length_m = Polyline(out.path_m).length_m();
  out.wall_s = seconds_since(t0);
  if (progress) {
    std::ostringstream os;
    os << "teach " << world->name << single_modality_tag(options.features, " [", "]") << ": "
       << out.frames << " frames, "
       << fmt("%.2f", out.length_m) << " m, " << out.map.key_images.size() << " key images ("
       << fmt("%.2f", key_images_per_m(static_cast<int>(out.map.key_images.size()), out.length_m))
       << " per m), map " << out.map_dir.string() << ", " << fmt("%.1f", out.wall_s) << " s";
    progress(os.str());
  }
  return out;
}

mock::Pose2D replay_start_pose(const mock::World& world, int k, const EvaluationOptions& options) {
  mock::Scenario sc = world.scenario;
  sc.replay_starts = {world.scenario.start_pose()};
  sc.perturb_lateral_m = options.perturb_lateral_m;
  sc.perturb_yaw_rad = options.perturb_yaw_deg * kDeg;
  if (options.perturb_along_m >= 0.0) sc.perturb_along_m = options.perturb_along_m;
  // Redraw (next seed) while the start touches an obstacle (0.3 m footprint + 2 cm).
  for (uint64_t attempt = 0; attempt < 50; ++attempt) {
    const uint64_t seed = options.seed + 7919 * attempt;
    const mock::Pose2D p = sc.replay_start(static_cast<size_t>(k), seed == 0 ? 1 : seed);
    if (!world.collision({p.x_m, p.y_m}, 0.32, 0.0)) return p;
  }
  return world.scenario.start_pose();
}

RunResult replay_run(const TeachResult& teach, const std::shared_ptr<const mock::World>& replay_world,
                     const std::string& lighting, const mock::Pose2D& start, int k,
                     const EvaluationOptions& options) {
  const auto wall0 = Clock::now();
  mock::MockRobotOptions ro;
  ro.lighting = lighting;
  ro.render.noise_seed = options.seed * 1000 + static_cast<uint64_t>(k) + 1;
  if (options.disturbances.count(Disturbance::kLatency)) {
    ro.kinematics.latency_s = options.disturbance.latency_s;
  }
  mock::MockRobot robot(replay_world, ro);
  mock::MockBridgeOptions bo;
  if (options.disturbances.count(Disturbance::kDrops)) {
    bo.wifi.drop_probability = options.disturbance.drop_probability;
    bo.wifi.seed = options.seed * 7 + static_cast<uint64_t>(k);
  }
  mock::MockBridge bridge(robot, bo);
  bridge.connect();
  bridge.start_camera({0, options.width_px, options.height_px, 15});
  robot.place(start);

  nav::NavigatorOptions no = options.navigator;
  no.features = options.features;
  no.controller = options.controller;
  nav::Navigator navigator(teach.map, no);

  const Polyline taught(teach.path_m);
  // The first projection searches the first half of the tour (starts are near its beginning),
  // so that the end of a loop tour is not taken for its start.
  PathTracker tracker(taught, 0.5 * taught.length_m());
  const Eigen::Vector2d end_m = teach.path_m.back();

  RunResult r;
  r.index = k;
  r.start_x_m = start.x_m;
  r.start_y_m = start.y_m;
  r.start_yaw_rad = start.yaw_rad;
  const double dt = 1.0 / ro.frame_rate_hz;
  const double time_limit_s =
      options.time_limit_factor * teach.length_m / kSlowSpeedMS + 20.0;

  mock::GroundTruth gt = robot.ground_truth();
  Eigen::Vector2d last_pos(gt.base.x_m, gt.base.y_m);
  r.start_lateral_m = tracker.update(last_pos).lateral_m;
  bool localized_once = false;
  double stopped_since_s = -1.0;  // sim time since which the robot has had no command
  double t_s = 0.0;
  int stop_frames_after_complete = 0;
  std::vector<double> step_ms;
  std::ofstream trace;
  if (!options.trace_dir.empty()) {
    std::filesystem::create_directories(options.trace_dir);
    // One file per world, modality, disturbance set and run: several --disturbance
    // configurations in one evaluation must not overwrite each other's traces.
    const auto file = options.trace_dir /
                      (teach.world_name + "_" + std::string(feature_label(options.features)) + "_" +
                       disturbance_label(options.disturbances) + "_run" + std::to_string(k + 1) +
                       ".jsonl");
    trace.open(file);
    if (!trace) throw std::runtime_error(file.string() + ": cannot open for writing");
    // First line: where each key image was taught (its ground-truth base position).
    nlohmann::json keys = nlohmann::json::array();
    for (const int64_t f : teach.key_frames) {
      const auto& p = teach.path_m.at(static_cast<std::size_t>(f));
      keys.push_back({{"frame", f}, {"x_m", p.x()}, {"y_m", p.y()}});
    }
    trace << nlohmann::json{{"taught_key_images", keys}}.dump() << '\n';
  }
  for (;; t_s += dt) {
    auto frame = bridge.next_frame(std::chrono::milliseconds(100));
    RunSample smp;
    smp.t_s = t_s;
    smp.frame_received = frame.has_value();
    smp.step_ms = kNaN;
    bool stopped = false;
    std::optional<nav::StepResult> step;
    if (frame) {
      const auto s0 = Clock::now();
      step = navigator.step(*frame);
      const nav::StepResult& res = *step;
      smp.step_ms = 1e3 * seconds_since(s0);
      step_ms.push_back(smp.step_ms);
      const nav::Command& c = res.command;
      if (c.stop) {
        bridge.stop();
        stopped = true;
      } else {
        bridge.move({c.v_m_s, 0.0, c.omega_rad_s});
        smp.v_m_s = c.v_m_s;
        smp.omega_rad_s = c.omega_rad_s;
        localized_once = true;
      }
      smp.n_lines = res.telemetry.n_lines_next;
      smp.n_points = res.telemetry.n_points_next;
      smp.key_next = res.telemetry.in;
      if (c.stop && c.reason == nav::StopReason::kTourComplete) r.tour_complete = true;
      if (c.stop && c.reason != nav::StopReason::kTourComplete && localized_once) ++r.lost_frames;
    } else if (!r.samples.empty()) {
      // Dropped frame: the base keeps the command in force.
      smp.v_m_s = r.samples.back().v_m_s;
      smp.omega_rad_s = r.samples.back().omega_rad_s;
      stopped = smp.v_m_s == 0.0 && smp.omega_rad_s == 0.0;
    }
    gt = robot.ground_truth();
    const Eigen::Vector2d pos(gt.base.x_m, gt.base.y_m);
    r.travelled_m += (pos - last_pos).norm();
    last_pos = pos;
    const PathProjection pr = tracker.update(pos);
    smp.x_m = pos.x();
    smp.y_m = pos.y();
    smp.yaw_rad = gt.base.yaw_rad;
    smp.travelled_m = r.travelled_m;
    smp.s_m = pr.s_m;
    smp.lateral_m = pr.lateral_m;
    r.samples.push_back(smp);
    if (trace) {
      nlohmann::json line = {{"t_s", t_s},
                             {"gt", {{"x_m", pos.x()}, {"y_m", pos.y()}, {"yaw_rad", gt.base.yaw_rad},
                                     {"s_m", pr.s_m}, {"lateral_m", pr.lateral_m}}}};
      if (step) {
        line["command"] = command_to_json(step->command);
        line["telemetry"] = telemetry_to_json(step->telemetry);
      }
      trace << line.dump() << '\n';
    }

    if (robot.collided()) {
      r.outcome = "collision";
      r.detail = gt.collision ? gt.collision->what : "";
      break;
    }
    if (step && step->telemetry.state == nav::NavState::kOverdue) {
      r.outcome = "overdue";
      r.detail = "navigator stopped: no switch after key image " +
                 std::to_string(step->telemetry.ip) + " for far longer than teaching took";
      break;
    }
    if (r.tour_complete) {
      // Let the base come to rest (it decelerates at its limits), then measure.
      if (std::abs(gt.velocity.v_x_m_s) < 1e-3 && std::abs(gt.velocity.omega_rad_s) < 1e-3) break;
      if (++stop_frames_after_complete > 45) break;
      continue;
    }
    if (stopped && !r.tour_complete) {
      if (stopped_since_s < 0) stopped_since_s = t_s;
      if (t_s - stopped_since_s > options.lost_timeout_s) {
        r.outcome = "lost";
        r.detail = localized_once ? "no command for " + fmt("%.1f", options.lost_timeout_s) + " s"
                                  : "never localised";
        break;
      }
    } else {
      stopped_since_s = -1.0;
    }
    if (std::abs(pr.lateral_m) > options.divergence_m) {
      r.outcome = "diverged";
      r.detail = "|lateral| " + fmt("%.2f", std::abs(pr.lateral_m)) + " m";
      break;
    }
    if (pr.s_m > taught.length_m() + options.divergence_m) {
      r.outcome = "overshot";
      r.detail = "drove " + fmt("%.2f", pr.s_m - taught.length_m()) + " m past the taught end";
      break;
    }
    if (t_s > time_limit_s) {
      r.outcome = "timeout";
      r.detail = "after " + fmt("%.0f", t_s) + " s";
      break;
    }
  }
  bridge.stop();
  r.frames = static_cast<int>(r.samples.size());
  r.frames_dropped = static_cast<int>(bridge.frames_dropped());
  r.sim_s = t_s;
  r.final_error_m = (last_pos - end_m).norm();
  if (r.tour_complete && r.outcome.empty()) {
    if (r.final_error_m <= options.end_tolerance_m) {
      r.outcome = "complete";
      r.success = true;
    } else {
      r.outcome = "wrong_end";
      r.detail = "stopped " + fmt("%.2f", r.final_error_m) + " m from the taught end";
    }
  }

  std::vector<double> travelled, lateral, omega, t;
  for (const RunSample& s : r.samples) {
    travelled.push_back(s.travelled_m);
    lateral.push_back(s.lateral_m);
    if (s.frame_received) {
      omega.push_back(s.omega_rad_s);
      t.push_back(s.t_s);
    }
  }
  const DeviationStats ds =
      lateral_stats(travelled, lateral, options.converged_after_m, options.converged_below_m);
  r.lateral_rms_m = ds.rms_m;
  r.lateral_max_m = ds.max_m;
  r.converged_from_m = ds.converged_from_m;
  r.first_under_5cm_m = ds.first_under_5cm_m;
  if (r.success && ds.samples == 0) {
    r.success = false;
    r.outcome = "not_converged";
    r.detail = "|lateral| never below " + fmt("%.2f", options.converged_below_m) + " m";
  }
  r.omega_rate_rms_rad_s2 = rate_rms(omega, t);
  r.step_ms_median = percentile(step_ms, 0.5);
  r.step_ms_p95 = percentile(step_ms, 0.95);
  r.wall_s = seconds_since(wall0);
  return r;
}

Summary summarize(const std::vector<RunResult>& runs, int key_images, double taught_length_m) {
  Summary s;
  s.runs = static_cast<int>(runs.size());
  std::vector<double> rmss, errors, rates, steps;
  s.lateral_max_m = 0.0;
  s.converged_from_max_m = 0.0;
  for (const RunResult& r : runs) {
    s.converged_from_max_m = r.converged_from_m < 0.0
                                 ? kNaN
                                 : std::max(s.converged_from_max_m, r.converged_from_m);
    s.successes += r.success ? 1 : 0;
    if (std::isfinite(r.lateral_rms_m)) rmss.push_back(r.lateral_rms_m);
    if (std::isfinite(r.lateral_max_m)) s.lateral_max_m = std::max(s.lateral_max_m, r.lateral_max_m);
    errors.push_back(r.final_error_m);
    if (std::isfinite(r.omega_rate_rms_rad_s2)) rates.push_back(r.omega_rate_rms_rad_s2);
    for (const RunSample& smp : r.samples) {
      if (std::isfinite(smp.step_ms)) steps.push_back(smp.step_ms);
    }
  }
  auto mean = [](const std::vector<double>& v) {
    if (v.empty()) return kNaN;
    double sum = 0.0;
    for (double x : v) sum += x;
    return sum / static_cast<double>(v.size());
  };
  s.success_rate = s.runs > 0 ? static_cast<double>(s.successes) / s.runs : 0.0;
  s.lateral_rms_m = mean(rmss);
  if (rmss.empty()) s.lateral_max_m = kNaN;
  s.final_error_mean_m = mean(errors);
  s.final_error_max_m = errors.empty() ? kNaN : *std::max_element(errors.begin(), errors.end());
  s.key_images_per_m = key_images_per_m(key_images, taught_length_m);
  s.omega_rate_rms_rad_s2 = mean(rates);
  s.step_ms_median = percentile(steps, 0.5);
  s.step_ms_p95 = percentile(steps, 0.95);
  return s;
}

Evaluation evaluate(const TeachResult& teach, const std::shared_ptr<const mock::World>& world,
                    const EvaluationOptions& options, const ProgressFn& progress) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument("EvaluationOptions: " + errors.front());
  }
  Evaluation ev;
  ev.world_name = world->name;
  ev.features = feature_label(options.features);
  ev.controller = core::navigator::to_string(options.controller);
  ev.size = std::to_string(options.width_px) + "x" + std::to_string(options.height_px);
  for (Disturbance d : options.disturbances) ev.disturbances.push_back(to_string(d));
  ev.key_images = static_cast<int>(teach.map.key_images.size());
  ev.taught_length_m = teach.length_m;
  ev.teach_frames = teach.frames;
  const DisturbedWorld dw = make_disturbed_world(world, options.disturbances, options.disturbance,
                                                 teach.path_m, options.seed);
  ev.disturbance_notes = dw.notes;
  if (progress) {
    for (const auto& n : dw.notes) progress("  disturbance: " + n);
  }
  for (int k = 0; k < options.starts; ++k) {
    if (!options.only_runs.empty() &&
        std::find(options.only_runs.begin(), options.only_runs.end(), k + 1) ==
            options.only_runs.end()) {
      continue;
    }
    const mock::Pose2D start = replay_start_pose(*world, k, options);
    RunResult r = replay_run(teach, dw.world, dw.lighting, start, k, options);
    if (progress) {
      std::ostringstream os;
      os << "[" << ev.features << "] start " << (k + 1) << "/" << options.starts << " ("
         << fmt("%.2f", start.x_m) << ", " << fmt("%.2f", start.y_m) << ", "
         << fmt("%.1f", start.yaw_rad / kDeg) << " deg; lateral "
         << fmt("%+.2f", r.start_lateral_m) << " m): " << r.outcome;
      if (!r.detail.empty()) os << " (" << r.detail << ")";
      os << ", " << fmt("%.1f", r.travelled_m) << " m, converged from "
         << fmt("%.1f", r.converged_from_m) << " m, lateral rms "
         << fmt("%.1f", 100 * r.lateral_rms_m) << " cm max " << fmt("%.1f", 100 * r.lateral_max_m)
         << " cm, end error " << fmt("%.1f", 100 * r.final_error_m) << " cm, step "
         << fmt("%.1f", r.step_ms_median) << " ms, " << r.frames << " frames in "
         << fmt("%.1f", r.wall_s) << " s";
      progress(os.str());
    }
    ev.runs.push_back(std::move(r));
  }
  ev.summary = summarize(ev.runs, ev.key_images, ev.taught_length_m);
  return ev;
}

}  // namespace pepper::app::evaluation
