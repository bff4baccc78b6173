#include "evaluation/closed_loop.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

#include "evaluation/metrics.hpp"
#include "naoqi_bridge/mock_bridge.hpp"
#include "session/ceiling_replay.hpp"
#include "session/robot_connection.hpp"
#include "session/session_link.hpp"
#include "session/teach_session.hpp"
#include "session/telemetry_json.hpp"
#include "sim/mock_robot.hpp"

namespace pepper::app::evaluation {
namespace {

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
  check(give_up_lost_s > 0, "give_up_lost_s: must be > 0");
  check(give_up_not_localised_s > 0, "give_up_not_localised_s: must be > 0");
  check(divergence_m > 0, "divergence_m: must be > 0");
  check(time_limit_factor >= 1.0, "time_limit_factor: must be >= 1");
  for (const auto& m : disturbance.validate()) e.push_back(m);
  for (const auto& m : navigator.validate()) e.push_back("navigator." + m);
  return e;
}

TeachResult teach_tour(const std::shared_ptr<const sim::World>& world,
                       const EvaluationOptions& options, const ProgressFn& progress) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument("EvaluationOptions: " + errors.front());
  }
  const auto t0 = Clock::now();
  TeachResult out;
  out.world_name = world->name;
  out.map_dir = options.map_dir.empty()
                    ? std::filesystem::temp_directory_path() /
                          ("pepper_eval_map_" + world->name + "_" +
                           std::to_string(options.width_px) + "x" +
                           std::to_string(options.height_px) +
                           single_modality_tag(options.features, "_") +
                           (options.mode == core::NavMode::kCeiling ? "_ceiling" : "") + "_" +
                           std::to_string(::getpid()))
                    : options.map_dir;

  // The teach session that `teach --scripted` runs, on a simulated robot of this evaluation.
  sim::MockRobotOptions ro;
  ro.lighting = "teach";
  ro.render.noise_seed = options.seed;
  ro.intrinsics_vga = mock_camera_vga(options);
  RobotConnection robot = open_mock_robot(world, ro, {});
  TeachSessionOptions so;
  so.map_dir = out.map_dir;
  so.camera = camera_request(options);
  so.camera_model = app_camera_model(options);
  so.head = options.head;
  so.mode = options.mode;
  so.teach.selector = options.key_images;
  so.teach.extractor = options.navigator.extractor;
  // A single-modality evaluation teaches with that modality too (the paper's "lines only" and
  // "points only" are whole systems): key images are chosen from its counts alone.
  so.teach.matcher = core::navigator::matcher_for(options.features, options.navigator.matcher);
  so.scripted = true;
  // Safety bound: the path at a tenth of the teach speed.
  const double max_t_s = 60.0 + 10.0 * world->scenario.path_length_m() /
                                    std::max(world->scenario.teach_speed_m_s, 0.05);
  so.max_frames = static_cast<int64_t>(max_t_s * ro.frame_rate_hz);
  std::ostringstream params;
  params << R"({"evaluation":{"world":")" << world->name << R"(","width_px":)" << options.width_px
         << R"(,"height_px":)" << options.height_px << "}}";
  so.config_json = params.str();
  SessionLink link(nullptr, nullptr);
  const app::TeachResult taught = run_teach_session(robot, so, link);
  if (!taught.ok()) {
    throw std::runtime_error("teach " + taught.outcome + ": " +
                             (taught.error.empty() ? "map not saved" : taught.error));
  }
  if (taught.frames_recorded >= so.max_frames) {
    throw std::runtime_error("teach drive did not finish in time");
  }
  core::memory::LoadOptions load;
  load.expected_mode = options.mode;
  out.map = core::memory::load_map(out.map_dir, load);
  out.path_m = taught.path_m;
  out.key_m = taught.key_m;
  out.key_yaw_rad = taught.key_yaw_rad;
  out.frames = static_cast<int>(taught.frames_recorded);
  out.length_m = Polyline(out.path_m).length_m();
  out.wall_s = seconds_since(t0);
  if (progress) {
    std::ostringstream os;
    os << "teach " << world->name << single_modality_tag(options.features, " [", "]");
    if (options.lens != EvaluationOptions::Lens::kNone) os << " (lens: " << lens_label(options) << ")";
    os << ": "
       << out.frames << " frames, "
       << fmt("%.2f", out.length_m) << " m, " << out.map.key_images.size() << " key images ("
       << fmt("%.2f", key_images_per_m(static_cast<int>(out.map.key_images.size()), out.length_m))
       << " per m), map " << out.map_dir.string() << ", " << fmt("%.1f", out.wall_s) << " s";
    progress(os.str());
  }
  return out;
}

sim::Pose2D replay_start_pose(const sim::World& world, int k, const EvaluationOptions& options) {
  if (options.seed == 0) return world.scenario.start_pose();
  sim::Scenario sc = world.scenario;
  sc.replay_starts = {world.scenario.start_pose()};
  sc.perturb_lateral_m = options.perturb_lateral_m;
  sc.perturb_yaw_rad = options.perturb_yaw_deg * kDeg;
  if (options.perturb_along_m >= 0.0) sc.perturb_along_m = options.perturb_along_m;
  // Redraw (next seed) while the start touches an obstacle (0.3 m footprint + 2 cm).
  for (uint64_t attempt = 0; attempt < 50; ++attempt) {
    const uint64_t seed = options.seed + 7919 * attempt;
    const sim::Pose2D p = sc.replay_start(static_cast<size_t>(k), seed == 0 ? 1 : seed);
    if (!world.collision({p.x_m, p.y_m}, 0.32, 0.0)) return p;
  }
  return world.scenario.start_pose();
}

namespace {

/// Run k's simulated robot and WiFi link (everything of MockReplaySetup but the start pose).
void set_run_options(MockReplaySetup& setup, int k, const std::string& lighting,
                     const EvaluationOptions& options) {
  setup.robot.lighting = lighting;
  setup.robot.intrinsics_vga = mock_camera_vga(options);
  setup.robot.render.noise_seed = options.seed * 1000 + static_cast<uint64_t>(k) + 1;
  if (options.disturbances.count(Disturbance::kLatency)) {
    setup.robot.kinematics.latency_s = options.disturbance.latency_s;
  }
  if (options.disturbances.count(Disturbance::kDrops)) {
    setup.bridge.wifi.drop_probability = options.disturbance.drop_probability;
    setup.bridge.wifi.seed = options.seed * 7 + static_cast<uint64_t>(k);
  }
}

}  // namespace

MockReplaySetup mock_replay_setup(const sim::World& start_world, int k, const std::string& lighting,
                                  const EvaluationOptions& options) {
  MockReplaySetup setup;
  setup.start = replay_start_pose(start_world, k, options);
  set_run_options(setup, k, lighting, options);
  return setup;
}

void set_lens_options(const std::string& lens, const std::string& correction,
                      EvaluationOptions& options) {
  if (lens == "none") {
    options.lens = EvaluationOptions::Lens::kNone;
  } else if (lens == "pepper") {
    options.lens = EvaluationOptions::Lens::kPepper;
  } else {
    throw std::invalid_argument("--lens must be none or pepper, got '" + lens + "'");
  }
  if (correction == "on") {
    options.correct_lens = true;
  } else if (correction == "off") {
    options.correct_lens = false;
  } else {
    throw std::invalid_argument("--lens-correction must be on or off, got '" + correction + "'");
  }
}

core::CameraIntrinsics mock_camera_vga(const EvaluationOptions& options) {
  return options.lens == EvaluationOptions::Lens::kPepper
             ? core::CameraIntrinsics::pepper_top_vga_with_distortion()
             : core::CameraIntrinsics::pepper_top_vga();
}

std::optional<core::CameraIntrinsics> app_camera_model(const EvaluationOptions& options) {
  // Without correction the app holds the pinhole calibration of the same camera, as a robot
  // whose calibration file has no distortion model would give it (the bridge reports the lens).
  if (options.lens != EvaluationOptions::Lens::kNone && !options.correct_lens) {
    return core::CameraIntrinsics::pepper_top_vga();
  }
  return std::nullopt;
}

std::string lens_label(const EvaluationOptions& options) {
  if (options.lens == EvaluationOptions::Lens::kNone) return "none";
  return options.correct_lens ? "pepper" : "pepper uncorrected";
}

naoqi_bridge::CameraRequest camera_request(const EvaluationOptions& options) {
  naoqi_bridge::CameraRequest request;
  request.width_px = options.width_px;
  request.height_px = options.height_px;
  request.fps = 15;  // the mock's lockstep rate (MockRobotOptions::frame_rate_hz)
  return request;
}

namespace {

/// What the robot navigates by, as the evaluation reports it and names its traces: "ceiling" in
/// ceiling mode, else the forward modality (feature_label).
std::string navigates_by(const EvaluationOptions& options) {
  return options.mode == core::NavMode::kCeiling ? "ceiling" : feature_label(options.features);
}

/// The evaluation's view of a replay: ground truth per loop iteration (also for dropped frames,
/// when the base keeps the command in force), the trace, and the ends that only ground truth can
/// see (left the path, drove past its end, out of time).
class GroundTruthMonitor final : public ReplayMonitor {
 public:
  GroundTruthMonitor(sim::MockRobot& robot, const TeachResult& teach,
                     const EvaluationOptions& options, RunResult& run, std::ofstream* trace)
      : robot_(robot),
        options_(options),
        run_(run),
        trace_(trace),
        taught_(teach.path_m),
        // The first projection searches the first half of the tour (starts are near its
        // beginning), so that the end of a loop tour is not taken for its start.
        tracker_(taught_, 0.5 * taught_.length_m()),
        dt_s_(1.0 / robot.options().frame_rate_hz),
        time_limit_s_(options.time_limit_factor * teach.length_m / kSlowSpeedMS + 20.0) {
    const sim::GroundTruth gt = robot_.ground_truth();
    last_pos_ = {gt.base.x_m, gt.base.y_m};
    run_.start_lateral_m = tracker_.update(last_pos_).lateral_m;
  }

  /// Ceiling mode: the step's ceiling telemetry (pose in the mosaic, the fix) for the trace.
  void set_ceiling_telemetry(std::function<nlohmann::json()> f) {
    ceiling_telemetry_ = std::move(f);
  }

  std::optional<ReplayEnd> after_iteration(const nav::StepResult* step,
                                           const ReplaySample* sample) override {
    RunSample smp;
    smp.frame_received = step != nullptr;
    smp.step_ms = kNaN;
    if (step) {
      const nav::Command& c = step->command;
      smp.step_ms = sample->step_ms;
      if (!c.stop) {
        smp.v_m_s = c.v_m_s;
        smp.omega_rad_s = c.omega_rad_s;
        localized_once_ = true;
      }
      smp.n_lines = step->telemetry.n_lines_next;
      smp.n_points = step->telemetry.n_points_next;
      smp.key_next = step->telemetry.in;
      if (c.stop && c.reason != nav::StopReason::kTourComplete && localized_once_) {
        ++run_.lost_frames;
      }
      const nav::Telemetry& tel = step->telemetry;
      smp.dead_reckoning = tel.state == nav::NavState::kDeadReckoning;
      run_.dead_reckoning_frames += smp.dead_reckoning;
      run_.line_heading_frames += std::isfinite(tel.line_yaw_correction_rad);
      if (tel.reacquired) {
        run_.reacquisitions.push_back({tel.dead_reckoned_m, tel.dead_reckoned_rad, kNaN, kNaN});
      }
      if (std::isfinite(tel.drift_corrected_m) && !run_.reacquisitions.empty()) {
        run_.reacquisitions.back().corrected_m = tel.drift_corrected_m;
        run_.reacquisitions.back().corrected_rad = tel.drift_corrected_rad;
      }
    } else if (!run_.samples.empty()) {
      // Dropped frame: the base keeps the command in force.
      smp.v_m_s = run_.samples.back().v_m_s;
      smp.omega_rad_s = run_.samples.back().omega_rad_s;
    }
    const PathProjection pr = record(smp, step);
    if (std::abs(pr.lateral_m) > options_.divergence_m) {
      return ReplayEnd{"diverged", "|lateral| " + fmt("%.2f", std::abs(pr.lateral_m)) + " m"};
    }
    if (pr.s_m > taught_.length_m() + options_.divergence_m) {
      return ReplayEnd{"overshot",
                       "drove " + fmt("%.2f", pr.s_m - taught_.length_m()) + " m past the taught end"};
    }
    if (t_s_ > time_limit_s_) return ReplayEnd{"timeout", "after " + fmt("%.0f", t_s_) + " s"};
    t_s_ += dt_s_;
    return std::nullopt;
  }

  /// After the session ended on the end of the tour: the base decelerates at its limits; let it
  /// come to rest (at most 3 s) before the final position is measured.
  void settle() {
    for (int i = 0; i < 45; ++i) {
      const sim::GroundTruth gt = robot_.ground_truth();
      if (std::abs(gt.velocity.v_x_m_s) < 1e-3 && std::abs(gt.velocity.omega_rad_s) < 1e-3) return;
      robot_.advance_s(dt_s_);
      t_s_ += dt_s_;
      RunSample smp;
      smp.frame_received = false;
      smp.step_ms = kNaN;
      record(smp, nullptr);
    }
  }

  double sim_s() const { return t_s_; }
  Eigen::Vector2d last_position() const { return last_pos_; }
  bool localized_once() const { return localized_once_; }

 private:
  PathProjection record(RunSample& smp, const nav::StepResult* step) {
    const sim::GroundTruth gt = robot_.ground_truth();
    const Eigen::Vector2d pos(gt.base.x_m, gt.base.y_m);
    run_.travelled_m += (pos - last_pos_).norm();
    last_pos_ = pos;
    const PathProjection pr = tracker_.update(pos);
    smp.t_s = t_s_;
    smp.x_m = pos.x();
    smp.y_m = pos.y();
    smp.yaw_rad = gt.base.yaw_rad;
    smp.travelled_m = run_.travelled_m;
    smp.s_m = pr.s_m;
    smp.lateral_m = pr.lateral_m;
    run_.samples.push_back(smp);
    if (trace_ && *trace_) {
      nlohmann::json line = {{"t_s", t_s_},
                             {"gt", {{"x_m", pos.x()}, {"y_m", pos.y()}, {"yaw_rad", gt.base.yaw_rad},
                                     {"s_m", pr.s_m}, {"lateral_m", pr.lateral_m}}}};
      if (step) {
        line["command"] = command_to_json(step->command);
        line["telemetry"] = telemetry_to_json(step->telemetry);
        if (ceiling_telemetry_) line["ceiling"] = ceiling_telemetry_();
      }
      *trace_ << line.dump() << '\n';
    }
    return pr;
  }

  sim::MockRobot& robot_;
  const EvaluationOptions& options_;
  RunResult& run_;
  std::ofstream* trace_;
  std::function<nlohmann::json()> ceiling_telemetry_;
  Polyline taught_;
  PathTracker tracker_;
  double dt_s_;
  double time_limit_s_;
  double t_s_ = 0.0;
  Eigen::Vector2d last_pos_;
  bool localized_once_ = false;
};

}  // namespace

ReplaySessionOptions replay_session_options(const EvaluationOptions& options) {
  ReplaySessionOptions so;
  so.camera = camera_request(options);
  so.head = options.head;
  so.navigator = options.navigator;
  so.navigator.features = options.features;
  so.give_up_lost_s = options.give_up_lost_s;
  so.give_up_not_localised_s = options.give_up_not_localised_s;
  so.arrival_tolerance_m = options.arrival_tolerance_m;
  so.arrival_tolerance_rad = options.arrival_tolerance_rad;
  return so;
}

RunResult replay_run(const TeachResult& teach,
                     const std::shared_ptr<const sim::World>& replay_world,
                     const std::string& lighting, const sim::Pose2D& start, int k,
                     const EvaluationOptions& options) {
  const auto wall0 = Clock::now();
  MockReplaySetup setup;  // the start is the caller's (drawn in the undisturbed world)
  set_run_options(setup, k, lighting, options);
  RobotConnection robot = open_mock_robot(replay_world, setup.robot, setup.bridge);
  robot.mock->place(start);

  RunResult r;
  r.index = k;
  r.start_x_m = start.x_m;
  r.start_y_m = start.y_m;
  r.start_yaw_rad = start.yaw_rad;
  std::ofstream trace;
  if (!options.trace_dir.empty()) {
    std::filesystem::create_directories(options.trace_dir);
    // One file per world, modality (or ceiling mode), disturbance set and run: several
    // --disturbance configurations in one evaluation must not overwrite each other's traces.
    const auto file = options.trace_dir /
                      (teach.world_name + "_" + navigates_by(options) + "_" +
                       disturbance_label(options.disturbances) + "_run" + std::to_string(k + 1) +
                       ".jsonl");
    trace.open(file);
    if (!trace) throw std::runtime_error(file.string() + ": cannot open for writing");
    // First line: where each key image was taught (its ground-truth base pose).
    nlohmann::json keys = nlohmann::json::array();
    for (size_t i = 0; i < teach.key_m.size(); ++i) {
      nlohmann::json k = {{"x_m", teach.key_m[i].x()}, {"y_m", teach.key_m[i].y()}};
      if (i < teach.key_yaw_rad.size()) k["yaw_rad"] = teach.key_yaw_rad[i];
      keys.push_back(std::move(k));
    }
    trace << nlohmann::json{{"taught_key_images", keys}}.dump() << '\n';
  }

  GroundTruthMonitor monitor(*robot.mock, teach, options, r, trace.is_open() ? &trace : nullptr);
  ReplaySessionOptions so = replay_session_options(options);
  so.monitor = &monitor;
  SessionLink link(nullptr, nullptr);
  // The replay loop users run (`replay`, `demo`): its decisions are what is scored here.
  StepFunction step;  // ceiling mode: the ceiling navigator steps the same loop
  if (options.mode == core::NavMode::kCeiling) {
    CeilingReplay ceiling = make_ceiling_replay(robot.mock.get(), 0.0, teach.map_dir,
                                                teach.map, options.head.head_pitch_rad,
                                                options.ceiling);
    step = std::move(ceiling.step);
    monitor.set_ceiling_telemetry(std::move(ceiling.telemetry_json));
  }
  const ReplayResult replayed = run_replay_session(robot, teach.map, so, link, step);
  r.tour_complete = replayed.tour_complete;
  if (replayed.tour_complete) {
    r.arrival_verdict = replayed.arrival.verdict;
    r.arrival_source = replayed.arrival.source;
    if (replayed.arrival.verdict != "unknown") r.arrival_offset_m = replayed.arrival.offset_m;
    monitor.settle();
  } else {
    r.outcome = replayed.outcome;
    r.detail = replayed.error.empty() ? replayed.detail : replayed.error;
  }
  if (const auto gt = robot.mock->ground_truth(); gt.collision && r.outcome.empty()) {
    r.outcome = "collision";
    r.detail = gt.collision->what;
  }
  r.frames = static_cast<int>(r.samples.size());
  r.frames_dropped =
      static_cast<int>(static_cast<naoqi_bridge::MockBridge&>(*robot.bridge).frames_dropped());
  r.sim_s = monitor.sim_s();
  const Eigen::Vector2d end_m = teach.path_m.back();
  r.final_error_m = (monitor.last_position() - end_m).norm();
  if (r.tour_complete && r.outcome.empty()) {
    if (r.final_error_m <= options.end_tolerance_m) {
      r.outcome = "complete";
      r.success = true;
    } else {
      r.outcome = "wrong_end";
      r.detail = "stopped " + fmt("%.2f", r.final_error_m) + " m from the taught end";
    }
  }

  std::vector<double> travelled, lateral, omega, t, step_ms;
  double lines_sum = 0.0, points_sum = 0.0;
  for (const RunSample& s : r.samples) {
    travelled.push_back(s.travelled_m);
    lateral.push_back(s.lateral_m);
    if (s.frame_received) {
      omega.push_back(s.omega_rad_s);
      t.push_back(s.t_s);
      step_ms.push_back(s.step_ms);
      lines_sum += s.n_lines;
      points_sum += s.n_points;
    }
  }
  if (!t.empty()) {
    r.verified_lines_mean = lines_sum / static_cast<double>(t.size());
    r.verified_points_mean = points_sum / static_cast<double>(t.size());
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

Summary summarize(const std::vector<RunResult>& runs, int key_images, double taught_length_m,
                  double arrival_tolerance_m) {
  Summary s;
  s.runs = static_cast<int>(runs.size());
  std::vector<double> rmss, errors, rates, steps, lines, points;
  s.lateral_max_m = 0.0;
  s.converged_from_max_m = 0.0;
  for (const RunResult& r : runs) {
    s.converged_from_max_m = r.converged_from_m < 0.0
                                 ? kNaN
                                 : std::max(s.converged_from_max_m, r.converged_from_m);
    s.successes += r.success ? 1 : 0;
    if (std::isfinite(r.lateral_rms_m)) rmss.push_back(r.lateral_rms_m);
    if (std::isfinite(r.verified_lines_mean)) lines.push_back(r.verified_lines_mean);
    if (std::isfinite(r.verified_points_mean)) points.push_back(r.verified_points_mean);
    if (std::isfinite(r.lateral_max_m)) s.lateral_max_m = std::max(s.lateral_max_m, r.lateral_max_m);
    errors.push_back(r.final_error_m);
    if (!r.arrival_verdict.empty()) {
      ++s.arrival_judged;
      const bool there = r.final_error_m <= arrival_tolerance_m;
      s.arrival_agreed += (r.arrival_verdict == "arrived") == there ? 1 : 0;
    }
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
  s.verified_lines_mean = mean(lines);
  s.verified_points_mean = mean(points);
  if (rmss.empty()) s.lateral_max_m = kNaN;
  s.final_error_mean_m = mean(errors);
  s.final_error_max_m = errors.empty() ? kNaN : *std::max_element(errors.begin(), errors.end());
  s.key_images_per_m = key_images_per_m(key_images, taught_length_m);
  s.omega_rate_rms_rad_s2 = mean(rates);
  s.step_ms_median = percentile(steps, 0.5);
  s.step_ms_p95 = percentile(steps, 0.95);
  return s;
}

Evaluation evaluate(const TeachResult& teach, const std::shared_ptr<const sim::World>& world,
                    const EvaluationOptions& options, const ProgressFn& progress) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument("EvaluationOptions: " + errors.front());
  }
  Evaluation ev;
  ev.world_name = world->name;
  ev.mode = core::to_string(options.mode);
  const bool ceiling = options.mode == core::NavMode::kCeiling;
  ev.features = navigates_by(options);
  ev.controller = ceiling ? "vnhv" : core::navigator::to_string(options.navigator.controller);
  ev.size = std::to_string(options.width_px) + "x" + std::to_string(options.height_px);
  ev.lens = lens_label(options);
  for (Disturbance d : options.disturbances) ev.disturbances.push_back(to_string(d));
  ev.key_images = static_cast<int>(teach.map.key_images.size());
  ev.taught_length_m = teach.length_m;
  ev.teach_frames = teach.frames;
  const DisturbedWorld dw = make_disturbed_world(world, options.disturbances, options.disturbance,
                                                 teach.path_m, options.seed, options.starts);
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
    const sim::Pose2D start = replay_start_pose(*world, k, options);
    RunResult r = replay_run(teach, dw.world, dw.lighting_of_run(k), start, k, options);
    r.light_factor = dw.light_factor_of_run(k);
    if (progress) {
      std::ostringstream os;
      os << "[" << ev.features << "] start " << (k + 1) << "/" << options.starts << " ("
         << fmt("%.2f", start.x_m) << ", " << fmt("%.2f", start.y_m) << ", "
         << fmt("%.1f", start.yaw_rad / kDeg) << " deg; lateral "
         << fmt("%+.2f", r.start_lateral_m) << " m";
      if (r.light_factor != 0.0) os << "; light x" << fmt("%.2f", r.light_factor);
      os << "): " << r.outcome;
      if (!r.detail.empty()) os << " (" << r.detail << ")";
      os << ", " << fmt("%.1f", r.travelled_m) << " m, converged from "
         << fmt("%.1f", r.converged_from_m) << " m, lateral rms "
         << fmt("%.1f", 100 * r.lateral_rms_m) << " cm max " << fmt("%.1f", 100 * r.lateral_max_m)
         << " cm, end error " << fmt("%.1f", 100 * r.final_error_m) << " cm, verified with IN "
         << fmt("%.1f", r.verified_lines_mean) << " lines " << fmt("%.1f", r.verified_points_mean)
         << " points, step "
         << fmt("%.1f", r.step_ms_median) << " ms, " << r.frames << " frames in "
         << fmt("%.1f", r.wall_s) << " s";
      progress(os.str());
    }
    ev.runs.push_back(std::move(r));
  }
  ev.summary =
      summarize(ev.runs, ev.key_images, ev.taught_length_m, options.arrival_tolerance_m);
  return ev;
}

}  // namespace pepper::app::evaluation
