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
// Matching is guided by the previous pose (frames are consecutive video frames; with odometry,
// by its prediction, below): a frame landmark is compared only with mosaic landmarks within
// `search_radius_m` of where that pose puts it, best Hamming distance <= `max_hamming`, each
// mosaic landmark used once. Without odometry, a frame without consensus (too few inliers) is
// reported as not localised and adds nothing; the next frame is matched with the last good pose.
//
// Re-localisation (docs/method/ceiling.md, "Re-localising after a loss"): a frame that the guided
// matching cannot pose (the ceiling was lost, e.g. hidden while the base moved farther than
// search_radius_m) is localised against the kept landmarks WITHOUT a prior, by MosaicLocaliser
// (brute-force descriptor matching, RANSAC, guided re-matching, and its acceptance test that
// refuses views of unmapped ceiling), on the first lost frame and then every
// `relocalisation.every_frames` lost frames (the cost grows with the mosaic). A fix replaces the
// last good pose as the prior of the ordinary frame step (guided matching, RANSAC, loop check,
// new landmarks); when that step poses the frame, the chain continues from there. The first
// frame that the guided matching from the last good pose poses again after a loss is checked by
// one such search too: from a pose left far behind, the guided matching can lock onto a repeated
// ceiling (the test hall's tiles: 1.2 m off on renders); where the two poses put the frame's
// landmarks more than the RANSAC threshold apart, the one whose fit has more inliers wins. The
// chained distance `travelled_m` grows across the gap by the straight line from the last good pose
// to the re-localised one (a lower bound of the path driven blind; it is also what a frame found
// again by the guided matching after a loss adds). Lost frames still add nothing. Without odometry
// nothing is compared with where the chain was before the loss (the motion while lost is
// unknown), so what was built before the gap keeps its drift, and there is no motion gate: a fix
// may be anywhere on the mosaic, so a ceiling that repeats an earlier part exactly would be
// taken for it. With odometry there is no search without a prior (below). A teach that never
// loses the ceiling is built exactly as without the feature (relocalisation.enabled = false).
//
// The odometry as the motion prior (docs/method/ceiling.md, "The odometry as the motion prior"):
// where the frames carry the robot's odometry, the guided matching starts from the last fitted
// frame's pose moved by the odometry since then, not from that pose itself, and the search
// without a prior is not used (it could only find a place the odometry contradicts). Through a
// loss (a turn at a corridor's end where the ceiling is plain tiles or hidden by a wall) the
// prior keeps up with the robot, so the first frame that sees enough again is matched where the
// robot is, not a tile away. A frame that has no fit is posed by the prediction
// (`odometry_posed`) and its unmatched landmarks become candidates there: after a turn into a
// corridor whose ceiling a wall hid, the view is new ceiling that nothing in the mosaic matches,
// and without this the teach would stay lost. Without odometry readings everything is as
// described above.
//
// Loop closure (docs/method/ceiling.md, "Closing a loop"): a teach that comes back under ceiling
// it mapped long before re-observes *old* landmarks (kept, and not seen as an inlier for
// `loop.min_gap_m` of chained travel) that the chain's drift has misplaced. So that the chain
// does not silently absorb them, old landmarks are left out of the guided matching and matched
// apart (within `loop.search_radius_m` of where the frame's pose puts each frame landmark). When
// at least `loop.min_inliers` of them agree on a pose T_old (RANSAC):
// - if the recent chain's pose T_recent misplaces them by at most `loop.min_error_m` (median),
//   they simply join the frame's fit;
// - otherwise the correction C = T_old T_recent^-1 is spread over what was created since the
//   loop's start (the old inliers' median creation distance s0): each landmark and each recorded
//   frame pose created at chained distance s moves by C^a, the SE(2) interpolation of C (a screw
//   motion) with a = (s - s0) / (s_now - s0); the frame is then matched again from its corrected
//   pose, the old landmarks included.
// Frame landmarks matched to old landmarks never become new landmarks, so a loop adds no
// duplicates. A tour that never re-observes old landmarks is built exactly as without the feature
// (loop.enabled = false).
// Errors: bad options throw std::invalid_argument naming the field. Not thread-safe (one teach).

#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <optional>
#include <unordered_map>
#include <vector>

#include "core/ceiling/mosaic.hpp"
#include "core/ceiling/mosaic_localiser.hpp"
#include "core/ceiling/observation.hpp"
#include "core/ceiling/planar_rigid.hpp"
#include "core/odometry.hpp"

namespace pepper::core::ceiling {

/// Loop closure (see the header's comment). Defaults: docs/method/ceiling.md, "Closing a loop".
struct LoopClosureOptions {
  bool enabled = true;
  /// A kept landmark is *old* once the chain has travelled this far since its last inlier
  /// sighting (a landmark stays in the ceiling view for up to ~3.4 m of forward travel), > 0.
  double min_gap_m = 5.0;
  /// Old landmarks are searched this far from where the frame's pose puts each frame landmark:
  /// the largest chain drift a closure can correct, > 0.
  double search_radius_m = 1.0;
  /// Old landmarks agreeing on one pose (RANSAC with the builder's threshold) to close, >= 3.
  /// They come into view as a band at the far edge; with 15 the band's rotation was too loose
  /// on renders (corrections of up to 2 deg, one after the other).
  int min_inliers = 30;
  /// Correct only when the recent chain misplaces the old inliers by more than this (median),
  /// >= 0. The default is the builder's RANSAC threshold: below it the old landmarks would be
  /// inliers of the ordinary fit anyway; on renders they are misplaced by 10-20 mm with no
  /// drift to correct, and correcting on that noise made things worse.
  double min_error_m = 0.03;
  /// A closure may move the frame's pose by at most max_correction_m + max_correction_per_m x
  /// the chained travel since the loop's start, and turn it by at most max_correction_rad +
  /// max_correction_per_rad x the chain's rotation since then (>= 0): a chain drifts by a small
  /// fraction of that (0.4 % of the test tour); a larger correction is a false closure on a
  /// repeated or symmetric ceiling (on a generated room's plain tiles: a room away, turned by
  /// 3 rad), refused (implausible_closures()).
  double max_correction_m = 0.1;
  double max_correction_per_m = 0.03;
  double max_correction_rad = 0.05;
  double max_correction_per_rad = 0.05;

  /// Throws std::invalid_argument naming the first invalid field (as "loop.<field>").
  void check() const;
};

/// Re-localisation after a loss (see the header's comment). Defaults: docs/method/ceiling.md,
/// "Re-localising after a loss".
struct RelocalisationOptions {
  bool enabled = true;
  /// While lost, a search without a prior on the first lost frame and then on every this many
  /// lost frames, >= 1 (and one to check the first frame posed again): each matches the frame
  /// against every kept landmark, about 3 us CPU per landmark (7.6 ms for the 2623 of the test
  /// tour's renders).
  int every_frames = 3;
  /// The localiser's options (its acceptance test refuses views of unmapped ceiling).
  LocaliserOptions localiser;

  /// Throws std::invalid_argument naming the first invalid field (as "relocalisation.<field>").
  void check() const;
};

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
  LoopClosureOptions loop;
  RelocalisationOptions relocalisation;
  /// The odometry as the motion prior (see the header's comment); false: as without readings.
  bool odometry_prior = true;

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
  double travelled_m = 0.0;  ///< chained path length from the first frame (as when added)
  bool closed_loop = false;  ///< this frame closed a loop (MosaicBuilder::loop_closures())
  /// This frame was posed from a search without a prior after a loss: a lost frame, or the first
  /// frame posed again where the search overruled the guided matching
  /// (MosaicBuilder::relocalisations()).
  bool relocalised = false;
  /// No fit, but the frame was posed by the odometry's prediction (the odometry prior): its
  /// unmatched landmarks became candidates there (localised is true, inliers 0).
  bool odometry_posed = false;
};

/// One loop closure: what was corrected.
struct LoopClosure {
  int64_t frame = -1;              ///< the frame that closed the loop
  double from_travelled_m = 0.0;   ///< the loop's start: the old inliers' median creation
  double to_travelled_m = 0.0;     ///< the closing frame's chained distance
  PlanarPose T_corrected_chained;  ///< the correction C at the closing frame (mosaic frame)
  int old_inliers = 0;             ///< old landmarks that agreed on the frame's pose
  double error_before_m = 0.0;     ///< median misplacement of those by the recent chain
  int landmarks_moved = 0;
  int frames_moved = 0;
};

/// One re-localisation after a loss.
struct Relocalisation {
  int64_t frame = -1;            ///< the re-localised frame
  int64_t last_good_frame = -1;  ///< the last frame with a pose before the loss
  int attempts = 0;              ///< searches without a prior during the loss, this one included
  int inliers = 0;               ///< of the frame's fit from the re-localised pose
  double gap_m = 0.0;            ///< straight line from the last good pose (added to travelled_m)
};

class MosaicBuilder {
 public:
  explicit MosaicBuilder(MosaicBuilderOptions options = {});

  /// Adds one frame's observation (consecutive frames of one teach). `odom`: the robot's
  /// odometry read with this frame (x forward, y left, yaw counter-clockwise, any fixed origin);
  /// nullopt when the robot reports none (then the previous pose is the prior, as without
  /// odometry_prior).
  MosaicFrameResult add_frame(const CeilingObservation& observation,
                              const std::optional<OdometryPose>& odom = std::nullopt);

  /// The kept landmarks (>= min_observations inlier sightings) as a valid Mosaic.
  Mosaic mosaic() const;
  /// Per frame so far, the sightings of the landmarks that are kept now (the relay-image
  /// selector's input, relay_images.hpp).
  std::vector<std::vector<LandmarkSighting>> kept_sightings() const;
  /// Per frame so far, the base pose (nullopt-like: localised = false where none was found).
  /// Poses recorded before a loop closure are the corrected ones.
  const std::vector<MosaicFrameResult>& frames() const { return frames_; }
  /// Landmarks not yet seen often enough to be kept (min_observations).
  size_t candidates() const;
  /// Landmarks mosaic() would keep now (no copy).
  size_t kept_landmarks() const;
  /// The loop closures so far, in order.
  const std::vector<LoopClosure>& loop_closures() const { return closures_; }
  /// Loop closures refused because their correction was beyond what a chain drifts
  /// (LoopClosureOptions::max_correction_*).
  int64_t implausible_closures() const { return implausible_closures_; }
  /// The re-localisations so far, in order.
  const std::vector<Relocalisation>& relocalisations() const { return relocalisations_; }
  /// Searches without a prior so far (each one the cost stated in RelocalisationOptions).
  int64_t relocalisation_attempts() const { return relocalisation_attempts_; }

 private:
  struct Landmark {
    int64_t id = -1;
    cv::Point2d position_m;  // fixed at creation (the paper: the mosaic is rigid) but for loops
    double orientation_rad = 0.0;
    cv::Mat descriptor;
    int observations = 0;
    int64_t last_seen_frame = -1;
    double created_travelled_m = 0.0;    // the chain's travelled distance at creation
    double created_turned_rad = 0.0;     // the chain's rotation (sum of |turns|) at creation
    double last_seen_travelled_m = 0.0;  // ... at the last inlier sighting
    bool alive() const { return observations > 0; }
  };
  struct Pair {  // a frame landmark matched to a mosaic landmark slot
    size_t obs = 0;
    size_t slot = 0;
  };
  int64_t cell_key(const cv::Point2d& p_m) const;
  void insert_in_grid(size_t index);
  std::vector<size_t> near(const cv::Point2d& p_m, double radius_m) const;
  void add_landmark(const cv::Point2d& p_m, double orientation_rad, const cv::Mat& descriptor,
                    int64_t frame);
  // The frame's unmatched, unclaimed landmarks as new candidates placed by T (when the base moved
  // or turned enough since the last creation), with their sightings.
  void add_new_landmarks(const CeilingObservation& obs, const PlanarPose& T,
                         const std::vector<int>& match_of_obs, const std::vector<uint8_t>& claimed,
                         int64_t frame, MosaicFrameResult& result);
  void prune(int64_t frame);
  void rebuild_grid();
  // Guided matching from `prior`; with `skip_old`, old landmarks (old_landmark) are left to
  // close_loop.
  std::vector<Pair> guided_matches(const CeilingObservation& obs, const PlanarPose& prior,
                                   bool skip_old) const;
  bool old_landmark(const Landmark& l) const;
  // After a loss: the pose of a search without a prior, when one is due (or `always`) and
  // accepted by the localiser (see the header's comment).
  std::optional<PlanarPose> relocalise(const CeilingObservation& obs, bool always);
  enum class LoopVerdict { kNone, kAgree, kCorrected };
  struct LoopCheck {
    LoopVerdict verdict = LoopVerdict::kNone;
    std::vector<Pair> old_pairs;  // frame landmarks matched to old landmarks
    std::vector<uint8_t> inlier;  // per old pair (kAgree)
  };
  // Matches the old landmarks around the view and compares them with the frame's pose on the
  // recent chain (see the header's comment); kCorrected: the mosaic and the recorded poses were
  // corrected, last_pose_ is the frame's corrected pose.
  LoopCheck close_loop(const CeilingObservation& obs, const PlanarPose& T_mosaic_base,
                       int64_t frame, double travelled_m);

  MosaicBuilderOptions options_;
  std::vector<Landmark> landmarks_;  // dropped candidates stay with observations = 0
  std::unordered_map<int64_t, std::vector<size_t>> grid_;  // cell -> landmark slots
  int64_t next_id_ = 0;
  std::vector<MosaicFrameResult> frames_;
  PlanarPose last_pose_;
  PlanarPose creation_pose_;  // pose of the last frame that added landmarks
  double travelled_m_ = 0.0;  // chained path length up to the last localised frame (the "now"
                              // of old_landmark while a frame is added)
  double turned_rad_ = 0.0;   // the chain's rotation (sum of |turns|) up to that frame
  int64_t implausible_closures_ = 0;
  std::vector<LoopClosure> closures_;
  // Re-localisation: frames without a pose since the last good one, the localiser over the kept
  // landmarks (built at a loss's first search; the kept landmarks do not change while lost).
  int64_t last_good_frame_ = 0;
  int lost_frames_ = 0;
  int loss_attempts_ = 0;
  std::optional<MosaicLocaliser> lost_localiser_;
  std::vector<Relocalisation> relocalisations_;
  int64_t relocalisation_attempts_ = 0;
  // The odometry prior: the reading of the last fitted frame.
  std::optional<OdometryPose> odom_at_good_;
};

}  // namespace pepper::core::ceiling
