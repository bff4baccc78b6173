#pragma once
// Ceiling-mode teach (issue 24; docs/method/ceiling.md): the part of the teach session that runs
// where the forward key-image selector runs in forward mode. Per frame: the canonical ceiling
// view (CanonicalView::warp), its landmarks (extract_landmarks, observe) and one MosaicBuilder
// step; the frame's grey image is kept (cloned: 77 kB at QVGA) because the relay images are only
// chosen at the end, when the builder knows which landmarks it kept. finish() picks the relay
// images (select_relay_images) and makes a CeilingMap: a VisualMemory in ceiling mode whose key
// images are the relay images (grey image and features, so every map tool reads it), the mosaic
// and the CeilingTour (relay poses and landmarks, breaks, drift indicators).
//
// The camera geometry (ceiling height above the optical centre, the optical centre on the base)
// comes from the simulated robot (ceiling_camera_of_mock) or, on a real Pepper, from its head
// geometry and the configured robot.ceiling_height_m (ceiling_camera_of_pepper). The tour records
// that ceiling (CeilingTour::ceiling) so that a replay under another one is refused, and checks
// it against the wheel odometry (core/ceiling/height_check.hpp; CeilingTour::height_check): a
// wrong height scales every distance of the mosaic, and finish() says so, it never changes it.
// Frames and units: core/ceiling (base frame x forward, y left, metres; mosaic frame = base frame
// of the first frame). Errors: bad options throw std::invalid_argument; finish() throws
// std::runtime_error when the tour gives no usable mosaic (fewer than 2 frames or no landmark).
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
};

/// The warning for a height check that disagrees with the configured height (nullopt when it
/// agrees or gave no estimate): the measured height, by how much every distance of the map is
/// off, and how to re-teach (--set robot.ceiling_height_m=X). For the console and `map info`.
std::optional<std::string> ceiling_height_warning(const core::ceiling::HeightCheck& check);

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

  /// One taught frame; travelled_m as the forward teacher takes it (drive_odometer.hpp).
  core::ceiling::MosaicFrameResult add_frame(
      const core::Frame& frame, double travelled_m = std::numeric_limits<double>::quiet_NaN());

  int64_t frames_seen() const { return static_cast<int64_t>(frames_.size()); }
  int64_t unlocalised_frames() const { return unlocalised_; }
  /// The mosaic builder's loop closures so far (docs/method/ceiling.md "Closing a loop").
  const std::vector<core::ceiling::LoopClosure>& loop_closures() const {
    return builder_.loop_closures();
  }

  /// Chooses the relay images and builds the map. Throws std::runtime_error when fewer than 2
  /// frames were taught or the mosaic kept no landmark.
  CeilingMap finish(const std::string& parameters_json = "{}") const;

 private:
  struct Kept {
    cv::Mat gray;
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
  std::vector<Kept> frames_;
  int64_t unlocalised_ = 0;
};

}  // namespace pepper::app
