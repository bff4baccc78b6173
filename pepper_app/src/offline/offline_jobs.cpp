#include "offline/offline_jobs.hpp"

#include <algorithm>
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

}  // namespace

core::memory::VisualMemory build_map_from_recording(const Recording& recording,
                                                    const core::mapping::TeachOptions& options,
                                                    bool every_frame_key,
                                                    const std::string& parameters_json,
                                                    const ProgressFn& progress,
                                                    std::vector<core::mapping::TeachStep>* steps) {
  const std::size_t total = recording.frames.size();
  // Distance driven to each frame, from the recorded odometry where frames have it, else the
  // recorded commands, as teach measured it (NaN for plain image folders).
  std::vector<double> travelled_m(total, std::numeric_limits<double>::quiet_NaN());
  if (recording.commands_known) {
    core::mapping::DriveOdometer odometer;
    for (std::size_t i = 0; i < total; ++i) {
      const RecordedFrame& f = recording.frames[i];
      travelled_m[i] = odometer.on_frame(f.t_ns, f.v_m_s, f.odom);
    }
  }
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
