#include "offline/offline_jobs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "core/mapping/drive_odometer.hpp"
#include "session/telemetry_json.hpp"

namespace pepper::app {

namespace {

void check_size(const core::Frame& frame, const cv::Size& expected, const Recording& rec,
                std::size_t i) {
  if (frame.gray.size() != expected) {
    throw RecordingError(rec.frames[i].file.string() + ": image is " +
                         std::to_string(frame.gray.cols) + "x" + std::to_string(frame.gray.rows) +
                         " but earlier frames are " + std::to_string(expected.width) + "x" +
                         std::to_string(expected.height));
  }
}

core::CameraIntrinsics camera_for(const core::CameraIntrinsics& camera, const cv::Size& size) {
  if (camera.width_px == size.width && camera.height_px == size.height) return camera;
  return camera.scaled_to(size.width, size.height);
}

/// Distance driven to each frame, from the recorded odometry where frames have it, else the
/// recorded commands, as teach measured it (NaN for plain image folders).
std::vector<double> travelled_per_frame(const Recording& recording) {
  std::vector<double> travelled_m(recording.frames.size(),
                                  std::numeric_limits<double>::quiet_NaN());
  if (recording.commands_known) {
    core::mapping::DriveOdometer odometer;
    for (std::size_t i = 0; i < recording.frames.size(); ++i) {
      const RecordedFrame& f = recording.frames[i];
      travelled_m[i] = odometer.on_frame(f.t_ns, f.v_m_s, f.odom);
    }
  }
  return travelled_m;
}

std::string radians(double rad) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f rad", rad);
  return text;
}

/// A number of the recorded configuration (`robot.KEY`), if it holds a finite one.
std::optional<double> recorded_robot_setting(const Recording& recording, const char* key) {
  const nlohmann::json& c = recording.config;
  if (!c.is_object() || !c.contains("robot") || !c["robot"].is_object()) return std::nullopt;
  const nlohmann::json& r = c["robot"];
  if (!r.contains(key) || !r[key].is_number()) return std::nullopt;
  const double v = r[key].get<double>();
  return std::isfinite(v) ? std::optional<double>(v) : std::nullopt;
}

}  // namespace

core::NavMode map_build_mode(const Recording& recording, std::optional<core::NavMode> requested) {
  if (!recording.setup) return requested.value_or(core::NavMode::kForward);
  const RecordingSetup& taught = *recording.setup;
  if (!requested || *requested == taught.mode) return taught.mode;
  const std::string dir = recording.folder.string();
  if (taught.mode == core::NavMode::kCeiling) {
    throw std::invalid_argument(
        dir + " was taught in ceiling mode (head at " + radians(taught.head_pitch_rad) +
        ", looking up at the ceiling): --mode forward would make key images of the ceiling, "
        "which a forward replay never sees; build it in ceiling mode (drop --mode forward)");
  }
  throw std::invalid_argument(
      dir + " was taught in forward mode (head at " + radians(taught.head_pitch_rad) +
      ", looking ahead): its frames do not look up at the ceiling as a ceiling map needs; build "
      "it in forward mode (drop --mode ceiling), or teach the tour again with --mode ceiling");
}

core::CameraIntrinsics recording_frame_camera(const Recording& recording) {
  return camera_for(recording.camera, load_frame(recording, 0).gray.size());
}

CeilingCameraSetup ceiling_setup_for_build(const Recording& recording,
                                           const core::CameraIntrinsics& camera,
                                           const CeilingBuildInputs& inputs) {
  if (recording.setup && recording.setup->ceiling) {
    return ceiling_setup_of_recorded(*recording.setup->ceiling, camera,
                                     recording.setup->head_pitch_rad, inputs.ceiling_height_m);
  }
  // Not recorded: a real Pepper's head geometry (the simulated robot's within a millimetre,
  // SessionMode.APeppersCeilingCameraIsTheSimulatedOnes) under the height the operator gives.
  const std::optional<double> recorded_height_m =
      recorded_robot_setting(recording, "ceiling_height_m");
  const double height_m = inputs.ceiling_height_m > 0.0 ? inputs.ceiling_height_m
                          : recorded_height_m && *recorded_height_m > 0.0
                              ? *recorded_height_m
                              : 0.0;
  if (!(height_m > 0.0)) {
    throw std::invalid_argument(
        recording.folder.string() +
        ": this recording does not say how high the ceiling was (" +
        (recording.version == 1 ? std::string("recording format version 1, before issue 24")
                                : std::string("not a teach's recording")) +
        "): give the ceiling's height above the floor where it was recorded, e.g. --set "
        "robot.ceiling_height_m=2.7 (a mock: world's ceiling_height_m)");
  }
  const double pitch_rad =
      recorded_robot_setting(recording, "ceiling_head_pitch_rad").value_or(inputs.head_pitch_rad);
  return ceiling_camera_of_pepper(height_m, camera, pitch_rad);
}

CeilingBuild build_ceiling_map_from_recording(
    const Recording& recording, const CeilingCameraSetup& setup,
    const core::features::FeatureExtractorOptions& extractor, const CeilingTeachOptions& options,
    const std::string& parameters_json, const ProgressFn& progress) {
  const std::size_t total = recording.frames.size();
  const std::vector<double> travelled_m = travelled_per_frame(recording);
  const core::Frame first = load_frame(recording, 0);
  const cv::Size size = first.gray.size();
  const core::CameraIntrinsics camera = camera_for(recording.camera, size);
  CeilingTeacher teacher(setup, camera, extractor, options);
  CeilingBuild out;
  for (std::size_t i = 0; i < total; ++i) {
    const core::Frame frame = i == 0 ? first : load_frame(recording, i);
    check_size(frame, size, recording, i);
    if (teacher.add_frame(frame, travelled_m[i]).relocalised) ++out.relocalisations;
    if (progress) progress(i + 1, total);
  }
  out.loops_closed = static_cast<int>(teacher.loop_closures().size());
  out.map = teacher.finish(parameters_json);
  return out;
}

core::memory::VisualMemory build_map_from_recording(const Recording& recording,
                                                    const core::mapping::TeachOptions& options,
                                                    bool every_frame_key,
                                                    const std::string& parameters_json,
                                                    const ProgressFn& progress,
                                                    std::vector<core::mapping::TeachStep>* steps) {
  const std::size_t total = recording.frames.size();
  const std::vector<double> travelled_m = travelled_per_frame(recording);
  const core::Frame first = load_frame(recording, 0);
  const cv::Size size = first.gray.size();
  const core::CameraIntrinsics camera = camera_for(recording.camera, size);

  if (every_frame_key) {
    if (total < 2) throw RecordingError(recording.folder.string() + ": a map needs 2+ images");
    core::features::FeatureExtractor extractor(camera, options.extractor);
    core::memory::VisualMemory map;
    map.camera = camera;
    map.parameters_json = parameters_json;
    for (std::size_t i = 0; i < total; ++i) {
      const core::Frame frame = i == 0 ? first : load_frame(recording, i);
      check_size(frame, size, recording, i);
      core::memory::KeyImage key;
      key.source_frame_index = frame.index;
      key.t_ns = frame.t_ns;
      key.travelled_m = travelled_m[i];
      key.odom = frame.odom;
      key.features = extractor.extract(frame.gray);
      map.key_images.push_back(std::move(key));
      if (progress) progress(i + 1, total);
    }
    return map;
  }

  core::mapping::Teacher teacher(camera, options);
  for (std::size_t i = 0; i < total; ++i) {
    const core::Frame frame = i == 0 ? first : load_frame(recording, i);
    check_size(frame, size, recording, i);
    const core::mapping::TeachStep step = teacher.add_frame(frame, travelled_m[i]);
    if (steps) steps->push_back(step);
    if (progress) progress(i + 1, total);
  }
  return teacher.finish(parameters_json);
}

void write_teach_steps_csv(const std::vector<core::mapping::TeachStep>& steps,
                           const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  out << "frame,n_lines_3v,n_points_2v,count,reference,new_key,key_images\n";
  for (const auto& s : steps) {
    out << s.frame_number << ',' << s.n_lines_three_view << ',' << s.n_points_two_view << ','
        << s.count << ',' << s.reference_count << ',' << (s.new_key_frame ? *s.new_key_frame : -1)
        << ',' << s.key_image_count << '\n';
  }
  if (!out) throw std::runtime_error(path + ": write failed");
}

nlohmann::json ReplayLogResult::to_json() const {
  nlohmann::json out;
  out["summary"] = {{"frames", frames.size()},
                    {"reached_end", reached_end},
                    {"max_key_image_reached", max_key_image_reached},
                    {"key_image_count", key_image_count}};
  nlohmann::json list = nlohmann::json::array();
  for (const auto& f : frames) {
    list.push_back({{"frame_index", f.frame_index},
                    {"odom", odometry_to_json(f.odom)},
                    {"command", command_to_json(f.command)},
                    {"telemetry", telemetry_to_json(f.telemetry)}});
  }
  out["frames"] = std::move(list);
  return out;
}

ReplayLogResult replay_log(const Recording& recording, core::memory::VisualMemory map,
                           const core::navigator::NavigatorOptions& options,
                           const ProgressFn& progress) {
  ReplayLogResult result;
  result.key_image_count = static_cast<int>(map.key_images.size());
  const cv::Size map_size(map.camera.width_px, map.camera.height_px);
  core::navigator::Navigator navigator(std::move(map), options);
  const std::size_t total = recording.frames.size();
  for (std::size_t i = 0; i < total; ++i) {
    core::Frame frame = load_frame(recording, i);
    if (i == 0 && frame.gray.size() != map_size) {
      // Issue 30: the map decides the size, and only what cannot be matched is refused. A
      // recording k times the map's size in both directions is the same view at more pixels.
      const int k = frame.gray.cols / std::max(1, map_size.width);
      if (k >= 2 && frame.gray.cols == k * map_size.width && frame.gray.rows == k * map_size.height) {
        result.downscale = k;
      } else {
        throw RecordingError(recording.folder.string() + ": frames are " +
                             std::to_string(frame.gray.cols) + "x" +
                             std::to_string(frame.gray.rows) + " but the map was taught at " +
                             std::to_string(map_size.width) + "x" +
                             std::to_string(map_size.height) +
                             ": replay-log needs frames of the map's size or a whole multiple of "
                             "it; replay a recording of this camera size against a map taught "
                             "at it");
      }
    }
    // Only frames of the scaled size are scaled: one of any other size reaches the navigator as it
    // is and is refused there, naming its size.
    if (result.downscale > 1 && frame.gray.cols == result.downscale * map_size.width &&
        frame.gray.rows == result.downscale * map_size.height) {
      cv::Mat small;
      cv::resize(frame.gray, small, map_size, 0, 0, cv::INTER_AREA);
      frame.gray = small;
    }
    const core::navigator::StepResult step = navigator.step(frame);
    result.max_key_image_reached = std::max(result.max_key_image_reached, step.telemetry.in);
    if (step.telemetry.state == core::navigator::NavState::kTourComplete) result.reached_end = true;
    result.frames.push_back({frame.index, frame.odom, step.command, step.telemetry});
    if (progress) progress(i + 1, total);
  }
  return result;
}

}  // namespace pepper::app
