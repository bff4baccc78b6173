#pragma once
// Ceiling-mode teach (issue 24; docs/method/ceiling.md): the part of the teach session that runs
// where the forward key-image selector runs in forward mode. Per frame: the canonical ceiling
// view (CanonicalView::warp), its landmarks (extract_landmarks, observe) and one MosaicBuilder
// step. The relay images are only chosen at the end, when the builder knows which landmarks it
// kept, so every frame's grey image is needed until then: it goes to disk as it comes (a
// TeachFrameStore, lossless PNG in a temporary folder the teacher owns), and RAM keeps per frame
// only its stamp, distance and odometry (docs/method/ceiling.md "Teach memory"; at VGA, 15 fps
// the images alone were 2.7 GB per 10 minutes). finish() picks the relay images
// (select_relay_images), reads back only those, and makes a CeilingMap: a VisualMemory in
// ceiling mode whose key images are the relay images (grey image and features, so every map tool
// reads it), the mosaic and the CeilingTour (relay poses and landmarks, breaks, drift
// indicators).
//
// The camera geometry (ceiling height above the optical centre, the optical centre on the base)
// comes from the simulated robot (ceiling_camera_of_mock) or, on a real Pepper, from its head
// geometry and the configured robot.ceiling_height_m (ceiling_camera_of_pepper). The tour records
// that ceiling (CeilingTour::ceiling) so that a replay under another one is refused, and checks
// it against the wheel odometry (core/ceiling/height_check.hpp; CeilingTour::height_check): a
// wrong height scales every distance of the mosaic, and finish() says so, it never changes it.
// Frames and units: core/ceiling (base frame x forward, y left, metres; mosaic frame = base frame
// of the first frame). Errors: bad options throw std::invalid_argument; finish() throws
// std::runtime_error when the tour gives no usable mosaic (fewer than 2 frames or no landmark),
// and the constructor, add_frame() and finish() throw std::runtime_error naming the path when the
// frame store fails (folder not creatable, image not written, image missing or damaged).
// Not thread-safe (one teach).

#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/ceiling/canonical_view.hpp"
#include "core/ceiling/ceiling_tour.hpp"
#include "core/ceiling/height_check.hpp"
#include "core/ceiling/mosaic.hpp"
#include "core/ceiling/mosaic_builder.hpp"
#include "core/ceiling/relay_images.hpp"
#include "core/features/feature_overlay.hpp"
#include "core/features/image_features.hpp"
#include "core/frame.hpp"
#include "core/memory/visual_memory.hpp"
#include "session/recording.hpp"
#include "sim/mock_robot.hpp"

namespace pepper::app {

/// The canonical view's geometry and where the optical centre is on the base.
struct CeilingCameraSetup {
  core::ceiling::CeilingCamera camera;
  cv::Point2d cam_in_base_m;  ///< optical centre's horizontal offset from the rotation axis
  double ceiling_height_m = 0.0;  ///< the ceiling above the floor (camera.ceiling_above_cam_m
                                  ///< is above the optical centre)
};

/// The simulated robot's: its world's ceiling height and its camera mount at `head_pitch_rad`.
/// Throws std::invalid_argument when the ceiling is not above the camera.
CeilingCameraSetup ceiling_camera_of_mock(const sim::MockRobot& robot,
                                          const core::CameraIntrinsics& camera,
                                          double head_pitch_rad);

/// A real Pepper's: the top camera's mount at `head_pitch_rad` (geometry::pepper_top_camera)
/// and the ceiling `ceiling_height_m` above the floor (robot.ceiling_height_m). Throws
/// std::invalid_argument when the ceiling is not above the camera (or not set: 0).
CeilingCameraSetup ceiling_camera_of_pepper(double ceiling_height_m,
                                            const core::CameraIntrinsics& camera,
                                            double head_pitch_rad);

/// The one a session uses: the simulated robot's when there is one (`mock`, its world's
/// ceiling), else a real Pepper's with the configured height.
CeilingCameraSetup ceiling_camera_for(const sim::MockRobot* mock, double ceiling_height_m,
                                      const core::CameraIntrinsics& camera, double head_pitch_rad);

/// The setup as a teach records it (recording.hpp, format version 2), and back: the same
/// numbers, so that `map build` runs the live teach's canonical view on the recorded frames.
RecordedCeiling to_recorded(const CeilingCameraSetup& setup);

/// The recorded setup with `camera` and `head_pitch_rad` (the recording's). `ceiling_height_m`
/// > 0 and not the recorded height replaces it, the camera's height on the base staying the
/// recorded one (a rebuild under a corrected ceiling). Throws std::invalid_argument when the
/// ceiling is then not above the camera.
CeilingCameraSetup ceiling_setup_of_recorded(const RecordedCeiling& recorded,
                                             const core::CameraIntrinsics& camera,
                                             double head_pitch_rad, double ceiling_height_m = 0.0);

struct CeilingTeachOptions {
  /// Canonical scale: 120 px/m drifted least on the test hall at QVGA (docs/method/ceiling.md).
  double px_per_m = 120.0;
  /// The canonical view ends this far ahead of the optical centre (rows near the horizon see
  /// the ceiling too far away to resolve).
  double max_forward_m = 3.5;
  core::ceiling::MosaicBuilderOptions builder;  ///< its px_per_m is replaced by the one above
  core::ceiling::RelayOptions relay;
  core::ceiling::HeightCheckOptions height_check;
  /// Where the teach keeps its frames' images until the teacher goes (a fresh folder inside
  /// it, see TeachFrameStore); empty: the system's temporary folder ($TMPDIR).
  std::filesystem::path frame_store_parent;
};

/// The warning for a height check that disagrees with the configured height (nullopt when it
/// agrees or gave no estimate): the measured height, by how much every distance of the map is
/// off, and how to re-teach (--set robot.ceiling_height_m=X). For the console and `map info`.
std::optional<std::string> ceiling_height_warning(const core::ceiling::HeightCheck& check);

/// The teach frames' grey images on disk while a ceiling teach runs (CeilingTeacher): a fresh
/// folder (`pepper_ceiling_teach_<pid>_<n>_<random>`) in `parent`, or in the system's temporary
/// folder (std::filesystem::temp_directory_path(), i.e. $TMPDIR) when `parent` is empty, holding
/// one lossless PNG per frame (`frame_00000012.png`); removed with everything in it when the
/// store is destroyed (also when a teach or finish() throws; not after a SIGKILL: such folders
/// stay in the temporary folder). Errors: std::runtime_error naming the path.
class TeachFrameStore {
 public:
  explicit TeachFrameStore(const std::filesystem::path& parent = {});
  ~TeachFrameStore();
  TeachFrameStore(const TeachFrameStore&) = delete;
  TeachFrameStore& operator=(const TeachFrameStore&) = delete;

  /// Writes frame `index`'s image now (nothing is buffered); replaces an earlier one of that
  /// index. `gray`: CV_8UC1, the size of every other frame of the store.
  void put(size_t index, const cv::Mat& gray);
  /// Reads frame `index`'s image back: the pixels put() got, bit for bit.
  cv::Mat get(size_t index) const;

  const std::filesystem::path& dir() const { return dir_; }
  std::filesystem::path file_of(size_t index) const;
  /// The PNG bytes written so far (the last write of each index), for the memory notes.
  uint64_t bytes_on_disk() const { return bytes_on_disk_; }

 private:
  std::filesystem::path dir_;
  cv::Size size_;                     ///< of the first image put; every image has it
  std::vector<uint32_t> file_bytes_;  ///< per index, to keep bytes_on_disk() right on rewrites
  uint64_t bytes_on_disk_ = 0;
};

/// A ceiling-mode map: the three parts saved in one map folder (ceiling_map.hpp).
struct CeilingMap {
  core::memory::VisualMemory map;  ///< mode ceiling; key images = the relay images
  core::ceiling::Mosaic mosaic;
  core::ceiling::CeilingTour tour;
};

class CeilingTeacher {
 public:
  /// `camera`: the started camera's intrinsics (the key images' features are extracted with
  /// them and `extractor`).
  CeilingTeacher(const CeilingCameraSetup& setup, const core::CameraIntrinsics& camera,
                 const core::features::FeatureExtractorOptions& extractor,
                 CeilingTeachOptions options = {});

  /// One taught frame; travelled_m as the forward teacher takes it (drive_odometer.hpp). Its
  /// image is written to the frame store before the mosaic builder's step: when that write
  /// fails (std::runtime_error naming the file) the teacher is as it was before the call.
  core::ceiling::MosaicFrameResult add_frame(
      const core::Frame& frame, double travelled_m = std::numeric_limits<double>::quiet_NaN());

  /// The teach view's overlay of one add_frame() result: its landmarks (the builder's inliers
  /// and the candidates it added, MosaicFrameResult::sightings) drawn back from the canonical
  /// view into the camera image, at most FeatureOverlay::kMaxPoints, those whose ceiling point
  /// is behind the image plane left out. No lines; key_index -1.
  core::features::FeatureOverlay overlay(const core::ceiling::MosaicFrameResult& result) const;

  int64_t frames_seen() const { return static_cast<int64_t>(frames_.size()); }
  /// RAM the teacher's own per-frame records take (their vector's capacity): a frame's stamp,
  /// distance and odometry, no image (each one is in the frame store on disk once add_frame()
  /// returns). The mosaic builder's records (landmarks, sightings, poses) are not counted.
  size_t frame_records_bytes() const { return frames_.capacity() * sizeof(Kept); }
  static constexpr size_t frame_record_bytes() { return sizeof(Kept); }
  /// The folder holding the frames' images until the teacher is destroyed.
  const std::filesystem::path& frame_store_dir() const { return store_->dir(); }
  uint64_t frame_store_bytes() const { return store_->bytes_on_disk(); }
  int64_t unlocalised_frames() const { return unlocalised_; }
  /// The landmarks the mosaic keeps so far (seen often enough; MosaicBuilder::kept_landmarks).
  size_t mosaic_landmarks() const { return builder_.kept_landmarks(); }
  /// The mosaic builder's loop closures so far (docs/method/ceiling.md "Closing a loop").
  const std::vector<core::ceiling::LoopClosure>& loop_closures() const {
    return builder_.loop_closures();
  }

  /// Chooses the relay images and builds the map, reading the relay images back from the frame
  /// store (which stays until the teacher is destroyed). Throws std::runtime_error when fewer
  /// than 2 frames were taught, the mosaic kept no landmark, or a relay image is missing or
  /// damaged on disk (naming its file).
  CeilingMap finish(const std::string& parameters_json = "{}") const;

 private:
  // What finish() needs of a frame besides its image (in store_).
  struct Kept {
    int64_t t_ns = 0;
    double travelled_m = 0.0;
    std::optional<core::OdometryPose> odom;
  };
  CeilingCameraSetup setup_;
  core::CameraIntrinsics camera_;
  core::features::FeatureExtractor extractor_;
  CeilingTeachOptions options_;
  std::unique_ptr<core::ceiling::CanonicalView> view_;
  core::ceiling::MosaicBuilder builder_;
  std::unique_ptr<TeachFrameStore> store_;  // a pointer: the teacher stays movable
  std::vector<Kept> frames_;
  int64_t unlocalised_ = 0;
};

}  // namespace pepper::app
