#pragma once
// Verified correspondences between images: the counts n(A,B), nL(A,B,C), nP(A,B,C) of
// METHOD.md are sizes of the verified sets returned here.
//
// Two views (key image K, current image C):
//  - lines: LBD-style descriptors matched by L2 distance, mutual best + ratio test, then a
//    geometric check: planar motion keeps vertical lines vertical (a line near-vertical in one
//    view must be near-vertical in the other), the image orientation may change by at most
//    `max_angle_change_rad`, and, when the point RANSAC found E, the segments must overlap along
//    the epipolar lines (`epipolar_overlap`);
//  - points: K's FAST corners tracked into C with pyramidal KLT, then five-point essential
//    RANSAC (geometry/essential_ransac.hpp).
// Three views (X, hub H, Y) with the hub in the middle of the chain X -> H <- Y (the navigator's
// hub is the current image: (IP, Ia, IN) and (Ia, IN, INN) both chain through Ia; teach's
// (Ik, Ic-1, Ic) chains through Ic):
//  - lines: two-view line matches X-H and Y-H chained through H's line index, then planar-motion
//    trifocal RANSAC (geometry/planar_trifocal.hpp) with H as reference view 0;
//  - points: verified KLT tracks X -> H and Y -> H whose end points in H are mutual nearest
//    neighbours within `three_view_point_radius_px`.
// Wide baseline (initial localisation): ORB matching (Hamming, mutual + ratio) + essential RANSAC
// for points, the two-view line matching for lines.
//
// Per-frame reuse: FrameMatcher holds one current image and caches its two-view results per key
// image id, so every pairwise computation (line matching, KLT, essential RANSAC, wide-baseline
// matching) runs once per frame whatever the number of three-view queries.
// Indices: LineMatch/PointMatch indices refer to each view's ImageFeatures::lines, corners_px
// (KLT) or keypoints (wide baseline). Normalised coordinates use each view's own intrinsics.
// Thread-safety: free functions are reentrant; a FrameMatcher is not thread-safe (one per frame;
// FrameMatcher::compute_two_views runs its own tasks concurrently and joins them before returning).

#include <cstdint>
#include <string>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

#include <opencv2/core/matx.hpp>
#include <opencv2/core/types.hpp>

#include "core/features/image_features.hpp"
#include "core/geometry/essential_ransac.hpp"
#include "core/geometry/planar_trifocal.hpp"

namespace pepper::core::features {

struct LineMatchOptions {
  double ratio = 0.85;                    ///< best / second-best distance must be below (0, 1]
  bool mutual = true;                     ///< keep only mutual best matches
  double max_descriptor_distance = 0.9;   ///< L2 on unit-norm descriptors, (0, 2]
  double max_angle_change_rad = 0.7854;   ///< |theta_a - theta_b| (mod pi) at most 45 deg
  double vertical_tolerance_rad = 0.0873; ///< "near vertical": |theta| below 5 deg
  double vertical_mismatch_rad = 0.2618;  ///< a near-vertical line must stay within 15 deg
  bool epipolar_overlap = true;           ///< check segment overlap along epipolars when E known
  std::vector<std::string> validate() const;
};

struct MatcherOptions {
  LineMatchOptions lines;
  KltOptions klt;                          ///< must match the key images' pyramid options
  geometry::EssentialRansacOptions essential;
  geometry::PlanarTrifocalOptions trifocal;
  double three_view_point_radius_px = 2.0; ///< X->H and Y->H tracks meet within this, px
  /// Start KLT at the median shift of the line matches when it exceeds the KLT window (turns
  /// move the image further than the pyramid reaches; matching.cpp shift_from_lines).
  bool klt_shift_from_lines = true;
  double orb_ratio = 0.8;                  ///< wide baseline ratio test
  int orb_max_hamming = 64;                ///< wide baseline max Hamming distance (0..256)
  /// FrameMatcher::two_view_for_control: when KLT verifies fewer points than this and both
  /// images carry ORB keypoints, the wide-baseline (ORB) points replace them if there are more
  /// and at least this many (ORB compares grey levels within a patch, so a light change does
  /// not defeat it the way it defeats KLT's patch error; but its matches are global, and a few
  /// wrong ones pass a five-point RANSAC: measured, room_corridor_room's first left turn, where
  /// 8-11 ORB points steered right while the lines and the tour turned left). 0: off. 12 since
  /// session 9 (closed-loop figures: README "Closed-loop evaluation", docs/perception.md
  /// "Light changes"); it costs ORB keypoints on every frame.
  int orb_fallback_below_points = 12;
  /// Which kinds of feature are matched at all (METHOD.md's "lines only" / "points only"
  /// systems). A kind switched off is never matched, in two, three or wide-baseline views, so
  /// nothing downstream (key-image counts, switching, the control laws, the segment
  /// reconstruction, the scale ratio) can use it; nor do its results steer the other kind (no
  /// KLT start from line shifts without lines, no epipolar check of lines without points).
  /// At least one must be on.
  bool match_lines = true;
  bool match_points = true;
  std::vector<std::string> validate() const;
};

struct LineMatch {
  int idx_a = -1;          ///< index into view a's lines
  int idx_b = -1;          ///< index into view b's lines
  float distance = 0.0f;   ///< descriptor distance
};

struct PointMatch {
  int idx_a = -1;          ///< index into a's corners_px (KLT) or keypoints (wide baseline)
  int idx_b = -1;          ///< index into b's keypoints (wide baseline); -1 for KLT tracks
  cv::Point2f a_px;
  cv::Point2f b_px;
  cv::Point2d a_norm;
  cv::Point2d b_norm;
};

/// Verified correspondences between view a (key image) and view b (current image).
struct TwoViewMatches {
  std::vector<LineMatch> lines;    ///< verified line matches
  std::vector<PointMatch> points;  ///< verified point matches (passed essential RANSAC)
  int line_candidates = 0;         ///< after mutual + ratio, before geometric checks
  int point_candidates = 0;        ///< KLT tracks (or ORB matches) before RANSAC
  bool essential_found = false;
  cv::Matx33d E_b_a = cv::Matx33d::zeros();
  /// The points are ORB matches (idx_a indexes a's keypoints, not its corners): see
  /// MatcherOptions::orb_fallback_below_points.
  bool points_from_orb = false;
  /// a's corners KLT did not track into b (the track failed, or `skip` in match_two_view left
  /// it out), ascending; empty when the points were not tracked.
  std::vector<int> klt_untracked;

  int n_lines() const { return static_cast<int>(lines.size()); }
  int n_points() const { return static_cast<int>(points.size()); }
  int total() const { return n_lines() + n_points(); }  ///< n(A, B) of METHOD.md
};

struct LineTripletMatch {
  int idx_x = -1;    ///< index into X's lines
  int idx_hub = -1;  ///< index into the hub's lines
  int idx_y = -1;    ///< index into Y's lines
};

struct PointTripletMatch {
  int idx_x = -1;      ///< index into X's corners_px
  int idx_y = -1;      ///< index into Y's corners_px
  cv::Point2f hub_px;  ///< mean of the two tracked positions in the hub
  cv::Point2d hub_norm;
};

/// Verified three-view correspondences for the chain X -> hub <- Y.
struct ThreeViewMatches {
  std::vector<LineTripletMatch> lines;     ///< nL(X, hub, Y)
  std::vector<PointTripletMatch> points;   ///< nP(X, hub, Y)
  int line_candidates = 0;                 ///< chained triplets before RANSAC
  geometry::PlanarTrifocalResult trifocal; ///< RANSAC diagnostics (motion of X, Y w.r.t. hub)

  int n_lines() const { return static_cast<int>(lines.size()); }
  int n_points() const { return static_cast<int>(points.size()); }
  int total() const { return n_lines() + n_points(); }
};

/// Wall-clock time of each matching stage, summed over the calls that fill it (telemetry only,
/// never used by a decision; issue 22's split of the step). Thread-compatible plain data.
struct MatchTimings {
  double lines_ms = 0.0;          ///< line descriptor matching, orientation and epipolar checks
  double klt_ms = 0.0;            ///< KLT tracking of the key image's corners
  double essential_ms = 0.0;      ///< essential RANSAC (KLT tracks and ORB matches)
  double three_view_ms = 0.0;     ///< three-view verification (trifocal RANSAC, point chaining)
  double wide_baseline_ms = 0.0;  ///< ORB descriptor matching (its RANSAC: essential_ms)
};

/// Which of a key image's untracked corners (TwoViewMatches::klt_untracked of one frame) the
/// next frame leaves out of tracking from scratch: all but those with (corner + frame) a multiple
/// of `retry_frames` (KltOptions::retry_untracked_frames), so that each corner is retried on one
/// frame in retry_frames and each frame retries about 1 / retry_frames of them. `frame`: the
/// number of the frame the list is for (any origin); retry_frames <= 1 skips none.
std::vector<int> klt_corners_to_skip(std::span<const int> untracked, int64_t frame,
                                     int retry_frames);

/// Descriptor matching (mutual + ratio) followed by the orientation checks; no epipolar check.
std::vector<LineMatch> match_lines(const ImageFeatures& a, const ImageFeatures& b,
                                   const LineMatchOptions& options = {});

/// Two-view verified lines and points, KLT from a (key, needs corners_px) into b (current).
/// b.klt_pyramid is used when built with the same KltOptions (else built on the fly).
/// `prior`: verified point matches of a with an earlier frame close to b (typically the previous
/// one; idx_a and b_px are used): those corners start from b_px with klt.prior_max_level levels
/// instead of from their position in a with klt.max_level (faster), and fall back to the latter
/// when that track fails. The result is a function of (a, b, options, prior).
/// `timings`, when given, gets the stages' wall-clock time added. `skip`: corners of a not to
/// track from scratch (a corner with a prior is still tracked from it): they are left
/// untracked (TwoViewMatches::klt_untracked).
TwoViewMatches match_two_view(const ImageFeatures& a, const ImageFeatures& b,
                              const MatcherOptions& options = {},
                              std::span<const PointMatch> prior = {},
                              MatchTimings* timings = nullptr,
                              std::span<const int> skip = {});

/// Wide-baseline verified lines and points (ORB keypoints of both views).
TwoViewMatches match_wide_baseline(const ImageFeatures& a, const ImageFeatures& b,
                                   const MatcherOptions& options = {},
                                   MatchTimings* timings = nullptr);

/// Three-view verification from two two-view results sharing the hub as their view b.
ThreeViewMatches verify_three_view(const ImageFeatures& x, const TwoViewMatches& x_to_hub,
                                   const ImageFeatures& hub, const ImageFeatures& y,
                                   const TwoViewMatches& y_to_hub,
                                   const MatcherOptions& options = {});

/// Where KLT starts tracking one key image's corners on a frame (match_two_view's `prior` and
/// `skip`, from the previous frame's results: FrameMatcher::set_klt_prior).
struct KltStart {
  std::vector<PointMatch> prior;  ///< the previous frame's verified matches of the key image
  std::vector<int> skip;          ///< its corners not tracked from scratch (klt_corners_to_skip)
};

/// The work of one current frame against several key images, each pairwise result computed once.
/// Key images are identified by a caller-chosen id (e.g. the key image index in the map; any
/// unique int64, e.g. a negative value for the previous frame in teach). Using one id for two
/// different images is a caller error (the cache would return the first image's result).
/// The referenced ImageFeatures must outlive the calls that pass them (nothing is retained but
/// the current frame's features, shared cv::Mat buffers).
class FrameMatcher {
 public:
  /// Builds the current frame's KLT pyramid if missing (no derivatives: only tracked into).
  /// Throws std::invalid_argument when the options are invalid or `current` has no image.
  explicit FrameMatcher(ImageFeatures current, const MatcherOptions& options = {});
  /// The same, with the current frame's ORB keypoints extracted by `wide_baseline_extractor`
  /// the first time a match needs them (the ORB fallback of two_view_for_control(),
  /// wide_baseline()) when `current` has none: most frames never need them (ORB on every frame
  /// was a third of the extraction at QVGA, bench_extract_real). The extractor must outlive
  /// this matcher; its time counts in timings().wide_baseline_ms.
  FrameMatcher(ImageFeatures current, const MatcherOptions& options,
               const FeatureExtractor* wide_baseline_extractor);

  const ImageFeatures& current() const { return current_; }
  const MatcherOptions& options() const { return options_; }
  /// Wall-clock time of the work done so far for this frame, per stage (telemetry).
  const MatchTimings& timings() const { return timings_; }

  /// KLT priors for a key image (see match_two_view): set before the first two_view() of that
  /// key id (later calls have no effect on an already computed result).
  void set_klt_prior(int64_t key_id, std::vector<PointMatch> prior, std::vector<int> skip = {});

  /// n(key, current): verified lines + KLT points (cached per key id).
  const TwoViewMatches& two_view(int64_t key_id, const ImageFeatures& key);

  /// A key image for compute_two_views(): its id and features (which must outlive the call).
  struct KeyRef {
    int64_t id = -1;
    const ImageFeatures* features = nullptr;
    /// Computed only where the tasks run concurrently (concurrent()), and then held back until
    /// two_view() asks for it: computed_two_view() does not see it before, so what the caller
    /// does with the computed results (e.g. the navigator's KLT priors for the next frame)
    /// stays what it was without the speculation.
    bool speculative = false;
  };
  /// two_view() of several key images at once: those not computed yet are computed as
  /// concurrent tasks, one per key image (the first on the calling thread, each other one on a
  /// thread started and joined by this call; with cv::getNumThreads() <= 1, as after
  /// cv::setNumThreads(1), all on the calling thread, one after the other); the call returns
  /// when all are done. The results are the same as
  /// two_view() called for each in turn: each is a function of its key image, the current
  /// frame, the options and that key's prior only, and the tasks share nothing else (their
  /// MatchTimings are added to timings() afterwards: the stages' sums then exceed the call's
  /// wall-clock time). Why: the navigator needs IN and INN on every frame, and their KLT and
  /// essential RANSAC are most of a step (docs/method/navigator.md "Speed"); two tasks use
  /// the robot's second core (ARCHITECTURE.md: a task-parallel split behind a plain call).
  /// An id given twice is computed once. Throws std::invalid_argument for a null `features`
  /// and what two_view() throws (the first task's error; the other results are then kept; a
  /// speculative task's error only when two_view() asks for that key).
  void compute_two_views(std::span<const KeyRef> keys);
  /// Whether compute_two_views() runs its tasks concurrently (cv::getNumThreads() > 1).
  static bool concurrent();

  /// two_view() for the control law and the scale ratio: when KLT verified fewer points than
  /// orb_fallback_below_points and both images carry ORB keypoints, the same lines with the
  /// wide-baseline points if those are more and at least orb_fallback_below_points
  /// (points_from_orb). The switching counts and the
  /// three-view sets keep using two_view().
  const TwoViewMatches& two_view_for_control(int64_t key_id, const ImageFeatures& key);

  /// The cached two-view result of key_id, nullptr when two_view() was not called for it (nor
  /// compute_two_views() without `speculative`).
  const TwoViewMatches* computed_two_view(int64_t key_id) const;

  /// nL, nP for (x, current, y): the three-view sets of the chain x -> current <- y (cached per
  /// ordered pair of ids: the result's idx_x/idx_y follow the argument order).
  const ThreeViewMatches& three_view(int64_t x_id, const ImageFeatures& x, int64_t y_id,
                                     const ImageFeatures& y);

  /// Wide-baseline (ORB) verified lines + points of key vs current (cached per key id); the
  /// current image must have been extracted with kPartWideBaseline.
  const TwoViewMatches& wide_baseline(int64_t key_id, const ImageFeatures& key);

 private:
  struct PairHash {
    size_t operator()(const std::pair<int64_t, int64_t>& p) const noexcept;
  };
  /// Extracts the current frame's ORB keypoints if they are due (see the constructor); whether
  /// it has any.
  bool current_keypoints();

  ImageFeatures current_;
  MatcherOptions options_;
  const FeatureExtractor* wide_baseline_extractor_ = nullptr;  ///< null once used
  MatchTimings timings_;
  std::unordered_map<int64_t, TwoViewMatches> two_view_;
  std::unordered_map<int64_t, TwoViewMatches> speculative_;  ///< computed, not asked for yet
  /// Moves a held speculative result for `key_id` to the asked-for ones; null when none.
  const TwoViewMatches* adopt_speculative(int64_t key_id);
  std::unordered_map<int64_t, KltStart> klt_starts_;
  /// The start held for key_id, or an empty one.
  const KltStart& klt_start(int64_t key_id) const;
  std::unordered_map<int64_t, TwoViewMatches> wide_;
  std::unordered_map<int64_t, TwoViewMatches> control_;
  std::unordered_map<std::pair<int64_t, int64_t>, ThreeViewMatches, PairHash> three_view_;
};

}  // namespace pepper::core::features
