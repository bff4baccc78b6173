#pragma once
// The odometry estimate's uncertainty, and the room-or-moved models of the three sources that
// correct it (docs/method/navigator.md "Fixes from the room or from a moved object"): one owner,
// so that the sigmas and every source's model of the same axes stay in step.
//
// Sources: the VNHV fixes (all three axes), the heading from lines (heading only), the floor
// lines' lateral position (across only) and a key-image switch decided by the image (along
// only: the robot is at IN's taught pose). Each source's measurements of a segment share an error
// that is the room's (small) or a moved object's (large): a FixErrorMixture per source. The VNHV
// fixes' model begins with begin() (a new VNHV model, a placement); a lines' model begins at its
// first measurement against an IN other than the one it was begun for, and again after begin().
//
// Why one owner: each model keeps its own copy of the estimate's variance on its axes (its
// hypotheses' variances). A source's update takes the estimate's variance on its axes from its
// model; the other models of those axes then scale theirs alike (FixErrorMixture::rescale), and
// odometry grows every model that is begun (FixErrorMixture::grow) with the sigmas. Done in one
// place, no source can forget another.
//
// Axes and units as FixErrorMixture: 0 along the robot (m), 1 across it (m), 2 heading (rad).
// The sigmas grow linearly with odometry (systematic errors' bounds add up) and are set to the
// square root of the updating model's variance. Pure; not thread-safe.

#include <array>

#include "core/navigator/fix_error_mixture.hpp"

namespace pepper::core::navigator {

enum class FixSource { kVnhv = 0, kLineYaw = 1, kFloorLines = 2, kSwitch = 3 };

class EstimateErrors {
 public:
  /// The sources' models: per-axis sigmas of each, all > 0 on the axes it measures and NaN on
  /// the others (the VNHV fixes measure all three). Throws std::invalid_argument otherwise.
  EstimateErrors(const FixErrorMixtureOptions& vnhv, const FixErrorMixtureOptions& line_yaw,
                 const FixErrorMixtureOptions& floor_lines, const FixErrorMixtureOptions& switches);

  /// A placed estimate: the sigmas become `sigma` (each > 0) and every model begins again
  /// (begin(); the switches' model at the next switch). Throws std::invalid_argument for a
  /// sigma <= 0.
  void place(const Axes3& sigma);
  /// A new segment model of the VNHV fixes, from the sigmas now; the lines' models begin again
  /// at their next measurement.
  void begin();
  /// The odometry moved: each sigma grows by d_sigma (>= 0), and every begun model alike.
  void grow(const Axes3& d_sigma);
  const Axes3& sigma() const { return sigma_; }
  /// How much each sigma grew with the odometry since its axis was last set by a placement or a
  /// measurement (update()): the error that driving alone added since the estimate last knew
  /// that axis (the dead-reckoning bound, NavigatorOptions::dead_reckoning_max_lateral_sigma_m).
  const Axes3& grown() const { return grown_; }

  /// Source `s`'s model for measurements against IN `in` (>= 0; ignored for the VNHV fixes,
  /// whose model begin() begins): a lines' model begins from the sigmas now when it was begun
  /// for another IN or not since begin(). The switches' model (`in` ignored) begins at the first
  /// switch after a placement and lasts until the next: every switch the rules decide shares
  /// one error (they fire a few centimetres early, switch after switch), so a run of them
  /// cannot pull the estimate further than that error's sigma allows.
  const FixErrorMixture& model_for(FixSource s, int in);
  /// Source `s`'s model as it is (a lines' model may not be begun: begun(s)).
  const FixErrorMixture& model(FixSource s) const { return source(s).mixture; }
  bool begun(FixSource s) const { return source(s).in != kNotBegun; }

  /// One measurement of source `s` (model_for first): the innovation (measurement minus the
  /// estimate, NaN on the axes it does not measure) and its weight in (0, 1]. Updates the
  /// model; on the axes the source measures the sigmas become the square root of its variance
  /// and every other begun model of those axes rescales alike. Returns the estimate's move (0 on
  /// the axes the source does not measure). Throws std::invalid_argument when `s`'s model is
  /// not begun, or as FixErrorMixture::update.
  Axes3 update(FixSource s, const Axes3& innovation, double weight);

 private:
  static constexpr int kNotBegun = -2;
  static constexpr int kAnyIn = -1;  // the VNHV fixes' model: begun, for every IN
  struct Source {
    FixErrorMixtureOptions options;
    FixErrorMixture mixture;
    int in = kNotBegun;
  };
  Source& source(FixSource s) { return sources_[static_cast<size_t>(s)]; }
  const Source& source(FixSource s) const { return sources_[static_cast<size_t>(s)]; }
  Axes3 variances() const;

  std::array<Source, 4> sources_;
  Axes3 sigma_{0.5, 0.5, 0.1};
  Axes3 grown_{0.0, 0.0, 0.0};
};

}  // namespace pepper::core::navigator
