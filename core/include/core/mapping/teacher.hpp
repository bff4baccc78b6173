#pragma once
// The teach phase: builds a visual memory from frames, online (one add_frame per frame) or
// offline (teach_offline over a recorded sequence). Both run the same code, so the same frames
// give the same map. METHOD.md "Teach"; selection rule in key_image_selector.hpp.
//
// Per frame c >= 1: features of Ic (all parts: key images need lines, corners, ORB), then with
// a FrameMatcher on Ic: nL(Ik, Ic-1, Ic) = three_view(Ik, Ic-1).n_lines() and
// nP(Ik, Ic) = two_view(Ik).n_points(); count = nL + nP drives the selector. The first and last
// frames are always key images.
//
// Inputs: Frame::gray CV_8UC1 of constant size; Frame::index is stored as the key image's source
// frame index (the teach frame number when index < 0); t_ns as its stamp; travelled_m (the
// distance driven since the first frame, drive_odometer.hpp; NaN when unknown, then on every
// frame) as its KeyImage::travelled_m; Frame::odom (the robot's odometry, may be missing on any
// frame) as its KeyImage::odom, and for the selector's heading rule: the heading change of Ic
// since Ik when both have odometry.
// Memory: keeps the features of the current key image and of the previous frame, plus the key
// images themselves. Not thread-safe. Bad frames (empty, wrong type, size change) and
// finish() with fewer than 2 frames throw std::invalid_argument; invalid options throw at
// construction.

#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/camera/intrinsics.hpp"
#include "core/features/image_features.hpp"
#include "core/features/matching.hpp"
#include "core/frame.hpp"
#include "core/mapping/key_image_selector.hpp"
#include "core/memory/visual_memory.hpp"

namespace pepper::core::mapping {

struct TeachOptions {
  KeyImageSelectorOptions selector;
  features::FeatureExtractorOptions extractor;
  features::MatcherOptions matcher;
  std::vector<std::string> validate() const;
};

struct TeachStep {
  int64_t frame_number = 0;              ///< 0-based position in this teach sequence
  int n_lines_three_view = 0;            ///< nL(Ik, Ic-1, Ic) (0 for the first frame)
  int n_points_two_view = 0;             ///< nP(Ik, Ic)
  int count = 0;                         ///< their sum, compared with the threshold
  double threshold = 0.0;                ///< the selector's threshold for this frame
  int reference_count = -1;              ///< relative rule: the key image's reference count
  std::optional<int64_t> new_key_frame;  ///< frame number of a key image taken at this step
  std::optional<KeyImageRule> new_key_rule;  ///< and the rule that took it
  /// |heading(Ic) - heading(Ik)| from the odometry, rad; nullopt without odometry on both.
  std::optional<double> heading_change_rad;
  int key_image_count = 0;               ///< key images so far
};

class Teacher {
 public:
  explicit Teacher(const CameraIntrinsics& camera, const TeachOptions& options = {});

  /// travelled_m: distance driven since the tour's first frame when this one was taken (given
  /// with every frame or with none: NaN; never decreasing), kept with the frame's key image.
  TeachStep add_frame(const Frame& frame,
                      double travelled_m = std::numeric_limits<double>::quiet_NaN());
  /// Ends the tour: the last frame becomes the final key image. The Teacher is spent afterwards.
  memory::VisualMemory finish(const std::string& parameters_json = "{}");

  int64_t frames_seen() const { return frames_; }
  int key_image_count() const { return static_cast<int>(keys_.size()); }
  /// Features of the frame given to the last add_frame (lines, corners; no pyramid), e.g. to
  /// draw them in the teach UI. Throws std::logic_error before the first frame or after finish().
  const features::ImageFeatures& last_frame_features() const;

 private:
  struct Stored {
    features::ImageFeatures features;
    int64_t source_frame_index = -1;
    int64_t t_ns = 0;
    double travelled_m = std::numeric_limits<double>::quiet_NaN();
    std::optional<OdometryPose> odom;
    int64_t frame_number = 0;
  };
  void store_key(const Stored& s);

  CameraIntrinsics camera_;
  TeachOptions options_;
  features::FeatureExtractor extractor_;
  KeyImageSelector selector_;
  std::optional<Stored> key_;
  std::optional<Stored> prev_;
  std::vector<memory::KeyImage> keys_;
  int64_t frames_ = 0;
  bool finished_ = false;
  cv::Size size_;
};

/// Offline teach over a recorded sequence: the same steps as add_frame on each frame, then
/// finish(). `steps`, when given, receives every TeachStep (for plots and tests).
memory::VisualMemory teach_offline(std::span<const Frame> frames, const CameraIntrinsics& camera,
                                   const TeachOptions& options = {},
                                   const std::string& parameters_json = "{}",
                                   std::vector<TeachStep>* steps = nullptr);

}  // namespace pepper::core::mapping
