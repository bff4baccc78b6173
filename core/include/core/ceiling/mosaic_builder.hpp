#pragma once
// Building the ceiling mosaic during teach (issue 24; Blanc et al. 2004, section 2.2): frames of
// the canonical ceiling view in (as base-frame observations, observation.hpp), a Mosaic out.
//
// As in the paper, the first frame fixes the mosaic frame (its landmarks get their poses directly)
// and every later landmark's pose is chained from landmarks already in the mosaic: the frame's
// pose T_mosaic_base is the robust rigid transform (RANSAC over two-point hypotheses, then least
// squares, planar_rigid.hpp) between the frame's landmarks and the mosaic landmarks they match,
// and a new landmark is placed at T_mosaic_base p_base. Unlike the paper's few large 2D models
// with particle-filter trackers, the landmarks are many ORB corners; to keep only those that stay
// consistent, a new landmark is a *candidate* until it has been matched as a RANSAC inlier in
// `min_observations` frames, and a candidate not re-seen for `candidate_timeout_frames` frames is
// dropped. The mosaic returned holds the kept (confirmed) landmarks only. As in the paper, a
// landmark's pose is fixed when it is created: averaging its later sightings (placed by poses
// that were themselves fitted to the mosaic) was measured to feed the drift back into the mosaic
// (docs/method/ceiling.md). New landmarks are created only once the base has moved
// landmark_step_m or turned landmark_step_rad since the last creation, so that most landmarks
// are chained over a long baseline rather than from the previous frame.
//
// Mosaic frame: the base frame of the first frame (x forward, y left, metres; theta
// counter-clockwise seen from above). Poses chained this way drift with the distance driven; the
// drift measured on sim renders is in docs/method/ceiling.md.
//
// Matching is guided by the previous pose (frames are consecutive video frames): a frame landmark
// is compared only with mosaic landmarks within `search_radius_m` of where the previous pose puts
// it, best Hamming distance <= `max_hamming`, each mosaic landmark used once. A frame without
// consensus (too few inliers) is reported as not localised and adds nothing; the next frame is
// matched with the last good pose. There is no global re-localisation during teach: a teach that
// loses the ceiling while the base moves farther than search_radius_m stays lost (every later
// frame reports localised = false); the teach session warns (a ceiling_lost event, the UI status,
// map info's warning) and does not recover.
// Errors: bad options throw std::invalid_argument naming the field. Not thread-safe (one teach).

#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <unordered_map>
#include <vector>

#include "core/ceiling/mosaic.hpp"
#include "core/ceiling/observation.hpp"
#include "core/ceiling/planar_rigid.hpp"

namespace pepper::core::ceiling {

struct MosaicBuilderOptions {
  double px_per_m = 80.0;            ///< the canonical view's scale, recorded in the mosaic, > 0
  double search_radius_m = 0.4;      ///< motion between two frames plus prediction error, > 0
  int max_hamming = 64;              ///< of a descriptor match, bits in [1, 256]
  int min_observations = 3;          ///< inlier sightings before a landmark is kept, >= 1
  int candidate_timeout_frames = 6;  ///< a candidate unseen this long is dropped, >= 1
  double min_separation_m = 0.015;   ///< no new landmark this close to an existing one, >= 0
  double landmark_step_m = 0.1;      ///< new landmarks only once the base moved this far, >= 0
  double landmark_step_rad = 0.05;   ///< ... or turned this much since the last ones, >= 0
  RigidRansacOptions ransac{0.03, 10, 300, 1};

  /// Throws std::invalid_argument naming the first invalid field.
  void check() const;
};

/// A mosaic landmark seen in one frame: where, in that frame's canonical view.
struct LandmarkSighting {
  int64_t id = -1;
  cv::Point2d p_canon_px;
  double orientation_canon_rad = 0.0;  ///< image axes (landmarks.hpp)
};

/// What one frame did to the mosaic.
struct MosaicFrameResult {
  bool localised = false;    ///< the pose below is valid (always true for the first frame)
  PlanarPose T_mosaic_base;  ///< the frame's base pose in the mosaic frame
  int matches = 0;           ///< guided descriptor matches tried by RANSAC
  int inliers = 0;
  double rms_m = 0.0;                       ///< inliers' residual
  int added = 0;                            ///< new candidates
  std::vector<LandmarkSighting> sightings;  ///< inlier (and new) landmarks of this frame
};

class MosaicBuilder {
 public:
  explicit MosaicBuilder(MosaicBuilderOptions options = {});

  /// Adds one frame's observation (consecutive frames of one teach).
  MosaicFrameResult add_frame(const CeilingObservation& observation);

  /// The kept landmarks (>= min_observations inlier sightings) as a valid Mosaic.
  Mosaic mosaic() const;
  /// Per frame so far, the sightings of the landmarks that are kept now (the relay-image
  /// selector's input, relay_images.hpp).
  std::vector<std::vector<LandmarkSighting>> kept_sightings() const;
  /// Per frame so far, the base pose (nullopt-like: localised = false where none was found).
  const std::vector<MosaicFrameResult>& frames() const { return frames_; }
  size_t candidates() const;

 private:
  struct Landmark {
    int64_t id = -1;
    cv::Point2d position_m;  // fixed at creation (the paper: the mosaic is rigid)
    double orientation_rad = 0.0;
    cv::Mat descriptor;
    int observations = 0;
    int64_t last_seen_frame = -1;
    bool alive() const { return observations > 0; }
  };
  int64_t cell_key(const cv::Point2d& p_m) const;
  void insert_in_grid(size_t index);
  std::vector<size_t> near(const cv::Point2d& p_m, double radius_m) const;
  void add_landmark(const cv::Point2d& p_m, double orientation_rad, const cv::Mat& descriptor,
                    int64_t frame);
  void prune(int64_t frame);

  MosaicBuilderOptions options_;
  std::vector<Landmark> landmarks_;  // dropped candidates stay with observations = 0
  std::unordered_map<int64_t, std::vector<size_t>> grid_;  // cell -> landmark slots
  int64_t next_id_ = 0;
  std::vector<MosaicFrameResult> frames_;
  PlanarPose last_pose_;
  PlanarPose creation_pose_;  // pose of the last frame that added landmarks
};

}  // namespace pepper::core::ceiling
