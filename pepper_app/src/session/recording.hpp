#pragma once
// Recordings of teach sessions: what the camera saw, frame by frame, kept so that an interrupted
// session (Ctrl-C, crash, lost robot) can still be turned into a map later (`map build`).
//
// Layout of a recording folder (format "pepper-recording", version 2; version 1 is read too):
//   recording.json   manifest: format, version, camera intrinsics, source URL, start time,
//                    free-form "config" (the effective configuration). Written atomically at start.
//                    Since version 2 (issue 24), a teach also writes how it ran, so that `map
//                    build` rebuilds its map in the same mode with the same camera geometry:
//                    "mode" ("forward" or "ceiling"), "head_pitch_rad" (the head lock's pitch)
//                    and, in ceiling mode, "ceiling" {"height_m" (above the floor),
//                    "above_camera_m" (above the optical centre), "camera_in_base_m" {"x_m",
//                    "y_m"} (the optical centre on the base)}. Replay's recordings (`--record`)
//                    and version 1 have none of them: their mode is not known.
//   frames.jsonl     one JSON object per line and per frame, appended and flushed as frames come:
//                    {"index": i, "t_ns": t, "file": "frames/000123.png",
//                     "v_m_s": v, "omega_rad_s": w,   (the command in force when it was taken)
//                     "odom": {"x_m": x, "y_m": y, "yaw_rad": a}}   (Frame::odom; absent when
//                    the frame had none, and in recordings made before it existed)
//   frames/NNNNNN.png  the grey frames, each written to a temp name and renamed before its index
//                    line is appended, so every indexed frame is complete.
// A crash can at worst leave a partial last line in frames.jsonl; the reader skips it and says so.
//
// A plain folder of images (png/jpg/jpeg/bmp/pgm/ppm, taken in name order) is also accepted as a
// recording; its camera comes from a separate file and its timestamps from a nominal rate.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/camera/intrinsics.hpp"
#include "core/frame.hpp"
#include "core/nav_mode.hpp"

namespace pepper::app {

/// A recording that cannot be read or written; what() names the file.
class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RecordedFrame {
  int64_t index = 0;
  int64_t t_ns = 0;
  std::filesystem::path file;  ///< absolute or relative to the recording folder
  double v_m_s = 0.0;          ///< command in force when the frame was taken (0 when unknown)
  double omega_rad_s = 0.0;
  std::optional<core::OdometryPose> odom;  ///< the robot's odometry with the frame, if it had one
};

/// The ceiling a ceiling-mode teach ran under (ceiling_teach.hpp CeilingCameraSetup): metres.
struct RecordedCeiling {
  double height_m = 0.0;         ///< the ceiling above the floor
  double above_camera_m = 0.0;   ///< the ceiling above the optical centre (> 0): the scale
  double cam_in_base_x_m = 0.0;  ///< the optical centre's horizontal offset from the
  double cam_in_base_y_m = 0.0;  ///< rotation axis (base frame: x forward, y left)
};

/// How a teach ran (recording format version 2): what `map build` needs to rebuild its map.
struct RecordingSetup {
  core::NavMode mode = core::NavMode::kForward;
  double head_pitch_rad = 0.0;             ///< the pitch the head was locked at (rad, > 0 down)
  std::optional<RecordedCeiling> ceiling;  ///< ceiling mode: always; forward mode: never
};

class RecordingWriter {
 public:
  /// Creates `folder` (must not exist or be empty) and writes the manifest; `setup`: a teach's
  /// (nullopt: the mode is not said, as in replay's recordings). Throws RecordingError, also
  /// for a setup whose mode and ceiling disagree or whose numbers are not finite.
  RecordingWriter(std::filesystem::path folder, const core::CameraIntrinsics& camera,
                  const std::string& source, const std::string& config_json = "{}",
                  const std::optional<RecordingSetup>& setup = std::nullopt);
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  /// Writes the frame's PNG (atomically) and appends its index line (flushed).
  void append(const core::Frame& frame, double v_m_s, double omega_rad_s);

  int64_t frame_count() const { return count_; }
  const std::filesystem::path& folder() const { return folder_; }

 private:
  std::filesystem::path folder_;
  std::ofstream index_;
  int64_t count_ = 0;
};

struct Recording {
  std::filesystem::path folder;
  core::CameraIntrinsics camera;
  std::string source;                 ///< where it was recorded ("plain image folder" otherwise)
  int version = 0;                    ///< of our format (1, 2); 0 for a plain image folder
  /// How the teach ran (version 2 teach recordings); nullopt when the recording does not say
  /// (version 1, replay's recordings, plain image folders).
  std::optional<RecordingSetup> setup;
  /// The manifest's "config" (the recording session's effective configuration; null if none).
  nlohmann::json config;
  std::vector<RecordedFrame> frames;  ///< in order
  /// Whether frames carry the commands in force (our format); a plain image folder has none.
  bool commands_known = false;
  std::vector<std::string> warnings;  ///< e.g. a partial last index line that was skipped
};

/// The camera a live session normalises features with: `calibration` (a `--camera` file, e.g.
/// with Pepper's lens model) scaled to the size the robot's camera delivers, else the intrinsics
/// the robot reports. Teach records it, and replay checks it against the map's.
core::CameraIntrinsics session_camera(const core::CameraIntrinsics& reported,
                                      const std::optional<core::CameraIntrinsics>& calibration);

/// Reads a recording folder (ours, or a plain image folder when `camera_override` is given or the
/// folder has no manifest). Plain folders get t_ns = i * 1e9 / nominal_fps.
/// Throws RecordingError naming the file on any problem (missing camera for a plain folder, bad
/// manifest, missing frame file, no frames, a version-2 setup that is malformed).
Recording read_recording(const std::filesystem::path& folder,
                         const std::optional<core::CameraIntrinsics>& camera_override,
                         double nominal_fps = 15.0);

/// Loads one recorded frame as 8-bit grey (colour images are converted), with its stamp, index
/// and odometry. Throws RecordingError.
core::Frame load_frame(const Recording& recording, std::size_t i);

}  // namespace pepper::app
