#include "session/replay_session.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <thread>

#include "session/console.hpp"
#include "session/recording.hpp"
#include "session/robot_supervision.hpp"
#include "session/signals.hpp"
#include "session/taught_path.hpp"
#include "session/telemetry_json.hpp"

namespace pepper::app {

namespace nb = naoqi_bridge;
namespace nav = core::navigator;
using Clock = std::chrono::steady_clock;

std::vector<std::string> ReplaySessionOptions::validate() const {
  std::vector<std::string> e;
  if (frame_timeout_ms < 100 || frame_timeout_ms > 10000)
    e.push_back("frame_timeout_ms must be in 100..10000");
  if (max_frames < 0) e.push_back("max_frames must be >= 0");
  if (!(pace_hz >= 0)) e.push_back("pace_hz must be >= 0");
  if (!(give_up_lost_s >= 0)) e.push_back("give_up_lost_s must be >= 0");
  if (!(give_up_not_localised_s >= 0)) e.push_back("give_up_not_localised_s must be >= 0");
  if (!(arrival_tolerance_m > 0)) e.push_back("arrival_tolerance_m must be > 0");
  if (!(arrival_tolerance_rad > 0)) e.push_back("arrival_tolerance_rad must be > 0");
  for (const auto& m : navigator.validate()) e.push_back("navigator: " + m);
  return e;
}

namespace {

std::string format_s(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", s);
  return buf;
}

bool close_rel(double a, double b, double tol) { return std::abs(a - b) <= tol * std::abs(b); }

/// Throws std::invalid_argument when the camera cannot replay the map.
void check_intrinsics(const core::CameraIntrinsics& map_cam, const core::CameraIntrinsics& cam) {
  if (map_cam.width_px != cam.width_px || map_cam.height_px != cam.height_px) {
    throw std::invalid_argument(
        "camera delivers " + std::to_string(cam.width_px) + "x" + std::to_string(cam.height_px) +
        " but the map was taught at " + std::to_string(map_cam.width_px) + "x" +
        std::to_string(map_cam.height_px) + ": use --set robot.camera_width_px=" +
        std::to_string(map_cam.width_px) + " --set robot.camera_height_px=" +
        std::to_string(map_cam.height_px));
  }
  constexpr double kTol = 0.02;  // 2 %: a different calibration, not rounding
  if (!close_rel(cam.fx_px, map_cam.fx_px, kTol) || !close_rel(cam.fy_px, map_cam.fy_px, kTol) ||
      std::abs(cam.cx_px - map_cam.cx_px) > 0.02 * cam.width_px ||
      std::abs(cam.cy_px - map_cam.cy_px) > 0.02 * cam.height_px) {
    throw std::invalid_argument("camera intrinsics differ from the map's (fx " +
                                std::to_string(cam.fx_px) + " vs " +
                                std::to_string(map_cam.fx_px) + "): another robot or camera?");
  }
}

/// The UI's floor plan under the top view (simulated robot only: a real one has no world file):
/// wall segments [ax, ay, bx, by] and furniture footprints as four corners, world frame, metres.
nlohmann::json floor_plan_json(const sim::World& world) {
  nlohmann::json walls = nlohmann::json::array(), boxes = nlohmann::json::array();
  for (const auto& w : world.walls) walls.push_back({w.a_m.x(), w.a_m.y(), w.b_m.x(), w.b_m.y()});
  for (const auto& b : world.boxes) {
    nlohmann::json corners = nlohmann::json::array();
    for (const auto& c : b.corners_m()) corners.push_back({c.x(), c.y()});
    boxes.push_back(corners);
  }
  return {{"walls", walls}, {"boxes", boxes}};
}

/// The UI's replay.localisation: whether this frame's localisation attempt found the segment,
/// and else the best candidate against the threshold.
bool has_segment(const nav::Telemetry& t) {
  return t.state != nav::NavState::kNotLocalized && t.state != nav::NavState::kLost;
}

nlohmann::json localisation_json(const nav::Telemetry& t, const ReplaySessionOptions& options) {
  const bool ok = has_segment(t);
  nlohmann::json j = {{"ok", ok}};
  if (ok) {
    j["key_index"] = t.in;
  } else if (t.localization_best >= 0) {
    j["key_index"] = t.localization_best;
    j["detail"] = "best candidate, " + std::to_string(t.localization_best_count) + " of " +
                  std::to_string(options.navigator.initial.rule.min_best_count) +
                  " verified matches needed";
  } else {
    j["detail"] = "no candidate key image";
  }
  return j;
}

std::string replay_state_name(nav::NavState s) {
  switch (s) {
    case nav::NavState::kNotLocalized: return "localising";
    case nav::NavState::kTourComplete: return "finished";
    case nav::NavState::kLost: return "stopped";
    case nav::NavState::kOverdue: return "stopped";
    default: return "running";
  }
}

}  // namespace

Arrival judge_arrival(const nav::Telemetry& t, double tolerance_m, double tolerance_rad) {
  Arrival a;
  if (t.arrival_source == nav::Telemetry::ArrivalSource::kNone || !std::isfinite(t.arrival_along_m) ||
      !std::isfinite(t.arrival_lateral_m) || !std::isfinite(t.arrival_heading_rad)) {
    return a;
  }
  a.source = nav::to_string(t.arrival_source);
  a.along_m = t.arrival_along_m;
  a.lateral_m = t.arrival_lateral_m;
  a.heading_rad = t.arrival_heading_rad;
  a.offset_m = std::hypot(a.along_m, a.lateral_m);
  a.verdict = a.offset_m <= tolerance_m && std::abs(a.heading_rad) <= tolerance_rad
                  ? "arrived"
                  : "not_aligned";
  return a;
}

namespace {

std::string arrival_detail(const Arrival& a) {
  if (a.verdict == "unknown") {
    return "end of tour reached (no estimate of the final offset: check the position by eye)";
  }
  char buf[200];
  std::snprintf(buf, sizeof buf, "%.0f cm %s, %.0f cm %s, heading %+.1f deg (from %s)",
                100 * std::abs(a.along_m), a.along_m >= 0 ? "past" : "short",
                100 * std::abs(a.lateral_m), a.lateral_m >= 0 ? "left" : "right",
                a.heading_rad * 180 / M_PI, a.source.c_str());
  if (a.verdict == "arrived") return std::string("arrived at the final key image: ") + buf;
  return std::string("reached the last key image but not aligned with it: ") + buf +
         "; check the view at the end of the tour";
}

}  // namespace

ReplayResult run_replay_session(RobotConnection& robot, core::memory::VisualMemory map,
                                const ReplaySessionOptions& options, SessionLink& link,
                                StepFunction step_override) {
  const auto problems = options.validate();
  if (!problems.empty()) {
    std::string all;
    for (const auto& p : problems) all += (all.empty() ? "" : "; ") + p;
    throw std::invalid_argument("replay options: " + all);
  }
  nb::RobotBridge& bridge = *robot.bridge;
  ReplayResult result;
  result.key_image_count = static_cast<int>(map.key_images.size());
  auto stop_base = [&](const std::string& why) {
    bridge.stop();
    link.command_event(0.0, 0.0, true, why);
  };
  auto end_with = [&](const std::string& outcome, const std::string& reason_text) {
    stop_base(outcome);
    result.outcome = outcome;
    result.detail = reason_text;
    link.publish_state({{"stop_reason", reason_text}});
  };

  std::optional<nav::Navigator> navigator;
  std::optional<RecordingWriter> writer;
  nlohmann::json last_replay_state = nlohmann::json::object();  // the page's last `replay`
  double total_m = 0.0;
  std::ofstream telemetry;
  try {
    link.publish_state({{"mode", "replay"},
                        {"robot_kind", robot.mock ? "mock" : "real"},
                        {"connection", {{"robot", "connecting"}, {"head_locked", false}}},
                        {"stop_reason", nullptr}});
    bridge.connect();
    const nb::HeadLockStatus head = bridge.lock_head(options.head);
    link.event({{"event", "head_lock"},
                {"holding", head.holding},
                {"head_yaw_rad", head.head_yaw_rad},
                {"head_pitch_rad", head.head_pitch_rad},
                {"max_error_rad", head.max_error_rad}});
    const core::CameraIntrinsics camera =
        session_camera(bridge.start_camera(options.camera), options.camera_model);
    check_intrinsics(map.camera, camera);
    if (options.camera_model && camera.model != map.camera.model) {
      throw std::invalid_argument(
          std::string("the camera file's projection model is ") + core::to_string(camera.model) +
          ", the map was taught with " + core::to_string(map.camera.model) +
          ": give replay the calibration the map was taught with");
    }
    link.publish_state({{"connection",
                         {{"robot", "connected"},
                          {"head_locked", head.holding},
                          {"detail", bridge.describe()}}}});
    // Key-image strip for the replay view.
    nlohmann::json keys = nlohmann::json::array();
    for (std::size_t i = 0; i < map.key_images.size(); ++i) {
      const auto& f = map.key_images[i].features;
      nlohmann::json key = {{"index", i}, {"weak", false}};
      if (!options.ceiling_telemetry) {
        // Forward mode's features; a ceiling map's relay images are driven by the mosaic's
        // landmarks, not by these counts, so their captions leave them out.
        key["n_lines"] = f.lines.size();
        key["n_points"] = f.corners_px.size();
      }
      keys.push_back(std::move(key));
      if (link.has_ui()) link.publish_thumbnail("key/" + std::to_string(i), f.gray);
    }
    link.publish_state({{"teach", {{"key_images", keys}}}});
    // The progress bar's metres: the map's own distances (KeyImage::travelled_m, what `map info`
    // prints), reached at the last key image passed (IP); NaN in maps without them.
    std::vector<double> key_distance_m;
    for (const auto& k : map.key_images) {
      key_distance_m.push_back(k.travelled_m - map.key_images.front().travelled_m);
    }
    total_m = key_distance_m.empty() ? 0.0 : key_distance_m.back();
    const auto json_m = [](double m) {
      return std::isfinite(m) ? nlohmann::json(m) : nlohmann::json(nullptr);
    };
    // The IP / IN / INN thumbnails come from the map's own images (cv::Mat shares the pixels):
    // the navigator that takes the map is absent where a step function replaces it (ceiling
    // mode), whose relay images the panel shows all the same.
    std::vector<cv::Mat> key_grays;
    for (const auto& k : map.key_images) key_grays.push_back(k.features.gray);
    if (!step_override) navigator.emplace(std::move(map), options.navigator);
    const auto key_gray = [&](int i) -> cv::Mat {
      if (i < 0 || i >= static_cast<int>(key_grays.size())) return {};
      return key_grays[static_cast<size_t>(i)];
    };
    if (!options.telemetry_jsonl.empty()) {
      telemetry.open(options.telemetry_jsonl);
      if (!telemetry) throw std::runtime_error(options.telemetry_jsonl.string() + ": cannot write");
    }
    if (!options.record_dir.empty()) {
      writer.emplace(options.record_dir, camera, bridge.describe(), options.config_json);
    }

    bool started = !options.wait_for_start;
    if (!started) link.publish_state({{"replay", {{"state", "stopped"}}}});
    auto last_frame_at = bridge.stall_clock();
    int64_t t0_ns = -1;
    int last_in = -2;
    int64_t last_moving_t_ns = -1;
    int best_candidate = -1, best_candidate_count = 0;  // last localisation attempt's best
    // The best candidate of all attempts, for the not-localised verdict: the robot stands still
    // while it searches, so the strongest match seen is the best evidence of where it stands
    // (the last attempt's may be a weaker one, e.g. 2 matches after 4).
    int best_of_wait = -1, best_of_wait_count = -1;
    int64_t last_localising_event_ns = std::numeric_limits<int64_t>::min() / 2;
    // The last localisation attempt's verdict stays on the page until the next attempt.
    nlohmann::json last_localisation = {{"ok", false}, {"detail", "not yet tried"}};
    // Lateral error against the taught path: ground truth, so the mock robot only.
    double max_lateral_m = 0.0, sum_lateral_m = 0.0;
    int64_t n_lateral = 0;
    nlohmann::json replayed = nlohmann::json::array();
    // The replayed poses driven on odometry alone (vision blind, issue 29), for the top view.
    nlohmann::json blind = nlohmann::json::array();
    if (!options.taught_path_m.empty()) {  // constant: sent once, not with every "trajectory"
      nlohmann::json taught = nlohmann::json::array(), taught_keys = nlohmann::json::array();
      for (const auto& p : options.taught_path_m) taught.push_back({p.x(), p.y()});
      for (const auto& p : options.taught_keys_m) taught_keys.push_back({p.x(), p.y()});
      link.publish_state({{"taught_path", {{"taught", taught}, {"keys", taught_keys}}}});
    }
    if (robot.mock && link.has_ui()) link.publish_state({{"floor_plan", floor_plan_json(robot.mock->world())}});
    auto next_iter = Clock::now();
    link.event({{"event", "replay_started"}, {"key_images", result.key_image_count}});

    for (;;) {
      if (interrupted()) {
        end_with("interrupted", "interrupted (Ctrl-C)");
        break;
      }
      bool ui_stop = false;
      while (auto in = link.poll_intent()) {
        if (in->kind == teach_ui::IntentKind::kEmergencyStop) ui_stop = true;
        if (in->kind == teach_ui::IntentKind::kStartReplay) started = true;
      }
      if (ui_stop) {
        end_with("ui_stop", "STOP pressed");
        break;
      }
      if (bridge.state() == nb::ConnectionState::kLost) {
        end_with("connection_lost",
                 "connection to the robot lost: check the network and the robot "
                 "(`pepper_app doctor --robot URL`), then replay again");
        break;
      }
      // The robot's own view (executed velocity, head lock): before this frame's command.
      const SupervisionStep robot_view = supervise_robot(bridge, link);
      if (robot_view.stop_reason) {
        end_with("head_lock_lost", *robot_view.stop_reason);
        break;
      }
      auto frame = bridge.next_frame(std::chrono::milliseconds(100));
      if (!frame) {
        if (bridge.stall_clock() - last_frame_at >
            std::chrono::milliseconds(options.frame_timeout_ms)) {
          end_with("frame_timeout",
                   "no camera frame for " + std::to_string(options.frame_timeout_ms) +
                       " ms: check the camera with `pepper_app doctor --robot URL` (another "
                       "program holding it, or a slow network)");
          break;
        }
        if (options.monitor) {
          if (auto end = options.monitor->after_iteration(nullptr, nullptr)) {
            end_with(end->outcome, end->detail);
            break;
          }
        }
        continue;
      }
      last_frame_at = bridge.stall_clock();
      if (t0_ns < 0) t0_ns = frame->t_ns;
      ++result.frames;
      if (writer) writer->append(*frame, 0.0, 0.0);
      if (!started) {
        link.publish_frame(*frame, nlohmann::json::object());
        Progress waiting;
        waiting.phase = "replay";
        waiting.frames = result.frames;
        waiting.key_count = result.key_image_count;
        waiting.detail = "waiting for the UI's start button";
        link.progress(waiting);
        continue;
      }
      const auto step_t0 = Clock::now();
      const nav::StepResult step = step_override ? step_override(*frame) : navigator->step(*frame);
      const double step_ms =
          std::chrono::duration<double, std::milli>(Clock::now() - step_t0).count();
      const nav::Command& c = step.command;
      const nav::Telemetry& t = step.telemetry;
      const bool finite = std::isfinite(c.v_m_s) && std::isfinite(c.omega_rad_s);
      if (c.stop || !finite) {
        stop_base(finite ? nav::to_string(c.reason) : "non_finite_command");
      } else {
        bridge.move({c.v_m_s, 0.0, c.omega_rad_s});
        link.command_event(c.v_m_s, c.omega_rad_s, false, "navigator");
      }
      result.max_key_reached = std::max(result.max_key_reached, t.in);
      if (!c.stop) last_moving_t_ns = frame->t_ns;
      if (t.localization_ran) {
        best_candidate = t.localization_best;
        best_candidate_count = t.localization_best_count;
        if (best_candidate >= 0 && best_candidate_count > best_of_wait_count) {
          best_of_wait = best_candidate;
          best_of_wait_count = best_candidate_count;
        }
        // The operator sees the search: once a second while it fails (frame time).
        if (!has_segment(t) && frame->t_ns - last_localising_event_ns >= 1'000'000'000) {
          last_localising_event_ns = frame->t_ns;
          link.event({{"event", "localising"},
                      {"best_key_image", best_candidate},
                      {"verified_matches", best_candidate_count},
                      {"needed", options.navigator.initial.rule.min_best_count}});
        }
      }
      if (link.console() != nullptr) {  // the evaluation has none: no strings per frame
        // The console's line: the map's distance at the key image passed (IP), as the UI's
        // progress bar, so a real robot shows the same measure.
        Progress p;
        p.phase = "replay";
        p.frames = result.frames;
        p.key_index = t.in;
        p.key_count = result.key_image_count;
        if (t.ip >= 0 && !key_distance_m.empty()) {
          p.distance_m =
              key_distance_m[std::clamp(t.ip, 0, static_cast<int>(key_distance_m.size()) - 1)];
        } else if (!key_distance_m.empty()) {
          p.distance_m = 0.0;
        }
        p.total_m = total_m;
        if (!has_segment(t)) {
          const std::string what =
              t.state == nav::NavState::kLost ? "lost, relocalising" : "localising";
          p.detail = best_candidate >= 0
                         ? what + ": best key image " + std::to_string(best_candidate) + ", " +
                               std::to_string(best_candidate_count) + " of " +
                               std::to_string(options.navigator.initial.rule.min_best_count) +
                               " verified matches"
                         : what;
        } else if (t.state == nav::NavState::kDeadReckoning) {
          p.detail = "driving on odometry (vision blind)";
        } else if (t.state == nav::NavState::kTourComplete ||
                   (c.stop && c.reason == nav::StopReason::kTourComplete)) {
          p.distance_m = total_m;  // IP is the one before the final image: show the whole tour
          p.detail = "end of tour";
        } else if (c.stop) {
          p.detail = std::string("stopped: ") + nav::to_string(c.reason);
        }
        link.progress(p);
      }
      const bool stopped_short = c.stop && c.reason != nav::StopReason::kTourComplete;
      const bool gave_up = options.give_up_lost_s > 0 && last_moving_t_ns >= 0 && stopped_short &&
                           (frame->t_ns - last_moving_t_ns) * 1e-9 > options.give_up_lost_s;
      const bool never_localised = options.give_up_not_localised_s > 0 && last_moving_t_ns < 0 &&
                                   stopped_short &&
                                   (frame->t_ns - t0_ns) * 1e-9 > options.give_up_not_localised_s;

      ReplaySample s;
      s.t_s = (frame->t_ns - t0_ns) * 1e-9;
      s.step_ms = step_ms;
      s.v_m_s = c.stop ? 0.0 : c.v_m_s;
      s.omega_rad_s = c.stop ? 0.0 : c.omega_rad_s;
      s.stop = c.stop;
      s.in = t.in;
      s.n_lines = t.n_lines_next;
      s.n_points = t.n_points_next;
      s.dead_reckoning = t.state == nav::NavState::kDeadReckoning;
      nlohmann::json line = {{"frame", result.frames - 1},
                             {"odom", odometry_to_json(frame->odom)},
                             {"command", command_to_json(c)},
                             {"telemetry", telemetry_to_json(t)}};
      if (!robot_view.telemetry.is_null()) line["robot"] = robot_view.telemetry;
      // Ceiling mode: this step's ceiling telemetry, built once for the JSON line, the
      // caption and the plot.
      const nlohmann::json ceiling =
          options.ceiling_telemetry ? options.ceiling_telemetry() : nlohmann::json();
      if (options.ceiling_telemetry) line["ceiling"] = ceiling;
      if (robot.mock) {
        const auto gt = robot.mock->ground_truth();
        s.has_pose = true;
        s.x_m = gt.base.x_m;
        s.y_m = gt.base.y_m;
        s.yaw_rad = gt.base.yaw_rad;
        line["ground_truth"] = {{"x_m", s.x_m}, {"y_m", s.y_m}, {"yaw_rad", s.yaw_rad}};
        replayed.push_back({s.x_m, s.y_m});
        if (s.dead_reckoning) blind.push_back({s.x_m, s.y_m});
        const double lateral_m =
            distance_to_path_m(options.taught_path_m, Eigen::Vector2d(s.x_m, s.y_m));
        if (std::isfinite(lateral_m)) {
          max_lateral_m = std::max(max_lateral_m, lateral_m);
          sum_lateral_m += lateral_m;
          ++n_lateral;
        }
        if (link.has_ui() && result.frames % 5 == 0) {
          nlohmann::json patch = {{"trajectory", {{"replayed", replayed}, {"blind", blind}}},
                                  {"pose", line["ground_truth"]}};
          if (n_lateral > 0) {
            patch["offline"] = {{"max_lateral_error_m", max_lateral_m},
                                {"mean_lateral_error_m", sum_lateral_m / n_lateral},
                                {"source", "ground_truth"}};
          }
          link.publish_state(patch);
        }
        if (robot.mock->collided()) {
          result.samples.push_back(s);
          if (options.monitor) options.monitor->after_iteration(&step, &result.samples.back());
          end_with("collision", "collision with " + (gt.collision ? gt.collision->what : "?") +
                                    " (simulated robot): start it elsewhere (--mock-start) or "
                                    "re-teach the tour away from it");
          break;
        }
      }
      result.samples.push_back(s);
      if (telemetry.is_open()) telemetry << line.dump() << "\n";
      std::optional<ReplayEnd> monitor_end;
      if (options.monitor) monitor_end = options.monitor->after_iteration(&step, &s);

      if (link.has_ui()) {
        // Ceiling mode: the points are the ceiling landmarks the mosaic localiser kept.
        nlohmann::json overlay =
            options.ceiling_telemetry
                ? ceiling_overlay_to_json(t.overlay)
                : overlay_to_json(t.overlay, t.overlay.key_index < 0
                                                 ? std::string("matched")
                                                 : "IN " + std::to_string(t.overlay.key_index) +
                                                       " matched");
        // The caption's counts are the navigator's matches with IN before verification; the
        // legend counts the verified ones drawn: say which is which. Two lines, so that a
        // 320-pixel-wide image shows the counts whole. On frames where the navigator drew none
        // (the end of the tour, a search) the caption says so, or the legend's 0 would
        // contradict it.
        const bool drawn = !t.overlay.lines.empty() || !t.overlay.points_px.empty();
        if (options.ceiling_telemetry) {
          // The second line says where the robot is in the mosaic (or that it coasts).
          overlay["text"] = nlohmann::json::array(
              {std::string(nav::to_string(t.state)) + "  relay IP " + std::to_string(t.ip) +
                   "  IN " + std::to_string(t.in),
               ceiling_overlay_caption(ceiling)});
        } else {
          overlay["text"] = nlohmann::json::array(
              {std::string(nav::to_string(t.state)) + "  IP " + std::to_string(t.ip) + "  IN " +
                   std::to_string(t.in),
               "matches with IN: lines " + std::to_string(t.n_lines_next) + ", points " +
                   std::to_string(t.n_points_next) + (drawn ? "" : " (none drawn)")});
        }
        link.publish_frame(*frame, overlay);
        nlohmann::json sample = {{"t_s", s.t_s},
                                 {"v_m_s", s.v_m_s},
                                 {"omega_rad_s", s.omega_rad_s},
                                 {"dead_reckoning", s.dead_reckoning}};
        if (options.ceiling_telemetry) {
          // Ceiling mode: the counts plot is the landmarks the mosaic localiser kept, as the
          // ceiling teach plots them (no lines, and no forward points, to plot).
          sample["ceiling_inliers"] = ceiling.value("inliers", 0);
        } else {
          sample["n_lines"] = s.n_lines;
          sample["n_points"] = s.n_points;
        }
        link.publish_samples(sample);
        if (t.localization_ran) last_localisation = localisation_json(t, options);
        const int passed = std::clamp(t.ip, 0, std::max(0, result.key_image_count - 1));
        nlohmann::json replay_state = {
            {"state", replay_state_name(t.state)},
            {"key_index", t.in >= 0 ? nlohmann::json(t.in) : nlohmann::json(nullptr)},
            {"key_count", result.key_image_count},
            {"max_key_reached", result.max_key_reached},
            {"frames", result.frames},
            {"distance_m", t.ip >= 0 && !key_distance_m.empty()
                               ? json_m(key_distance_m[passed])
                               : nlohmann::json(0.0)},
            {"total_m", json_m(total_m)},
            {"localisation", last_localisation}};
        last_replay_state = replay_state;
        link.publish_state({{"replay", replay_state},
                            {"drive", {{"v_m_s", s.v_m_s}, {"omega_rad_s", s.omega_rad_s}}}});
        if (t.in != last_in) {
          last_in = t.in;
          link.publish_thumbnail("ip", key_gray(t.ip));
          link.publish_thumbnail("in", key_gray(t.in));
          link.publish_thumbnail("inn", key_gray(t.inn));
        }
      }
      if (t.state == nav::NavState::kTourComplete ||
          (c.stop && c.reason == nav::StopReason::kTourComplete)) {
        result.tour_complete = true;
        result.arrival =
            judge_arrival(t, options.arrival_tolerance_m, options.arrival_tolerance_rad);
        end_with("tour_complete", arrival_detail(result.arrival));
        break;
      }
      if (c.stop && c.reason == nav::StopReason::kRelayBreak) {
        // Ceiling mode: the next relay segment was taught without a landmark linking its relay
        // images (the teach lost the ceiling there); the navigator stops for good.
        end_with("relay_break",
                 "the taught relay chain breaks after relay image " + std::to_string(t.ip) +
                     " (the teach lost the ceiling there, `map info` lists the breaks): stopped; "
                     "teach the tour again with the ceiling in view");
        break;
      }
      if (t.state == nav::NavState::kOverdue) {
        end_with("overdue", "no key-image switch after key image " + std::to_string(t.ip) +
                                " for far longer than teaching took: stopped, unsure where the "
                                "robot is (end of tour not visible?)");
        break;
      }
      if (monitor_end) {
        end_with(monitor_end->outcome, monitor_end->detail);
        break;
      }
      if (gave_up) {
        end_with("lost", "stopped (" + std::string(nav::to_string(c.reason)) + ") for more than " +
                             format_s(options.give_up_lost_s) +
                             " s after driving: giving up. Check the lights and the view; "
                             "place the robot back on the taught path and replay again");
        break;
      }
      if (never_localised) {
        end_with("not_localised",
                 "not localised after " + format_s(options.give_up_not_localised_s) +
                     " s (best candidate: key image " + std::to_string(best_of_wait) + " with " +
                     std::to_string(std::max(0, best_of_wait_count)) + " verified matches): place the "
                     "robot on the taught path near a key image facing the taught direction, "
                     "check the lights, and check that the map belongs to this place");
        break;
      }
      if (options.max_frames > 0 && result.frames >= options.max_frames) {
        end_with("max_frames", "frame limit (--max-frames " + std::to_string(options.max_frames) +
                                   ") reached: drop --max-frames to replay the whole tour");
        break;
      }
      if (options.pace_hz > 0) {
        next_iter += std::chrono::duration_cast<Clock::duration>(
            std::chrono::duration<double>(1.0 / options.pace_hz));
        std::this_thread::sleep_until(next_iter);
        if (Clock::now() > next_iter + std::chrono::seconds(1)) next_iter = Clock::now();
      }
    }
  } catch (const std::exception& e) {
    bridge.stop();  // first
    link.command_event(0.0, 0.0, true, "error");
    result.outcome = bridge.state() == nb::ConnectionState::kLost ? "connection_lost" : "error";
    result.error = e.what();
    result.error_exception = std::current_exception();
    link.publish_state({{"stop_reason", std::string("error: ") + e.what()}});
  }
  bridge.release();
  link.end_progress();
  nlohmann::json arrival = nullptr;
  if (result.tour_complete) {
    arrival = {{"verdict", result.arrival.verdict},
               {"source", result.arrival.source},
               {"along_m", result.arrival.along_m},
               {"lateral_m", result.arrival.lateral_m},
               {"heading_rad", result.arrival.heading_rad},
               {"offset_m", result.arrival.offset_m}};
  }
  // The final figures, from the same result as the replay_done event and the console line.
  {
    const int last_key = result.key_image_count - 1;
    nlohmann::json final_state = last_replay_state;
    final_state.update(nlohmann::json{
        {"state", result.tour_complete ? "finished" : "stopped"},
        {"outcome", result.outcome},
        {"key_index", result.max_key_reached >= 0 ? nlohmann::json(result.max_key_reached)
                                                   : nlohmann::json(nullptr)},
        {"max_key_reached", result.max_key_reached},
        {"key_count", result.key_image_count},
        {"frames", result.frames},
        {"arrival", arrival}});
    if (result.tour_complete && last_key >= 0) {
      final_state["key_index"] = last_key;
      if (std::isfinite(total_m)) final_state["distance_m"] = total_m;
    }
    link.publish_state({{"replay", final_state},
                        {"drive", {{"v_m_s", 0.0}, {"omega_rad_s", 0.0}}},
                        {"connection", {{"robot", "disconnected"},
                                        {"head_locked", false},
                                        {"detail", "replay ended (" + result.outcome + ")"}}}});
  }
  link.event({{"event", "replay_done"},
              {"outcome", result.outcome},
              {"arrival", arrival},
              {"error", result.error},
              {"frames", result.frames},
              {"max_key_reached", result.max_key_reached},
              {"key_images", result.key_image_count},
              {"tour_complete", result.tour_complete}});
  return result;
}

}  // namespace pepper::app
