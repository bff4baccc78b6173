#include "session/teach_session.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <optional>
#include <stdexcept>
#include <thread>

#include "core/ceiling/ceiling_tour.hpp"
#include "core/features/feature_overlay.hpp"
#include "core/mapping/drive_odometer.hpp"
#include "core/memory/visual_memory.hpp"
#include "session/ceiling_map.hpp"
#include "session/console.hpp"
#include "session/recording.hpp"
#include "session/robot_supervision.hpp"
#include "session/signals.hpp"
#include "session/taught_path.hpp"
#include "session/telemetry_json.hpp"
#include "sim/teach_driver.hpp"

namespace pepper::app {

namespace nb = naoqi_bridge;
using Clock = std::chrono::steady_clock;

std::vector<std::string> TeachSessionOptions::validate() const {
  std::vector<std::string> e;
  if (map_dir.empty()) e.push_back("map_dir must be given");
  if (max_distance_m < 0) e.push_back("max_distance_m must be >= 0");
  if (max_frames < 0) e.push_back("max_frames must be >= 0");
  if (frame_timeout_ms < 100 || frame_timeout_ms > 10000)
    e.push_back("frame_timeout_ms must be in 100..10000");
  if (!(drive_timeout_s >= 0.1 && drive_timeout_s <= 10)) e.push_back("drive_timeout_s must be in [0.1, 10]");
  if (!(pace_hz >= 0)) e.push_back("pace_hz must be >= 0");
  if (!(max_v_m_s > 0 && max_v_m_s <= 0.55)) e.push_back("max_v_m_s must be in (0, 0.55]");
  if (!(max_omega_rad_s > 0 && max_omega_rad_s <= 2.0))
    e.push_back("max_omega_rad_s must be in (0, 2]");
  for (const auto& m : teach.validate()) e.push_back("teach: " + m);
  for (const auto& m : feedback.validate()) e.push_back("feedback: " + m);
  if (camera_model) {
    for (const auto& m : camera_model->validate()) e.push_back("camera_model." + m);
  }
  return e;
}

namespace {

/// The teach panel's facts. `map_distance_m` is the map's own measure (the odometer that
/// writes KeyImage::travelled_m), so the live figure ends where `map info`'s "driven" does.
nlohmann::json teach_state(double map_distance_m, const nlohmann::json& keys, int n_lines,
                           int n_points) {
  return {{"key_images", keys},
          {"distance_m", map_distance_m},
          {"n_lines", n_lines},
          {"n_points", n_points}};
}

/// |a - b| wrapped to [0, pi].
double heading_difference_rad(double a, double b) {
  return std::abs(std::remainder(a - b, 2.0 * M_PI));
}

/// The last few frames' headings, for the turn over the key-image gap (teach_feedback.hpp): the
/// odometry's yaw when every frame in the window has one, else the commanded yaw rate
/// integrated over the frame stamps.
class TurnWindow {
 public:
  explicit TurnWindow(int frames) : frames_(frames) {}
  void add(int64_t t_ns, std::optional<double> odom_yaw_rad, double commanded_omega_rad_s) {
    if (!samples_.empty()) {
      commanded_rad_ += commanded_omega_rad_s * (t_ns - samples_.back().t_ns) * 1e-9;
    }
    samples_.push_back({t_ns, odom_yaw_rad, commanded_rad_});
    while (static_cast<int>(samples_.size()) > frames_ + 1) samples_.pop_front();
  }
  void reset() { samples_.clear(); commanded_rad_ = 0.0; }
  /// |heading turned| over the last `frames` frames; nullopt until that many were seen.
  std::optional<double> turned_rad() const {
    if (static_cast<int>(samples_.size()) < frames_ + 1) return std::nullopt;
    const Sample& a = samples_.front();
    const Sample& b = samples_.back();
    bool odom = true;
    for (const auto& s : samples_) odom = odom && s.odom_yaw_rad.has_value();
    if (odom) return heading_difference_rad(*b.odom_yaw_rad, *a.odom_yaw_rad);
    return std::abs(b.commanded_rad - a.commanded_rad);
  }

 private:
  struct Sample {
    int64_t t_ns;
    std::optional<double> odom_yaw_rad;
    double commanded_rad;
  };
  int frames_;
  std::deque<Sample> samples_;
  double commanded_rad_ = 0.0;
};

}  // namespace

TeachResult run_teach_session(RobotConnection& robot, const TeachSessionOptions& options,
                              SessionLink& link) {
  const auto problems = options.validate();
  if (!problems.empty()) {
    std::string all;
    for (const auto& p : problems) all += (all.empty() ? "" : "; ") + p;
    throw std::invalid_argument("teach options: " + all);
  }
  if (options.scripted && !robot.mock) {
    throw std::invalid_argument("teach: --scripted needs a mock: robot (it drives on ground truth)");
  }
  const bool ceiling_mode = options.mode == core::NavMode::kCeiling;
  if (ceiling_mode && !robot.mock && !(options.ceiling_height_m > 0.0)) {
    throw std::invalid_argument(
        "teach --mode ceiling on a real robot needs the ceiling's height above the floor: measure "
        "it and set robot.ceiling_height_m (e.g. --set robot.ceiling_height_m=2.7; "
        "docs/method/ceiling.md)");
  }
  nb::RobotBridge& bridge = *robot.bridge;
  TeachResult result;
  std::optional<RecordingWriter> writer;
  // One of the two runs: the forward key-image selector, or the ceiling mosaic builder.
  std::optional<core::mapping::Teacher> teacher;
  std::optional<CeilingTeacher> ceiling_teacher;
  auto frames_taught = [&]() -> int64_t {
    if (ceiling_teacher) return ceiling_teacher->frames_seen();
    return teacher ? teacher->frames_seen() : 0;
  };
  bool ceiling_lost = false;  // the builder found no pose for the last frame
  int64_t ceiling_lost_frames = 0;  // ... and for this many frames in a row
  int ceiling_relocalisations = 0;  // losses the builder recovered from by re-localising
  TeachFeedbackLimits feedback_limits;
  TeachFeedback feedback;
  nlohmann::json feedback_sent = to_json(feedback);
  std::vector<std::string> feedback_kinds_sent;  // kinds in the last teach_feedback event
  TurnWindow turn_window(options.feedback.min_frame_gap);
  std::optional<int> key_features;  // lines + points of the current key image when taken
  int previous_frame_features = 0;
  // The live warnings go to the page whenever their text changes (it carries the live counts),
  // and to the events file when a warning comes or goes (never the console: issue 25 keeps it
  // quiet); the frames per kind go into the result.
  auto publish_feedback = [&](const TeachFeedback& f) {
    nlohmann::json j = to_json(f);
    if (j == feedback_sent) return;
    link.publish_state({{"teach_feedback", j}});
    std::vector<std::string> kinds;
    for (const auto& w : f.warnings) kinds.emplace_back(to_string(w.kind));
    if (kinds != feedback_kinds_sent) {
      nlohmann::json ev = {{"event", "teach_feedback"}};
      ev.update(j);
      link.event(ev);
      feedback_kinds_sent = std::move(kinds);
    }
    feedback_sent = std::move(j);
  };
  nlohmann::json key_list = nlohmann::json::array();
  bool recording = options.record_from_start;
  auto stop_base = [&](const std::string& why) {
    bridge.stop();
    link.command_event(0.0, 0.0, true, why);
    link.publish_state({{"drive", {{"v_m_s", 0.0}, {"omega_rad_s", 0.0}}}});
  };

  // The map's distances; declared out here so that the odometry report after the loop covers a
  // session that ended in a failure too (its map is still saved).
  core::mapping::DriveOdometer odometer;
  int64_t frames_with_odometry = 0, frames_without_odometry = 0;
  std::string odometry_problem;  // the bridge's reason for the last frame without odometry

  try {
    link.publish_state({{"mode", "teach"},
                        {"robot_kind", robot.mock ? "mock" : "real"},
                        {"connection", {{"robot", "connecting"}, {"head_locked", false}}}});
    bridge.connect();
    const nb::HeadLockStatus head = bridge.lock_head(options.head);
    link.event({{"event", "head_lock"},
                {"holding", head.holding},
                {"head_yaw_rad", head.head_yaw_rad},
                {"head_pitch_rad", head.head_pitch_rad},
                {"max_error_rad", head.max_error_rad}});
    if (!head.holding) {
      result.warnings.push_back("head lock not holding: max error " +
                                std::to_string(head.max_error_rad) + " rad");
    }
    const core::CameraIntrinsics camera =
        session_camera(bridge.start_camera(options.camera), options.camera_model);
    link.publish_state({{"connection",
                         {{"robot", "connected"},
                          {"head_locked", head.holding},
                          {"detail", bridge.describe()}}},
                        {"recording", recording}});
    // The recording says how the teach ran (mode, head pitch, ceiling), so that `map build`
    // rebuilds this map from it (recording.hpp, format version 2).
    RecordingSetup setup{options.mode, options.head.head_pitch_rad, std::nullopt};
    std::optional<CeilingCameraSetup> ceiling_setup;
    if (ceiling_mode) {
      ceiling_setup = ceiling_camera_for(robot.mock.get(), options.ceiling_height_m, camera,
                                         options.head.head_pitch_rad);
      setup.ceiling = to_recorded(*ceiling_setup);
    }
    if (!options.recording_dir.empty()) {
      writer.emplace(options.recording_dir, camera, bridge.describe(), options.config_json, setup);
    }
    if (ceiling_mode) {
      ceiling_teacher.emplace(*ceiling_setup, camera, options.teach.extractor, options.ceiling);
    } else {
      teacher.emplace(camera, options.teach);
    }
    feedback_limits = options.feedback;
    feedback_limits.half_view_rad = std::atan(0.5 * camera.width_px / camera.fx_px);
    link.event({{"event", "teach_started"},
                {"recording", options.recording_dir.string()},
                {"camera", {{"width_px", camera.width_px}, {"height_px", camera.height_px}}}});

    std::optional<sim::TeachDriver> driver;
    if (options.scripted) driver.emplace(robot.mock->world().scenario);

    nb::BaseVelocity drive{};  // UI drive request
    Clock::time_point drive_at{};
    nb::BaseVelocity sent{};  // what the base is doing
    bool moving = false;
    auto last_frame_at = bridge.stall_clock();
    bool stalled = false;
    int64_t t0_ns = -1;
    std::optional<Eigen::Vector2d> prev_pos;
    auto next_iter = Clock::now();

    for (;;) {
      if (interrupted()) {
        stop_base("interrupted");
        result.outcome = "interrupted";
        break;
      }
      bool finish = false;
      while (auto in = link.poll_intent()) {
        using K = teach_ui::IntentKind;
        switch (in->kind) {
          case K::kDrive:
            drive.v_x_m_s = std::clamp(in->v_m_s, -options.max_v_m_s, options.max_v_m_s);
            drive.omega_rad_s =
                std::clamp(in->omega_rad_s, -options.max_omega_rad_s, options.max_omega_rad_s);
            drive_at = Clock::now();
            break;
          case K::kDriveReleased:
            drive = {};
            break;
          case K::kEmergencyStop:
            drive = {};
            driver.reset();  // a scripted drive does not resume after STOP
            stop_base("ui_stop");
            moving = false;
            sent = {};
            break;
          case K::kStartRecording:
            recording = true;
            link.publish_state({{"recording", true}});
            break;
          case K::kStopRecording:
            recording = false;
            link.publish_state({{"recording", false}});
            feedback = {};
            turn_window.reset();
            publish_feedback(feedback);
            break;
          case K::kFinishTeach:
            finish = true;
            break;
          case K::kStartReplay:
            break;
        }
      }
      if (finish) break;

      // The robot's own view: move failures are reported; a head lock the robot does not let
      // us hold ends the teach (key images taken with a moving head would mislead the replay).
      const SupervisionStep robot_view = supervise_robot(bridge, link);
      for (const auto& w : robot_view.warnings) result.warnings.push_back("robot: " + w);
      if (robot_view.stop_reason) {
        stop_base("head_lock_lost");
        throw std::runtime_error(*robot_view.stop_reason);
      }

      auto frame = bridge.next_frame(std::chrono::milliseconds(100));
      if (!frame) {
        if (!stalled && bridge.stall_clock() - last_frame_at >
                            std::chrono::milliseconds(options.frame_timeout_ms)) {
          stalled = true;
          stop_base("frame_timeout");
          moving = false;
          sent = {};
          result.warnings.push_back("frames stalled: base stopped");
          link.publish_state({{"stop_reason", "no camera frame for " +
                                                  std::to_string(options.frame_timeout_ms) +
                                                  " ms: base stopped"}});
        }
        continue;
      }
      last_frame_at = bridge.stall_clock();
      if (stalled) {
        stalled = false;
        link.publish_state({{"stop_reason", nullptr}});
      }
      if (t0_ns < 0) t0_ns = frame->t_ns;

      // The map's distances: the robot's odometry over every frame (also while not recording:
      // the base moved); where a frame has none, the commanded speed over that interval.
      const double travelled_m = odometer.on_frame(frame->t_ns, sent.v_x_m_s, frame->odom);
      if (frame->odom) {
        ++frames_with_odometry;
      } else {
        ++frames_without_odometry;
        odometry_problem = bridge.odometry_problem();
      }
      // Distance shown and limited (max_distance_m): ground truth on the mock robot, else the
      // map's own measure.
      std::optional<Eigen::Vector2d> pos;
      double yaw_rad = 0.0;  // with pos: the ground-truth base yaw
      if (robot.mock) {
        const auto gt = robot.mock->ground_truth();
        if (gt.collision) {
          throw std::runtime_error("the simulated robot collided with " + gt.collision->what);
        }
        pos = Eigen::Vector2d(gt.base.x_m, gt.base.y_m);
        yaw_rad = gt.base.yaw_rad;
        if (prev_pos) result.distance_m += (*pos - *prev_pos).norm();
        prev_pos = pos;
      } else {
        result.distance_m = travelled_m;
      }

      if (recording) {
        if (writer) writer->append(*frame, sent.v_x_m_s, sent.omega_rad_s);
        ++result.frames_recorded;
      }
      // The plot samples both modes publish, each adding its own counts.
      const auto drive_sample = [&] {
        return nlohmann::json{{"t_s", (frame->t_ns - t0_ns) * 1e-9},
                              {"distance_m", result.distance_m},
                              {"v_m_s", sent.v_x_m_s},
                              {"omega_rad_s", sent.omega_rad_s}};
      };
      // Ceiling mode: this frame's landmarks for the teach view (none when not recording).
      std::optional<core::features::FeatureOverlay> ceiling_overlay;
      if (recording && ceiling_teacher) {
        const core::ceiling::MosaicFrameResult step =
            ceiling_teacher->add_frame(*frame, travelled_m);
        if (link.has_ui()) {
          ceiling_overlay = ceiling_teacher->overlay(step);
          link.publish_state(
              {{"teach", ceiling_teach_state(travelled_m, step, ceiling_teacher->mosaic_landmarks(),
                                             ceiling_teacher->unlocalised_frames(),
                                             ceiling_teacher->loop_closures().size())}});
        }
        if (pos) {
          result.path_m.push_back(*pos);
          result.path_yaw_rad.push_back(yaw_rad);
        }
        // Say so when the ceiling is lost, once per loss, so that the operator can drive back
        // while the teach is still running (the builder re-localises when it sees mapped
        // ceiling again, mosaic_builder.hpp).
        if (step.relocalised) {
          ++ceiling_relocalisations;
          link.event({{"event", "ceiling_relocalised"},
                      {"frame", ceiling_teacher->frames_seen() - 1},
                      {"inliers", step.inliers},
                      {"frames_lost", ceiling_lost_frames}});
        }
        ceiling_lost_frames = step.localised ? 0 : ceiling_lost_frames + 1;
        if (!step.localised && !ceiling_lost) {
          link.event({{"event", "ceiling_lost"},
                      {"frame", ceiling_teacher->frames_seen() - 1},
                      {"matches", step.matches},
                      {"inliers", step.inliers}});
          if (link.has_ui()) {
            link.publish_state({{"stop_reason",
                                 "ceiling lost: no pose in the mosaic; drive back under "
                                 "ceiling already taught"}});
          }
        } else if (step.localised && ceiling_lost && link.has_ui()) {
          link.publish_state({{"stop_reason", nullptr}});
        }
        ceiling_lost = !step.localised;
        if (step.closed_loop && !ceiling_teacher->loop_closures().empty()) {
          // The teach came back under ceiling it mapped long before: the chain was corrected.
          const core::ceiling::LoopClosure& c = ceiling_teacher->loop_closures().back();
          link.event({{"event", "ceiling_loop_closed"},
                      {"frame", ceiling_teacher->frames_seen() - 1},
                      {"old_landmarks", c.old_inliers},
                      {"misplaced_m", c.error_before_m},
                      {"from_travelled_m", c.from_travelled_m},
                      {"to_travelled_m", c.to_travelled_m},
                      {"correction_m", std::hypot(c.T_corrected_chained.x_m,
                                                  c.T_corrected_chained.y_m)},
                      {"correction_rad", c.T_corrected_chained.theta_rad},
                      {"landmarks_moved", c.landmarks_moved}});
        }
        nlohmann::json sample = drive_sample();
        sample["ceiling_inliers"] = step.inliers;
        sample["ceiling_added"] = step.added;
        link.publish_samples(sample);
      } else if (recording) {
        const core::mapping::TeachStep step = teacher->add_frame(*frame, travelled_m);
        if (pos) {
          result.path_m.push_back(*pos);
          result.path_yaw_rad.push_back(yaw_rad);
        }
        // The first frame is always key image 0 (the teacher does not report it as a new one).
        if (step.new_key_frame || step.frame_number == 0) {
          const int k = step.key_image_count - 1;
          // The selector may pick the previous frame: take the position of the frame it chose.
          if (pos) {
            result.key_m.push_back(result.path_m.at(step.new_key_frame.value_or(0)));
            result.key_yaw_rad.push_back(result.path_yaw_rad.at(step.new_key_frame.value_or(0)));
          }
          nlohmann::json key = {{"index", k}, {"distance_m", travelled_m}, {"weak", false}};
          if (step.new_key_rule) {
            key["rule"] = core::mapping::to_string(*step.new_key_rule);
            if (*step.new_key_rule == core::mapping::KeyImageRule::kHeading) {
              ++result.heading_key_images;
            }
          }
          // No feature counts yet: the step's counts are three-view matches, not the key
          // image's own lines and points; the saved map's counts replace the list at the end.
          key_list.push_back(std::move(key));
          link.publish_thumbnail("key/" + std::to_string(k), frame->gray);
        }
        const auto& f = teacher->last_frame_features();
        turn_window.add(frame->t_ns,
                        frame->odom ? std::optional<double>(frame->odom->yaw_rad) : std::nullopt,
                        sent.omega_rad_s);
        TeachView view;
        view.n_lines = static_cast<int>(f.lines.size());
        view.n_points = static_cast<int>(f.corners_px.size());
        // The key image's own richness: the frame the selector took (this one or the previous).
        const int features_now = view.n_lines + view.n_points;
        if (step.frame_number == 0 || step.new_key_frame == step.frame_number) {
          key_features = features_now;
        } else if (step.new_key_frame) {
          key_features = previous_frame_features;
        }
        previous_frame_features = features_now;
        view.key_features = key_features;
        if (step.frame_number > 0) view.verified_with_key = step.count;
        view.turned_over_gap_rad = turn_window.turned_rad();
        view.heading_since_key_rad = step.heading_change_rad;
        feedback = teach_feedback(view, feedback_limits, feedback);
        for (const auto& w : feedback.warnings) ++result.feedback_frames[static_cast<int>(w.kind)];
        publish_feedback(feedback);
        if (link.has_ui()) {
          link.publish_state({{"teach", teach_state(travelled_m, key_list, view.n_lines,
                                                    view.n_points)}});
        }
        nlohmann::json sample = drive_sample();
        sample["n_lines"] = step.n_lines_three_view;
        sample["n_points"] = step.n_points_two_view;
        link.publish_samples(sample);
      }
      if (link.console() != nullptr) {
        Progress p;
        p.phase = "teach";
        p.frames = frames_taught();
        p.distance_m = result.distance_m;
        if (teacher) p.key_index = teacher->key_image_count() - 1;
        if (ceiling_teacher) {
          p.detail =
              "ceiling mosaic, " + std::to_string(ceiling_teacher->unlocalised_frames()) +
              " frames without a pose" + (ceiling_lost ? ", CEILING LOST" : "") +
              (ceiling_relocalisations == 0
                   ? ""
                   : ", re-localised " + std::to_string(ceiling_relocalisations)) +
              (ceiling_teacher->loop_closures().empty()
                   ? ""
                   : ", loops closed " + std::to_string(ceiling_teacher->loop_closures().size()));
        }
        if (!recording) p.detail = "not recording";
        link.progress(p);
      }
      nlohmann::json overlay = nlohmann::json::object();
      if (recording && teacher && link.has_ui()) {  // the teacher has just extracted them
        overlay = overlay_to_json(
            core::features::detected_overlay(teacher->last_frame_features()), "detected");
      } else if (ceiling_overlay) {
        overlay = ceiling_overlay_to_json(*ceiling_overlay);
      }
      overlay["text"] = nlohmann::json::array(
          {std::string(recording ? "REC " : "") + "frame " + std::to_string(frame->index) +
           (teacher ? ", key images " + std::to_string(teacher->key_image_count())
                    : std::string(", ceiling mosaic") + (ceiling_lost ? " (lost)" : ""))});
      link.publish_frame(*frame, overlay);

      // Command for the next frame period.
      nb::BaseVelocity cmd{};
      if (driver) {
        const auto gt = robot.mock->ground_truth();
        cmd = driver->command(gt.base, (frame->t_ns - t0_ns) * 1e-9);
        if (driver->done()) finish = true;
      } else if (Clock::now() - drive_at <
                 std::chrono::duration<double>(options.drive_timeout_s)) {
        cmd = drive;
      }
      if (options.max_distance_m > 0 && result.distance_m >= options.max_distance_m) finish = true;
      if (options.max_frames > 0 && frames_taught() >= options.max_frames) finish = true;
      if (finish) break;
      const bool want_move = cmd.v_x_m_s != 0.0 || cmd.omega_rad_s != 0.0;
      if (want_move) {
        bridge.move(cmd);
        moving = true;
        sent = cmd;
        link.command_event(cmd.v_x_m_s, cmd.omega_rad_s, false, driver ? "scripted" : "operator");
        link.publish_state({{"drive", {{"v_m_s", cmd.v_x_m_s}, {"omega_rad_s", cmd.omega_rad_s}}}});
      } else if (moving) {
        stop_base("released");
        moving = false;
        sent = {};
      }
      if (robot.mock) {
        const auto gt = robot.mock->ground_truth();
        link.publish_state({{"pose", {{"x_m", gt.base.x_m}, {"y_m", gt.base.y_m},
                                      {"yaw_rad", gt.base.yaw_rad}}}});
      }
      if (options.pace_hz > 0) {
        next_iter += std::chrono::duration_cast<Clock::duration>(
            std::chrono::duration<double>(1.0 / options.pace_hz));
        std::this_thread::sleep_until(next_iter);
        if (Clock::now() > next_iter + std::chrono::seconds(1)) next_iter = Clock::now();
      }
    }
    if (result.outcome.empty()) {
      stop_base("tour_finished");
      result.outcome = "finished";
    }
  } catch (const std::exception& e) {
    bridge.stop();  // first, before anything else
    link.command_event(0.0, 0.0, true, "error");
    result.outcome = "failed";
    result.error = e.what();
    result.error_exception = std::current_exception();
  }

  link.end_progress();
  publish_feedback(TeachFeedback{});  // the session is over: nothing is live to warn about
  result.distance_from_odometry_m = odometer.from_odometry_m();
  if (frames_with_odometry == 0 && frames_without_odometry > 0) {
    result.warnings.push_back("the robot gave no odometry" +
                              (odometry_problem.empty() ? "" : " (" + odometry_problem + ")") +
                              ": the map's distances come from the commanded speeds");
  } else if (frames_without_odometry > 0) {
    result.warnings.push_back(std::to_string(frames_without_odometry) + " of " +
                              std::to_string(frames_with_odometry + frames_without_odometry) +
                              " frames came without odometry (last: " + odometry_problem +
                              "): their intervals are measured by the commanded speed");
  }
  if (odometer.odometry_jumps() > 0) {
    result.warnings.push_back(std::to_string(odometer.odometry_jumps()) +
                              " odometry steps faster than the robot can drive were ignored "
                              "(odometry reset?) and measured by the commanded speed instead");
  }
  result.frames_seen = frames_taught();
  // Save what can be saved: the recording is already on disk; now the map.
  if (ceiling_teacher && ceiling_teacher->frames_seen() >= 2) {
    try {
      const CeilingMap cm = ceiling_teacher->finish(options.config_json);
      save_ceiling_map(cm, options.map_dir);
      result.map_saved = true;
      result.key_images = static_cast<int>(cm.map.key_images.size());
      result.ceiling_landmarks = static_cast<int64_t>(cm.mosaic.landmarks.size());
      result.ceiling_unlocalised_frames = cm.tour.unlocalised_frames;
      result.map_length_m =
          cm.map.key_images.back().travelled_m - cm.map.key_images.front().travelled_m;
      for (const auto& w : ceiling_warnings(cm.tour)) result.warnings.push_back(w);
      if (cm.tour.height_check) {
        // The configured ceiling height against the odometry (docs/method/ceiling.md "Checking
        // the ceiling height at teach"): reported, never changed.
        const core::ceiling::HeightCheck& h = *cm.tour.height_check;
        nlohmann::json ev = {{"event", "ceiling_height_check"}};
        ev.update(core::ceiling::height_check_to_json(h));  // the tour file's object
        link.event(ev);
        if (const auto w = ceiling_height_warning(h)) result.warnings.push_back(*w);
      }
      if (robot.mock && !result.path_m.empty()) {
        // path_m has one position per taught frame, as the relay images' frame indices count.
        for (const auto& r : cm.tour.relay_images) {
          result.key_m.push_back(result.path_m.at(static_cast<size_t>(r.frame)));
          result.key_yaw_rad.push_back(result.path_yaw_rad.at(static_cast<size_t>(r.frame)));
        }
        try {
          save_taught_path(options.map_dir,
                           {robot.mock->world().name, result.path_m, result.key_m});
        } catch (const std::exception& e) {
          result.warnings.push_back(std::string("taught path not saved (top view only): ") +
                                    e.what());
        }
      }
      link.publish_state({{"map_summary",
                           {{"mode", "ceiling"},
                            {"key_images", result.key_images},
                            {"length_m", result.map_length_m},
                            {"landmarks", result.ceiling_landmarks},
                            {"path", options.map_dir.string()}}},
                          {"warnings", result.warnings}});
      link.event({{"event", "map_saved"},
                  {"path", options.map_dir.string()},
                  {"mode", "ceiling"},
                  {"key_images", result.key_images},
                  {"landmarks", result.ceiling_landmarks},
                  {"relay_breaks", cm.tour.breaks},
                  {"unlocalised_frames", cm.tour.unlocalised_frames}});
    } catch (const std::exception& e) {
      result.warnings.push_back(std::string("map not saved: ") + e.what() +
                                " (the recording keeps the frames)");
    }
  } else if (teacher && teacher->frames_seen() >= 2) {
    try {
      core::memory::VisualMemory map = teacher->finish(options.config_json);
      core::memory::save_map(map, options.map_dir);
      result.map_saved = true;
      if (robot.mock && !result.path_m.empty()) {
        // finish() makes the last frame the final key image when the selector had not.
        if (result.key_m.size() < map.key_images.size()) {
          result.key_m.push_back(result.path_m.back());
          result.key_yaw_rad.push_back(result.path_yaw_rad.back());
        }
        try {
          save_taught_path(options.map_dir,
                           {robot.mock->world().name, result.path_m, result.key_m});
        } catch (const std::exception& e) {
          result.warnings.push_back(std::string("taught path not saved (top view only): ") +
                                    e.what());
        }
      }
      const core::memory::MapSummary summary = core::memory::summarize(map);
      result.key_images = summary.key_image_count;
      nlohmann::json weak = nlohmann::json::array();
      int min_lines = 1 << 30, min_points = 1 << 30;
      for (std::size_t i = 0; i < summary.key_images.size(); ++i) {
        const auto& k = summary.key_images[i];
        min_lines = std::min(min_lines, k.lines);
        min_points = std::min(min_points, k.corners);
        if (k.lines + k.corners < options.min_key_features) {
          weak.push_back(i);
          result.warnings.push_back("key image " + std::to_string(i) + " has few features (" +
                                    std::to_string(k.lines) + " lines, " +
                                    std::to_string(k.corners) +
                                    " points): replay may get lost there; add texture or "
                                    "re-teach this part");
        }
      }
      // The panel, the strip and the "Map saved" box all show the saved map: its key images
      // (finish() may have added the last frame), their own feature counts, its driven length.
      const double map_length_m =
          summary.key_images.empty()
              ? 0.0
              : summary.key_images.back().travelled_m - summary.key_images.front().travelled_m;
      result.map_length_m = map_length_m;
      nlohmann::json saved_keys = nlohmann::json::array();
      const double first_m = summary.key_images.empty() ? 0.0 : summary.key_images[0].travelled_m;
      for (std::size_t i = 0; i < summary.key_images.size(); ++i) {
        const auto& k = summary.key_images[i];
        const bool is_weak = k.lines + k.corners < options.min_key_features;
        nlohmann::json key = {{"index", i},
                              {"n_lines", k.lines},
                              {"n_points", k.corners},
                              {"distance_m", k.travelled_m - first_m},
                              {"weak", is_weak}};
        if (i < key_list.size() && key_list[i].contains("rule")) key["rule"] = key_list[i]["rule"];
        saved_keys.push_back(std::move(key));
        if (link.has_ui()) {
          link.publish_thumbnail("key/" + std::to_string(i), map.key_images[i].features.gray);
        }
      }
      link.publish_state({{"teach", {{"key_images", saved_keys}, {"distance_m", map_length_m}}}});
      link.publish_state({{"map_summary",
                           {{"key_images", summary.key_image_count},
                            {"length_m", map_length_m},
                            {"min_lines", min_lines},
                            {"min_points", min_points},
                            {"weak_key_images", weak},
                            {"path", options.map_dir.string()}}},
                          {"warnings", result.warnings}});
      link.event({{"event", "map_saved"},
                  {"path", options.map_dir.string()},
                  {"key_images", summary.key_image_count},
                  {"weak_key_images", weak}});
    } catch (const std::exception& e) {
      result.warnings.push_back(std::string("map not saved: ") + e.what() +
                                " (the recording can be turned into a map with `map build`)");
    }
  } else {
    result.warnings.push_back("map not saved: fewer than 2 frames taught");
  }
  bridge.release();
  // The page must not show a live session after it ended: recording off, robot released.
  link.publish_state({{"recording", false},
                      {"drive", {{"v_m_s", 0.0}, {"omega_rad_s", 0.0}}},
                      {"connection", {{"robot", "disconnected"},
                                      {"head_locked", false},
                                      {"detail", "teach ended (" + result.outcome + ")"}}}});
  link.event({{"event", "teach_done"},
              {"outcome", result.outcome},
              {"error", result.error},
              {"frames", result.frames_recorded},
              {"key_images", result.key_images},
              {"map_saved", result.map_saved},
              // Recorded frames on which each live warning was shown (teach_feedback.hpp).
              {"warning_frames",
               {{to_string(TeachWarningKind::kFewFeatures), result.feedback_frames[0]},
                {to_string(TeachWarningKind::kTurningFast), result.feedback_frames[1]},
                {to_string(TeachWarningKind::kOverlapLost), result.feedback_frames[2]}}}});
  return result;
}

}  // namespace pepper::app
