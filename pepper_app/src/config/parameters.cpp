#include "config/parameters.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "config/app_config.hpp"

namespace pepper::app {
namespace {

using nlohmann::json;
namespace cc = core::control;
namespace cn = core::navigator;

// ---- Ranges. ---------------------------------------------------------------------------------

std::string_view trim(std::string_view s) {
  while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
  while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
  return s;
}

[[noreturn]] void bad_range(const std::string& whole, const std::string& why) {
  throw std::invalid_argument("range \"" + whole + "\": " + why);
}

bool is_identifier(std::string_view s) {
  if (s.empty() || !(std::islower(static_cast<unsigned char>(s.front())) || s.front() == '_'))
    return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return std::islower(static_cast<unsigned char>(c)) ||
           std::isdigit(static_cast<unsigned char>(c)) || c == '_';
  });
}

// ---- Values: one template per direction, chosen by the field's C++ type. --------------------

template <class E>
using EnumNames = std::vector<std::pair<std::string, E>>;

const EnumNames<cn::ControllerKind>& names_of(cn::ControllerKind) {
  static const EnumNames<cn::ControllerKind> names = {{"ibvs", cn::ControllerKind::kIbvs},
                                                      {"vnhv", cn::ControllerKind::kVnhv}};
  return names;
}
const EnumNames<cc::FeatureMode>& names_of(cc::FeatureMode) {
  static const EnumNames<cc::FeatureMode> names = {{"both", cc::FeatureMode::kLinesAndPoints},
                                                   {"lines", cc::FeatureMode::kLinesOnly},
                                                   {"points", cc::FeatureMode::kPointsOnly}};
  return names;
}

template <class T>
constexpr ParamType type_of() {
  if constexpr (std::is_same_v<T, bool>)
    return ParamType::kBool;
  else if constexpr (std::is_enum_v<T>)
    return ParamType::kEnum;
  else if constexpr (std::is_same_v<T, int>)
    return ParamType::kInt;
  else if constexpr (std::is_same_v<T, std::int64_t>)
    return ParamType::kInt64;
  else if constexpr (std::is_same_v<T, std::uint64_t>)
    return ParamType::kUint64;
  else if constexpr (std::is_same_v<T, float>)
    return ParamType::kFloat;
  else if constexpr (std::is_same_v<T, double>)
    return ParamType::kDouble;
  else {
    static_assert(std::is_same_v<T, std::string>, "unsupported parameter type");
    return ParamType::kString;
  }
}

template <class T>
json to_json_value(const T& value) {
  if constexpr (std::is_enum_v<T>) {
    for (const auto& [name, e] : names_of(value)) {
      if (e == value) return name;
    }
    return nullptr;  // not reached: every enumerator has a name
  } else {
    return value;
  }
}

template <class T>
std::string from_json_value(const json& v, T& field) {
  if constexpr (std::is_same_v<T, bool>) {
    if (!v.is_boolean()) return "must be true or false, got " + v.dump();
  } else if constexpr (std::is_enum_v<T>) {
    std::string allowed;
    for (const auto& [name, e] : names_of(field)) {
      if (v.is_string() && v.get<std::string>() == name) {
        field = e;
        return "";
      }
      allowed += (allowed.empty() ? "" : ", ") + name;
    }
    return "must be one of " + allowed + ", got " + v.dump();
  } else if constexpr (std::is_integral_v<T>) {
    if (!v.is_number_integer()) return "must be a whole number, got " + v.dump();
    using L = std::numeric_limits<T>;
    const bool fits = v.is_number_unsigned()
                          ? v.get<std::uint64_t>() <= static_cast<std::uint64_t>(L::max())
                          : v.get<std::int64_t>() >= static_cast<std::int64_t>(L::min()) &&
                                (std::is_unsigned_v<T> ||
                                 v.get<std::int64_t>() <= static_cast<std::int64_t>(L::max()));
    if (!fits) {
      return "must be a whole number in [" + std::to_string(L::min()) + ", " +
             std::to_string(L::max()) + "], got " + v.dump();
    }
  } else if constexpr (std::is_floating_point_v<T>) {
    if (!v.is_number()) return "must be a number, got " + v.dump();
  } else {
    if (!v.is_string()) return "must be a string, got " + v.dump();
  }
  if constexpr (!std::is_enum_v<T>) field = v.get<T>();
  return "";
}

/// Where a section's struct lives in AppConfig: `field` is a generic lambda returning a
/// reference to it (const or not).
template <class F>
struct Section {
  std::string prefix;  ///< the section's dotted key
  F field;
};

template <class F>
Section<F> section(std::string prefix, F field) {
  return {std::move(prefix), field};
}

/// One row: the member `member` of the section's struct, at `key` (the section's key + "." + a
/// name). The C++ type of the member gives the parameter's type.
template <class F, class S, class T>
Parameter row(std::string key, const Section<F>& section, T S::*member, std::string unit,
              std::string range, std::string doc) {
  using Struct = std::remove_cvref_t<decltype(section.field(std::declval<AppConfig&>()))>;
  static_assert(std::is_same_v<S, Struct>, "the member belongs to another struct");
  Parameter p;
  p.key = std::move(key);
  const std::size_t name_at = section.prefix.size() + 1;
  if (p.key.compare(0, name_at, section.prefix + ".") != 0 ||
      p.key.find('.', name_at) != std::string::npos) {
    throw std::logic_error(p.key + ": not a key of section " + section.prefix);
  }
  p.type = type_of<T>();
  if constexpr (std::is_enum_v<T>) {
    for (const auto& [name, e] : names_of(T{})) p.enum_names.push_back(name);
  }
  p.unit = std::move(unit);
  try {
    p.range = Range(std::move(range));
  } catch (const std::invalid_argument& e) {
    throw std::logic_error(p.key + ": " + e.what());
  }
  p.doc = std::move(doc);
  const F field = section.field;
  p.get = [field, member](const AppConfig& c) { return to_json_value(field(c).*member); };
  p.set = [field, member](AppConfig& c, const json& v) {
    return from_json_value(v, field(c).*member);
  };
  return p;
}

using Extractor = core::features::FeatureExtractorOptions;
using Klt = core::features::KltOptions;
using Matcher = core::features::MatcherOptions;
using Lines = core::features::LineMatchOptions;
using Essential = core::geometry::EssentialRansacOptions;
using Trifocal = core::geometry::PlanarTrifocalOptions;
using KeyImages = core::mapping::KeyImageSelectorOptions;
using Navigator = core::navigator::NavigatorOptions;
using Ibvs = core::control::IbvsOptions;
using Vnhv = core::control::VnhvOptions;
using Pose = core::control::SegmentPoseOptions;
using Filter = core::control::DeviationFilterOptions;
using Speed = core::control::VelocityScheduleOptions;
using Localization = core::localization::InitialLocalizerOptions;
using LocalizationRule = core::localization::InitialLocalizationOptions;
using Switching = core::localization::SwitcherOptions;

// ---- The table. -------------------------------------------------------------------------------
// One row per parameter: key; section, member; unit; range; doc. Ranges: the core's validate()
// functions (core/src/**) and RobotConfig / ReplayConfig / UiConfig; docs: the options headers
// and docs/method/*.md. Rules a range cannot say (odd KLT windows, ibvs.g1 + ibvs.g2 > 0, the
// camera size as a pair) stay in the validate() functions.
std::vector<Parameter> build_table() {
  // clang-format off
  const auto extractor =
      section("features.extractor", [](auto& c) -> auto& { return c.extractor; });
  const auto klt = section("features.klt", [](auto& c) -> auto& { return c.extractor.klt; });
  const auto matcher = section("features.matcher", [](auto& c) -> auto& { return c.matcher; });
  const auto lines =
      section("features.matcher.lines", [](auto& c) -> auto& { return c.matcher.lines; });
  const auto essential =
      section("features.matcher.essential", [](auto& c) -> auto& { return c.matcher.essential; });
  const auto trifocal =
      section("features.matcher.trifocal", [](auto& c) -> auto& { return c.matcher.trifocal; });
  const auto key_images = section("key_images", [](auto& c) -> auto& { return c.key_images; });
  const auto navigator = section("navigator", [](auto& c) -> auto& { return c.navigator; });
  const auto ibvs = section("navigator.ibvs", [](auto& c) -> auto& { return c.navigator.ibvs; });
  const auto vnhv = section("navigator.vnhv", [](auto& c) -> auto& { return c.navigator.vnhv; });
  const auto pose =
      section("navigator.vnhv.pose", [](auto& c) -> auto& { return c.navigator.vnhv.pose; });
  const auto filter =
      section("navigator.vnhv.filter", [](auto& c) -> auto& { return c.navigator.vnhv.filter; });
  const auto speed =
      section("navigator.speed", [](auto& c) -> auto& { return c.navigator.schedule; });
  const auto localization =
      section("navigator.localization", [](auto& c) -> auto& { return c.navigator.initial; });
  const auto localization_rule =
      section("navigator.localization", [](auto& c) -> auto& { return c.navigator.initial.rule; });
  const auto switching =
      section("navigator.switching", [](auto& c) -> auto& { return c.navigator.switching; });
  const auto robot = section("robot", [](auto& c) -> auto& { return c.robot; });
  const auto replay = section("replay", [](auto& c) -> auto& { return c.replay; });
  const auto ceiling = section("ceiling", [](auto& c) -> auto& { return c.ceiling; });
  const auto ui = section("ui", [](auto& c) -> auto& { return c.ui; });

  return {
    // features.extractor: FeatureExtractorOptions (core/features/image_features.hpp)
    row("features.extractor.max_lines",
        extractor, &Extractor::max_lines, "", "[0, 100000]",
        "keep the longest N line segments (bounds the descriptor cost)"),
    row("features.extractor.min_line_length_frac",
        extractor, &Extractor::min_line_length_frac, "", "[0, 1]",
        "shortest segment kept, as a fraction of the image width (0.04: 25.6 px at VGA)"),
    row("features.extractor.ed_gradient_threshold",
        extractor, &Extractor::ed_gradient_threshold, "grey levels", "[1, 255]",
        "EdgeDrawing GradientThresholdValue"),
    row("features.extractor.ed_anchor_threshold",
        extractor, &Extractor::ed_anchor_threshold, "", "[0, 255]",
        "EdgeDrawing AnchorThresholdValue"),
    row("features.extractor.ed_sigma",
        extractor, &Extractor::ed_sigma, "px", "[0.1, 10]",
        "EdgeDrawing Gaussian smoothing sigma"),
    row("features.extractor.ed_line_fit_error_px",
        extractor, &Extractor::ed_line_fit_error_px, "px", "[0.1, 10]",
        "EdgeDrawing LineFitErrorThreshold"),
    row("features.extractor.lbd_band_width_px",
        extractor, &Extractor::lbd_band_width_px, "px", "[1, 20]",
        "width of each of the 9 bands of the line descriptor (at any image size)"),
    row("features.extractor.lbd_samples_along",
        extractor, &Extractor::lbd_samples_along, "", "[2, 1000]",
        "samples along a segment for its descriptor, at most"),
    row("features.extractor.fast_threshold",
        extractor, &Extractor::fast_threshold, "grey levels", "[1, 255]",
        "FAST corner threshold"),
    row("features.extractor.max_corners",
        extractor, &Extractor::max_corners, "", "[0, 100000]",
        "FAST corners kept for KLT"),
    row("features.extractor.corner_grid_cols",
        extractor, &Extractor::corner_grid_cols, "", "[1, 100]",
        "corners are spread over a grid: at most max_corners / (cols x rows) per cell"),
    row("features.extractor.corner_grid_rows",
        extractor, &Extractor::corner_grid_rows, "", "[1, 100]",
        "rows of that grid"),
    row("features.extractor.orb_max_features",
        extractor, &Extractor::orb_max_features, "", "[0, 100000]",
        "ORB keypoints for wide-baseline matching (initial localisation)"),

    // features.klt: KltOptions, shared by the key images' pyramids and the tracker
    row("features.klt.window_px",
        klt, &Klt::window_px, "px", "[5, 101]",
        "square KLT window side at each pyramid level (odd)"),
    row("features.klt.max_level",
        klt, &Klt::max_level, "", "[0, 6]",
        "pyramid levels above the base"),
    row("features.klt.max_iterations",
        klt, &Klt::max_iterations, "", "[1, 1000]",
        "KLT iterations per level"),
    row("features.klt.epsilon",
        klt, &Klt::epsilon, "px", "[1e-6, 10]",
        "KLT convergence threshold"),
    row("features.klt.min_eig_threshold",
        klt, &Klt::min_eig_threshold, "", "[0, 1]",
        "OpenCV minEigThreshold"),
    row("features.klt.max_error",
        klt, &Klt::max_error, "grey levels", "[0, 255]",
        "tracks whose mean patch error exceeds this are rejected"),
    row("features.klt.prior_max_level",
        klt, &Klt::prior_max_level, "", "[-1, 6]",
        "levels when tracking from a prior position (capped at max_level; -1: priors ignored)"),
    row("features.klt.prior_probes",
        klt, &Klt::prior_probes, "", "[0, 1000]",
        "priors tracked first with max_level to measure the image shift (0: no shift)"),
    row("features.klt.prior_window_px",
        klt, &Klt::prior_window_px, "px", "[5, 101]",
        "window when tracking from a prior (odd, capped at window_px)"),
    row("features.klt.retry_untracked_frames",
        klt, &Klt::retry_untracked_frames, "frames", "[1, 1000]",
        "a key image's corner not tracked into the previous frame is tracked from scratch on one frame in this many (1: every frame)"),
    row("features.klt.normalise_window_frac",
        klt, &Klt::normalise_window_frac, "", "[0, 0.3]",
        "side of the local normalisation window KLT and line detection work on, as a fraction of the image width (0: raw grey)"),

    // features.matcher: MatcherOptions (core/features/matching.hpp)
    row("features.matcher.three_view_point_radius_px",
        matcher, &Matcher::three_view_point_radius_px, "px", "(0, 50]",
        "three-view point check: the X->H and Y->H tracks meet within this"),
    row("features.matcher.klt_shift_from_lines",
        matcher, &Matcher::klt_shift_from_lines, "", "",
        "start KLT at the line matches' median shift when it exceeds the KLT window (turns)"),
    row("features.matcher.orb_ratio",
        matcher, &Matcher::orb_ratio, "", "(0, 1]",
        "wide-baseline (ORB) ratio test"),
    row("features.matcher.orb_max_hamming",
        matcher, &Matcher::orb_max_hamming, "bits", "[0, 256]",
        "wide-baseline (ORB) Hamming distance at most"),
    row("features.matcher.orb_fallback_below_points",
        matcher, &Matcher::orb_fallback_below_points, "", "0 (off) or [1, inf)",
        "fewer KLT-verified points than this: ORB points replace them if there are more"),

    // features.matcher.lines: LineMatchOptions
    row("features.matcher.lines.ratio",
        lines, &Lines::ratio, "", "(0, 1]",
        "best / second-best descriptor distance must be below this"),
    row("features.matcher.lines.mutual",
        lines, &Lines::mutual, "", "",
        "keep only mutual best matches"),
    row("features.matcher.lines.max_descriptor_distance",
        lines, &Lines::max_descriptor_distance, "", "(0, 2]",
        "L2 distance of the unit-norm descriptors at most"),
    row("features.matcher.lines.max_angle_change_rad",
        lines, &Lines::max_angle_change_rad, "rad", "(0, pi/2]",
        "|theta_a - theta_b| (mod pi) at most"),
    row("features.matcher.lines.vertical_tolerance_rad",
        lines, &Lines::vertical_tolerance_rad, "rad", "[0, pi/2)",
        "a line is near vertical when |theta| is below this"),
    row("features.matcher.lines.vertical_mismatch_rad",
        lines, &Lines::vertical_mismatch_rad, "rad", "[vertical_tolerance_rad, pi/2]",
        "a near-vertical line must stay within this of vertical in the other view"),
    row("features.matcher.lines.epipolar_overlap",
        lines, &Lines::epipolar_overlap, "", "",
        "check the segments' overlap along epipolar lines when the essential matrix is known"),

    // features.matcher.essential: EssentialRansacOptions (core/geometry/essential_ransac.hpp)
    row("features.matcher.essential.threshold_px",
        essential, &Essential::threshold_px, "px", "(0, 100]",
        "Sampson distance inlier threshold"),
    row("features.matcher.essential.confidence",
        essential, &Essential::confidence, "", "(0, 1)",
        "RANSAC confidence"),
    row("features.matcher.essential.max_iterations",
        essential, &Essential::max_iterations, "", "[1, 100000]",
        "RANSAC iterations at most"),
    row("features.matcher.essential.min_inliers",
        essential, &Essential::min_inliers, "", "[5, inf)",
        "fewer inliers: no essential matrix"),
    row("features.matcher.essential.planar",
        essential, &Essential::planar, "", "",
        "planar-motion 2-point RANSAC seeds the general model (general_refit); off: "
        "five-point RANSAC on all matches (docs/perception.md \"Two-view verification\")"),
    row("features.matcher.essential.planar_threshold_factor",
        essential, &Essential::planar_threshold_factor, "", "[1, 10]",
        "planar model: its RANSAC threshold in multiples of threshold_px"),
    row("features.matcher.essential.general_refit",
        essential, &Essential::general_refit, "", "",
        "planar model: seeds the general model, refined on Sampson distances and refitted by "
        "five-point RANSAC on its candidates (off: a linear refinement of the planar model only)"),
    row("features.matcher.essential.general_refit_max_iterations",
        essential, &Essential::general_refit_max_iterations, "", "[1, 100000]",
        "planar model: five-point samples on its candidates at most"),
    row("features.matcher.essential.five_point_fallback",
        essential, &Essential::five_point_fallback, "", "",
        "planar model: run five-point when it finds no model"),

    // features.matcher.trifocal: PlanarTrifocalOptions (core/geometry/planar_trifocal.hpp)
    row("features.matcher.trifocal.threshold_px",
        trifocal, &Trifocal::threshold_px, "px", "(0, 100]",
        "reprojection distance of a segment endpoint at most"),
    row("features.matcher.trifocal.confidence",
        trifocal, &Trifocal::confidence, "", "(0, 1)",
        "adaptive stopping confidence"),
    row("features.matcher.trifocal.max_iterations",
        trifocal, &Trifocal::max_iterations, "", "[1, 1e6]",
        "samples drawn at most"),
    row("features.matcher.trifocal.min_iterations",
        trifocal, &Trifocal::min_iterations, "", "[1, max_iterations]",
        "samples drawn at least (adaptive stopping is optimistic with noisy minimal models)"),
    row("features.matcher.trifocal.min_inliers",
        trifocal, &Trifocal::min_inliers, "", "[3, inf)",
        "fewer verified triplets: not found"),
    row("features.matcher.trifocal.max_yaw_rad",
        trifocal, &Trifocal::max_yaw_rad, "rad", "(0, pi/2)",
        "|yaw| searched (views of one tour turn less)"),
    row("features.matcher.trifocal.min_rotation_leverage",
        trifocal, &Trifocal::min_rotation_leverage, "", "[0, 1)",
        "|normal_y| a triplet needs in all views to fix the yaws"),
    row("features.matcher.trifocal.yaw_scan_steps",
        trifocal, &Trifocal::yaw_scan_steps, "", "[4, 10000]",
        "samples of the yaw scan before bisection"),
    row("features.matcher.trifocal.lo_iterations",
        trifocal, &Trifocal::lo_iterations, "", "[0, 100]",
        "Levenberg-Marquardt iterations of each local optimisation (0: none)"),
    row("features.matcher.trifocal.max_lo_runs",
        trifocal, &Trifocal::max_lo_runs, "", "[0, 1000]",
        "local optimisations during sampling (then one at the end)"),
    row("features.matcher.trifocal.optimal_threshold_px",
        trifocal, &Trifocal::optimal_threshold_px, "px", "(0, inf)",
        "final check: RMS endpoint distance after optimal triangulation under the model"),
    row("features.matcher.trifocal.check_overlap",
        trifocal, &Trifocal::check_overlap, "", "",
        "final inliers must overlap on their 3D line, in front of the cameras"),
    row("features.matcher.trifocal.overlap_margin_px",
        trifocal, &Trifocal::overlap_margin_px, "px", "[0, inf)",
        "extra margin of that overlap check"),
    row("features.matcher.trifocal.overlap_min_plane_sine",
        trifocal, &Trifocal::overlap_min_plane_sine, "", "[0, 1)",
        "sine between the back-projected planes below which the overlap check abstains"),
    row("features.matcher.trifocal.prior_from_points",
        trifocal, &Trifocal::prior_from_points, "", "",
        "seed the line RANSAC from the point branch's two essential matrices"),
    row("features.matcher.trifocal.prior_min_points",
        trifocal, &Trifocal::prior_min_points, "", "[5, inf)",
        "verified point pairs an essential matrix needs to serve as prior"),
    row("features.matcher.trifocal.prior_max_tilt_rad",
        trifocal, &Trifocal::prior_max_tilt_rad, "rad", "[0, pi/2)",
        "prior: rotation off the vertical axis at most"),
    row("features.matcher.trifocal.prior_max_t_y",
        trifocal, &Trifocal::prior_max_t_y, "", "[0, 1]",
        "prior: |t_y| / |t| at most (translation in the floor plane)"),
    row("features.matcher.trifocal.prior_min_parallax_px",
        trifocal, &Trifocal::prior_min_parallax_px, "px", "[0, inf)",
        "prior: median parallax after derotation at least (else near-pure rotation)"),
    row("features.matcher.trifocal.prior_min_cheirality",
        trifocal, &Trifocal::prior_min_cheirality, "", "(0.5, 1]",
        "prior: fraction of the points in front under the chosen pose"),
    row("features.matcher.trifocal.prior_min_samples",
        trifocal, &Trifocal::prior_min_samples, "", "[1, max_iterations]",
        "single-triplet samples drawn at least"),
    row("features.matcher.trifocal.prior_max_challengers",
        trifocal, &Trifocal::prior_max_challengers, "", "[0, max_iterations]",
        "unseeded 3-triplet samples drawn at most after a prior"),
    row("features.matcher.trifocal.prior_replace_ratio",
        trifocal, &Trifocal::prior_replace_ratio, "", "[1, inf)",
        "a challenger replaces the prior's model only with this many times as many triplets"),
    row("features.matcher.trifocal.seed",
        trifocal, &Trifocal::seed, "", "[0, inf)",
        "RNG seed (deterministic)"),

    // key_images: KeyImageSelectorOptions (core/mapping/key_image_selector.hpp)
    row("key_images.epsilon",
        key_images, &KeyImages::epsilon, "", "[1, inf)",
        "verified lines + points below which a new key image is taken (the relative rule's floor)"),
    row("key_images.min_frame_gap",
        key_images, &KeyImages::min_frame_gap, "frames", "[1, inf)",
        "frames between a key image and the next at least (1: the paper)"),
    row("key_images.relative",
        key_images, &KeyImages::relative, "", "[0, 1)",
        "threshold max(epsilon, this x the count 2 frames after the key image); 0: the paper's"),
    row("key_images.max_fraction",
        key_images, &KeyImages::max_fraction, "", "(relative, 1]",
        "relative rule: the threshold never exceeds this x that count (1: no cap)"),
    row("key_images.max_heading_change_rad",
        key_images, &KeyImages::max_heading_change_rad, "rad", "[0, pi]",
        "also a key image when the odometry heading turned this much since the last one, so a "
        "turn facing a blank wall still gets key images inside it (0: off; ~1/3 of the view)"),

    // navigator: NavigatorOptions (core/navigator/navigator.hpp)
    row("navigator.controller",
        navigator, &Navigator::controller, "", "",
        "vnhv: Blanc et al. per segment, IBVS where it has no estimate; ibvs: the paper's law"),
    row("navigator.features",
        navigator, &Navigator::features, "", "",
        "kinds of feature matched and used (the paper's lines only / points only / combined)"),
    row("navigator.hold_s",
        navigator, &Navigator::hold_s, "s", "[0, inf)",
        "hold the last command this long (frame time) when features vanish, then stop"),
    row("navigator.min_line_matches",
        navigator, &Navigator::min_line_matches, "", "[1, inf)",
        "fewer verified line matches with IN: no line term"),
    row("navigator.min_point_matches",
        navigator, &Navigator::min_point_matches, "", "[1, inf)",
        "fewer (textured) point matches with IN: no point term"),
    row("navigator.min_point_texture",
        navigator, &Navigator::min_point_texture, "grey^2/px^2", "[0, inf)",
        "point matches on textureless spots (structure-tensor min eigenvalue below) are dropped"),
    row("navigator.arrival_scale_ratio",
        navigator, &Navigator::arrival_scale_ratio, "", "(0, 2)",
        "arrival at the final image: scale ratio (key -> current) of the points with IN at least"),
    row("navigator.arrival_min_scale_points",
        navigator, &Navigator::arrival_min_scale_points, "", "[3, inf)",
        "points the scale ratio needs on the final segment"),
    row("navigator.blind_switch_min_driven_fraction",
        navigator, &Navigator::blind_switch_min_driven_fraction, "", "0 (off) or (0, 1]",
        "scale ratio unknown: a switch waits until v covered this x the taught IP->IN length"),
    row("navigator.dead_reckoning_max_lateral_sigma_m",
        navigator, &Navigator::dead_reckoning_max_lateral_sigma_m, "m", "(0, inf)",
        "vision lost, odometry drives the taught path until its error across it grew this much"),
    row("navigator.odometry_steer_max_m",
        navigator, &Navigator::odometry_steer_max_m, "m", "(0, inf)",
        "VNHV has no estimate, the image has features: odometry steers this far past a fix"),
    row("navigator.min_scale_points",
        navigator, &Navigator::min_scale_points, "", "[3, inf)",
        "verified points the apparent-scale ratio vs IN needs"),
    row("navigator.scale_quantile",
        navigator, &Navigator::scale_quantile, "", "(0, 1)",
        "the scale ratio is this quantile of the pairwise ratios (0.5: the median)"),
    row("navigator.min_scale_lines",
        navigator, &Navigator::min_scale_lines, "", "0 (points only) or [1, inf)",
        "fewer points than min_scale_points: the ratio from the lines if at least this many"),
    row("navigator.min_scale_pairs",
        navigator, &Navigator::min_scale_pairs, "", "[1, inf)",
        "ratios of line pairs the line scale ratio needs"),
    row("navigator.scale_line_max_angle_rad",
        navigator, &Navigator::scale_line_max_angle_rad, "rad", "(0, 0.5]",
        "\"nearly parallel\" for those line pairs"),
    row("navigator.segment_overdue_factor",
        navigator, &Navigator::segment_overdue_factor, "", "0 (off) or (0, inf)",
        "no switch for max(segment_overdue_min_s, this x the taught IP->IN time): stop for good"),
    row("navigator.segment_overdue_min_s",
        navigator, &Navigator::segment_overdue_min_s, "s", "[0, inf)",
        "the overdue rule's shortest wait (frame time)"),

    // navigator.ibvs: IbvsOptions (core/control/ibvs_law.hpp)
    row("navigator.ibvs.g1",
        ibvs, &Ibvs::g1, "", "[0, 1]",
        "weight of the next key image IN (paper; g1 + g2 > 0)"),
    row("navigator.ibvs.g2",
        ibvs, &Ibvs::g2, "", "[0, 1]",
        "weight of the next-next key image INN, feed-forward (paper)"),
    row("navigator.ibvs.lambda",
        ibvs, &Ibvs::lambda, "1/s", "(0, inf)",
        "gain (paper)"),

    // navigator.vnhv: VnhvOptions (core/control/vnhv_law.hpp)
    row("navigator.vnhv.kp_1_m2",
        vnhv, &Vnhv::kp_1_m2, "1/m^2", "(0, inf)",
        "Kp: natural frequency in distance sqrt(Kp)"),
    row("navigator.vnhv.kd_1_m",
        vnhv, &Vnhv::kd_1_m, "1/m", "(0, inf)",
        "Kd: 2 sqrt(Kp) is critically damped"),
    row("navigator.vnhv.max_abs_theta_rad",
        vnhv, &Vnhv::max_abs_theta_rad, "rad", "(0, pi/2)",
        "validity bound on |theta|"),
    row("navigator.vnhv.teach_speed_m_s",
        vnhv, &Vnhv::teach_speed_m_s, "m/s", "(0, inf)",
        "maps without driven distances: a segment's length is its taught time x this"),
    row("navigator.vnhv.max_segment_turn_rad",
        vnhv, &Vnhv::max_segment_turn_rad, "rad", "(0, inf)",
        "segments turning more than this follow their arc or IBVS"),
    row("navigator.vnhv.max_arc_turn_rad",
        vnhv, &Vnhv::max_arc_turn_rad, "rad", "[0, inf)",
        "turning segments up to this follow their arc (0: IBVS drives every turn)"),
    row("navigator.vnhv.straight_min_parallax_rad",
        vnhv, &Vnhv::straight_min_parallax_rad, "rad", "(0, inf)",
        "long straight segments: triangulation parallax at least (instead of pose's)"),
    row("navigator.vnhv.straight_min_points",
        vnhv, &Vnhv::straight_min_points, "", "[3, inf)",
        "long straight segments: model and resection points at least"),
    row("navigator.vnhv.straight_min_length_m",
        vnhv, &Vnhv::straight_min_length_m, "m", "[0, inf)",
        "taught length from which a straight segment is long"),

    // navigator.vnhv.pose: SegmentPoseOptions (core/control/segment_pose.hpp)
    row("navigator.vnhv.pose.min_parallax_rad",
        pose, &Pose::min_parallax_rad, "rad", "(0, inf)",
        "triangulation: angle between the two viewing rays at least"),
    row("navigator.vnhv.pose.max_reprojection_px",
        pose, &Pose::max_reprojection_px, "px", "(0, inf)",
        "triangulation check and resection inlier threshold"),
    row("navigator.vnhv.pose.min_points",
        pose, &Pose::min_points, "", "[3, inf)",
        "triangulated points for a segment model, and resection inliers for a pose"),
    row("navigator.vnhv.pose.ransac_iterations",
        pose, &Pose::ransac_iterations, "", "[1, inf)",
        "resection RANSAC samples"),
    row("navigator.vnhv.pose.gauss_newton_iterations",
        pose, &Pose::gauss_newton_iterations, "", "[1, inf)",
        "resection refinement steps"),

    // navigator.vnhv.filter: DeviationFilterOptions (core/control/deviation_filter.hpp)
    row("navigator.vnhv.filter.measurement_sigma_m",
        filter, &Filter::measurement_sigma_m, "m", "(0, inf)",
        "lateral measurement noise"),
    row("navigator.vnhv.filter.measurement_sigma_rad",
        filter, &Filter::measurement_sigma_rad, "rad", "(0, inf)",
        "heading measurement noise"),
    row("navigator.vnhv.filter.process_sigma_m",
        filter, &Filter::process_sigma_m, "m/sqrt(s)", "(0, inf)",
        "lateral drift of the prediction"),
    row("navigator.vnhv.filter.process_sigma_rad",
        filter, &Filter::process_sigma_rad, "rad/sqrt(s)", "(0, inf)",
        "heading drift of the prediction"),
    row("navigator.vnhv.filter.gate_chi2",
        filter, &Filter::gate_chi2, "", "(0, inf)",
        "innovation gate, chi-square with 2 dof (13.8: 99.9 %)"),
    row("navigator.vnhv.filter.max_rejections",
        filter, &Filter::max_rejections, "", "[1, inf)",
        "consecutive rejections before a restart"),
    row("navigator.vnhv.filter.max_prediction_s",
        filter, &Filter::max_prediction_s, "s", "[0, inf)",
        "how long a prediction alone stays valid"),

    // navigator.speed: VelocityScheduleOptions (core/control/velocity_schedule.hpp)
    row("navigator.speed.v_straight_m_s",
        speed, &Speed::v_straight_m_s, "m/s", "[0, inf)",
        "forward speed (paper)"),
    row("navigator.speed.v_turn_m_s",
        speed, &Speed::v_turn_m_s, "m/s", "[0, v_straight_m_s]",
        "forward speed while turning (paper)"),
    row("navigator.speed.turn_enter_rad_s",
        speed, &Speed::turn_enter_rad_s, "rad/s", "(turn_exit_rad_s, inf)",
        "|omega| at which turning starts"),
    row("navigator.speed.turn_exit_rad_s",
        speed, &Speed::turn_exit_rad_s, "rad/s", "[0, inf)",
        "|omega| at which turning ends"),
    row("navigator.speed.turn_exit_hold_s",
        speed, &Speed::turn_exit_hold_s, "s", "[0, inf)",
        "turning ends only once |omega| stayed at or below turn_exit_rad_s this long"),
    row("navigator.speed.max_omega_rad_s",
        speed, &Speed::max_omega_rad_s, "rad/s", "(0, inf)",
        "yaw-rate saturation"),
    row("navigator.speed.max_omega_accel_rad_s2",
        speed, &Speed::max_omega_accel_rad_s2, "rad/s^2", "(0, inf)",
        "yaw-rate rate limit"),
    row("navigator.speed.first_step_dt_s",
        speed, &Speed::first_step_dt_s, "s", "(0, inf)",
        "interval assumed for the first step after a (re)start"),

    // navigator.localization: InitialLocalizationOptions (core/localization/key_image_logic.hpp)
    row("navigator.localization.min_best_count",
        localization_rule, &LocalizationRule::min_best_count, "", "[1, inf)",
        "verified matches with the best key image below this: not localised"),

    // navigator.localization: InitialLocalizerOptions (core/localization/initial_localizer.hpp)
    row("navigator.localization.top_k",
        localization, &Localization::top_k, "", "[1, inf)",
        "key images verified geometrically after the vote"),
    row("navigator.localization.vote_ratio",
        localization, &Localization::vote_ratio, "", "(0, 1]",
        "2-NN ratio test of the vote"),
    row("navigator.localization.vote_max_hamming",
        localization, &Localization::vote_max_hamming, "bits", "[0, 256]",
        "ORB distance above which a match does not vote"),

    // navigator.switching: SwitcherOptions (core/localization/key_image_logic.hpp)
    row("navigator.switching.consecutive_frames",
        switching, &Switching::consecutive_frames, "frames", "[1, inf)",
        "frames in a row a switch (or arrival) must be seen (paper: 2)"),
    row("navigator.switching.min_next_scale_ratio",
        switching, &Switching::min_next_scale_ratio, "", "[0, 2)",
        "a switch is wanted only once IN's scale ratio reached this (0: the paper's rule)"),

    // robot: RobotConfig
    row("robot.camera_width_px",
        robot, &RobotConfig::camera_width_px, "px", "320 (QVGA) or 640 (VGA)",
        "camera image width (with the height: 320x240 or 640x480)"),
    row("robot.camera_height_px",
        robot, &RobotConfig::camera_height_px, "px", "240 (QVGA) or 480 (VGA)",
        "camera image height"),
    row("robot.camera_fps",
        robot, &RobotConfig::camera_fps, "frames/s", "[1, 30]",
        "camera frame rate requested"),
    row("robot.head_pitch_rad",
        robot, &RobotConfig::head_pitch_rad, "rad", "[-0.707, 0.637]",
        "head pitch while locked (Pepper's HeadPitch range; 0: optical axis horizontal)"),
    row("robot.ceiling_head_pitch_rad",
        robot, &RobotConfig::ceiling_head_pitch_rad, "rad", "[-0.707, 0)",
        "head pitch while locked in ceiling mode (--mode ceiling; < 0 looks up)"),
    row("robot.ceiling_height_m",
        robot, &RobotConfig::ceiling_height_m, "m", "[0, 30]",
        "ceiling's height above the floor, measured (ceiling mode on a real robot needs it; 0: not "
        "set, mock: robots use their world's)"),
    row("robot.head_yaw_rad",
        robot, &RobotConfig::head_yaw_rad, "rad", "[-2.086, 2.086]",
        "head yaw while locked (Pepper's HeadYaw range)"),
    row("robot.watchdog_s",
        robot, &RobotConfig::watchdog_s, "s", "[0.05, 2]",
        "the bridge stops the base without a fresh command this long"),
    row("robot.frame_timeout_s",
        robot, &RobotConfig::frame_timeout_s, "s", "[0.1, 10]",
        "the session stops the base when no frame comes this long (a simulated robot: its "
        "simulated time)"),
    row("robot.deadman_horizon_s",
        robot, &RobotConfig::deadman_horizon_s, "s", "0 (off) or [0.05, 2]",
        "tcp/tcps robots: each velocity command ends by itself on the robot after this long "
        "(ALMotion.moveTo with a time), so a frozen or killed laptop cannot leave it driving"),
    row("robot.user",
        robot, &RobotConfig::user, "", "",
        "login user for tcps:// (NAOqi 2.9: nao); the password is never here"),

    // replay: ReplayConfig
    row("replay.give_up_lost_s",
        replay, &ReplayConfig::give_up_lost_s, "s", "0 (never) or (0, 3600]",
        "stopped this long (frame time) after having driven: the replay ends as lost"),
    row("replay.give_up_not_localised_s",
        replay, &ReplayConfig::give_up_not_localised_s, "s", "0 (never) or (0, 3600]",
        "not localised this long: the replay ends as not_localised"),
    row("replay.arrival_tolerance_m",
        replay, &ReplayConfig::arrival_tolerance_m, "m", "(0, 2]",
        "end of tour: arrived when the estimated offset from the final key image is within this "
        "(else not aligned)"),
    row("replay.arrival_tolerance_rad",
        replay, &ReplayConfig::arrival_tolerance_rad, "rad", "(0, 1]",
        "end of tour: arrived when the estimated heading error is within this"),

    // ceiling: CeilingConfig (ceiling-mode replay, core/ceiling/ceiling_navigator.hpp; its law's
    // gains and speeds are navigator.vnhv.* and navigator.speed.*)
    row("ceiling.arc_min_turn_rad",
        ceiling, &CeilingConfig::arc_min_turn_rad, "rad", "[0, inf)",
        "relay segments turning more than this follow their arc, the others their chord"),
    row("ceiling.turn_in_place_gain_1_s",
        ceiling, &CeilingConfig::turn_in_place_gain_1_s, "1/s", "(0, 5]",
        "heading beyond navigator.vnhv.max_abs_theta_rad: turn on the spot at this gain"),
    row("ceiling.coast_max_error_m",
        ceiling, &CeilingConfig::coast_max_error_m, "m", "[0, 0.5]",
        "no fix against the mosaic: drive on odometry while its error model says the pose may "
        "be at most this far off, then stop (0: stop)"),
    row("ceiling.coast_max_s",
        ceiling, &CeilingConfig::coast_max_s, "s", "[0, 20]",
        "and at most this long since the last fix"),

    // ui: UiConfig
    row("ui.port",
        ui, &UiConfig::port, "", "0 (any free port) or [1, 65535]",
        "teach UI port"),
    row("ui.max_v_m_s",
        ui, &UiConfig::max_v_m_s, "m/s", "(0, 0.55]",
        "teach driving limit from the keyboard / buttons"),
    row("ui.max_omega_rad_s",
        ui, &UiConfig::max_omega_rad_s, "rad/s", "(0, 2]",
        "teach yaw-rate limit from the keyboard / buttons"),
  };
  // clang-format on
}

struct Index {
  std::vector<Parameter> rows;
  std::map<std::string, std::size_t, std::less<>> by_key;
  std::set<std::string, std::less<>> sections;
};

const Index& index() {
  static const Index idx = [] {
    Index i;
    i.rows = build_table();
    for (std::size_t k = 0; k < i.rows.size(); ++k) {
      const Parameter& p = i.rows[k];
      if (!i.by_key.emplace(p.key, k).second) throw std::logic_error(p.key + ": listed twice");
      for (auto dot = p.key.find('.'); dot != std::string::npos; dot = p.key.find('.', dot + 1))
        i.sections.insert(p.key.substr(0, dot));
    }
    for (const Parameter& p : i.rows) {
      for (const auto& ref : p.range.references()) {
        const auto it = i.by_key.find(p.section() + "." + ref);
        if (it == i.by_key.end() || !i.rows[it->second].numeric())
          throw std::logic_error(p.key + ": range names " + ref + ", not a number of its section");
      }
    }
    return i;
  }();
  return idx;
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string format_number(const json& v) {
  if (!v.is_number_float()) return v.dump();
  std::ostringstream os;
  os.precision(10);
  os << v.get<double>();
  return os.str();
}

}  // namespace

// ---- Range. ----------------------------------------------------------------------------------

Range::Range(std::string text) : text_(std::move(text)) {
  std::string_view rest = trim(text_);
  while (!rest.empty()) {
    const auto sep = rest.find(" or ");
    alternatives_.push_back(parse_alternative(trim(rest.substr(0, sep)), text_));
    rest = sep == std::string_view::npos ? std::string_view() : rest.substr(sep + 4);
    if (sep != std::string_view::npos && trim(rest).empty()) bad_range(text_, "nothing after 'or'");
  }
}

Range::Bound Range::parse_bound(std::string_view text, const std::string& whole) {
  text = trim(text);
  Bound b;
  const bool negative = !text.empty() && text.front() == '-';
  const std::string_view magnitude = negative ? text.substr(1) : text;
  const double sign = negative ? -1.0 : 1.0;
  if (magnitude == "inf") {
    b.value = sign * std::numeric_limits<double>::infinity();
  } else if (magnitude.substr(0, 2) == "pi") {
    double divisor = 1.0;
    if (magnitude.size() > 2) {
      if (magnitude[2] != '/') bad_range(whole, "bad bound '" + std::string(text) + "'");
      const std::string d(magnitude.substr(3));
      char* end = nullptr;
      divisor = std::strtod(d.c_str(), &end);
      if (d.empty() || *end != '\0' || !(divisor > 0.0))
        bad_range(whole, "bad bound '" + std::string(text) + "'");
    }
    b.value = sign * std::numbers::pi / divisor;
  } else if (is_identifier(text)) {
    b.reference = std::string(text);
  } else {
    const std::string s(text);
    char* end = nullptr;
    b.value = std::strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0' || !std::isfinite(b.value))
      bad_range(whole, "bad bound '" + s + "'");
  }
  return b;
}

Range::Alternative Range::parse_alternative(std::string_view text, const std::string& whole) {
  Alternative a;
  a.text = std::string(text);
  if (text.empty()) bad_range(whole, "empty alternative");
  if ((text.front() == '[' || text.front() == '(') && text.find(',') != std::string_view::npos) {
    const char close = text.back();
    if (close != ']' && close != ')') bad_range(whole, "an interval ends with ] or )");
    const auto comma = text.find(',');
    a.low = parse_bound(text.substr(1, comma - 1), whole);
    a.high = parse_bound(text.substr(comma + 1, text.size() - comma - 2), whole);
    a.low_open = text.front() == '(';
    a.high_open = close == ')';
    if (!a.low_open && std::isinf(a.low.value)) bad_range(whole, "infinity is always open: (");
    if (!a.high_open && std::isinf(a.high.value)) bad_range(whole, "infinity is always open: )");
    if (a.low.reference.empty() && a.high.reference.empty() && !(a.low.value <= a.high.value))
      bad_range(whole, "low bound above high bound");
    return a;
  }
  // A single value, optionally labelled: "0 (off)".
  const auto space = text.find(' ');
  a.single = true;
  a.low = a.high = parse_bound(text.substr(0, space), whole);
  if (!a.low.reference.empty()) bad_range(whole, "a single value must be a number");
  if (space != std::string_view::npos) {
    const std::string_view label = trim(text.substr(space));
    if (label.size() < 2 || label.front() != '(' || label.back() != ')')
      bad_range(whole, "a value's label goes in parentheses: 0 (off)");
  }
  return a;
}

std::vector<std::string> Range::references() const {
  std::vector<std::string> out;
  for (const auto& a : alternatives_) {
    for (const Bound* b : {&a.low, &a.high}) {
      if (!b->reference.empty()) out.push_back(b->reference);
    }
  }
  return out;
}

bool Range::contains(double value, const std::function<double(const std::string&)>& lookup) const {
  if (alternatives_.empty()) return true;
  auto bound = [&](const Bound& b) { return b.reference.empty() ? b.value : lookup(b.reference); };
  for (const auto& a : alternatives_) {
    const double low = bound(a.low), high = bound(a.high);
    const bool above = a.low_open ? value > low : value >= low;
    const bool below = a.high_open ? value < high : value <= high;
    if (above && below) return true;
  }
  return false;
}

std::string Range::describe() const {
  std::string out;
  for (const auto& a : alternatives_) {
    if (!out.empty()) out += " or ";
    if (!a.single) out += "in ";
    out += a.text;
  }
  return out;
}

// ---- Parameter. ------------------------------------------------------------------------------

std::string Parameter::section() const {
  const auto dot = key.rfind('.');
  return dot == std::string::npos ? std::string() : key.substr(0, dot);
}

std::string Parameter::name() const { return key.substr(key.rfind('.') + 1); }

std::string Parameter::type_name() const {
  switch (type) {
    case ParamType::kBool:
      return "bool";
    case ParamType::kInt:
      return "int";
    case ParamType::kInt64:
      return "int64";
    case ParamType::kUint64:
      return "uint64";
    case ParamType::kFloat:
      return "float";
    case ParamType::kDouble:
      return "double";
    case ParamType::kString:
      return "string";
    case ParamType::kEnum:
      return "enum";
  }
  return "?";
}

bool Parameter::numeric() const {
  return type != ParamType::kBool && type != ParamType::kString && type != ParamType::kEnum;
}

const std::vector<Parameter>& parameters() { return index().rows; }

const Parameter* find_parameter(std::string_view key) {
  const Index& i = index();
  const auto it = i.by_key.find(key);
  return it == i.by_key.end() ? nullptr : &i.rows[it->second];
}

bool is_section(std::string_view key) { return index().sections.count(key) > 0; }

std::string closest_key(std::string_view key) {
  const auto dot = key.rfind('.');
  const std::string parent(dot == std::string_view::npos ? "" : key.substr(0, dot));
  const std::string_view last = dot == std::string_view::npos ? key : key.substr(dot + 1);
  // A known name under another section ("navigator.kp_1_m2"): that key.
  for (const auto& p : parameters()) {
    if (p.name() == last) return p.key;
  }
  // Else the closest sibling by its last component (any key when the parent is unknown too),
  // names that begin with the typed one ("kp" of "kp_1_m2") first, then by edit distance.
  const bool known_parent = parent.empty() || is_section(parent);
  std::vector<std::string> candidates;
  for (const auto& p : parameters()) candidates.push_back(p.key);
  for (const auto& s : index().sections) candidates.push_back(s);
  std::string best;
  std::pair<int, std::size_t> best_score{2, 0};
  for (const auto& c : candidates) {
    const auto c_dot = c.rfind('.');
    const std::string c_parent = c_dot == std::string::npos ? "" : c.substr(0, c_dot);
    if (known_parent && c_parent != parent) continue;
    const std::string_view c_last = std::string_view(c).substr(c_dot + 1);
    const std::pair<int, std::size_t> score =
        !known_parent              ? std::pair<int, std::size_t>{1, edit_distance(key, c)}
        : c_last.starts_with(last) ? std::pair<int, std::size_t>{0, c_last.size()}
                                   : std::pair<int, std::size_t>{1, edit_distance(last, c_last)};
    if (best.empty() || score < best_score) {
      best_score = score;
      best = c;
    }
  }
  return best;
}

const std::vector<std::pair<std::string, std::string>>& section_docs() {
  static const std::vector<std::pair<std::string, std::string>> docs = {
      {"features.extractor",
       "Per-image features (EDLines segments, LBD-style descriptors, FAST corners, ORB); teach "
       "and replay share them, since a map's descriptors must match replay's."},
      {"features.klt", "Pyramidal KLT, shared by the key images' pyramids and the tracker."},
      {"features.matcher", "Matching and verification between images."},
      {"features.matcher.lines", "Line matching by descriptor and geometry."},
      {"features.matcher.essential", "Essential-matrix RANSAC verifying point matches (five-point, or planar 2-point)."},
      {"features.matcher.trifocal", "Three-view RANSAC verifying line matches."},
      {"key_images", "Key-image selection while teaching (the epsilon rule)."},
      {"navigator", "Replay: controller, feature kinds, holds, arrival, switching guards."},
      {"navigator.ibvs", "The paper's IBVS law."},
      {"navigator.vnhv", "The VNHV law (Blanc et al.) on a per-segment reconstruction."},
      {"navigator.vnhv.pose", "Segment reconstruction and resection for VNHV."},
      {"navigator.vnhv.filter", "Filter of VNHV's lateral and heading deviations."},
      {"navigator.speed", "Forward speed schedule and yaw-rate limits."},
      {"navigator.localization", "Initial localisation among the key images."},
      {"navigator.switching", "When to switch to the next key image."},
      {"robot", "Camera request, head lock, safety timeouts, login user."},
      {"replay", "When a replay that cannot go on gives up."},
      {"ceiling",
       "Ceiling-mode replay (`--mode ceiling`, docs/method/ceiling.md): the reference between "
       "relay images and what happens without a fix against the mosaic. The law's gains and the "
       "speeds are `navigator.vnhv.*` and `navigator.speed.*`."},
      {"ui", "Teach UI port and driving limits."},
  };
  return docs;
}

std::vector<std::string> check_ranges(const AppConfig& config) {
  std::vector<std::string> errors;
  for (const Parameter& p : parameters()) {
    if (!p.numeric()) continue;
    const json value = p.get(config);
    const std::string section = p.section();
    auto lookup = [&](const std::string& ref) {
      return find_parameter(section + "." + ref)->get(config).get<double>();
    };
    if (p.range.contains(value.get<double>(), lookup)) continue;
    std::string notes = p.unit;
    for (const auto& ref : p.range.references()) {
      notes += (notes.empty() ? "" : "; ") + ref + " = " +
               format_number(find_parameter(section + "." + ref)->get(config));
    }
    errors.push_back(p.key + " = " + format_number(value) + ": must be " + p.range.describe() +
                     (notes.empty() ? "" : " (" + notes + ")"));
  }
  return errors;
}

const std::vector<Preset>& presets() {
  static const std::vector<Preset> list = {
      {"default",
       "The measured defaults: the VNHV controller with the paper's gains and speeds, the "
       "configuration behind the README's closed-loop figures.",
       {}},
      {"paper",
       "The paper's settings: its IBVS law alone (g1 0.7, g2 0.3, lambda 1, 0.15 / 0.08 m/s; "
       "those are the defaults) instead of VNHV.",
       {"navigator.controller=ibvs"}},
      {"fast",
       "Issue 22's cheaper tracking: a 9 px KLT window instead of 15 (the step's median on real "
       "Pepper frames: QVGA ~12 ms instead of ~21, VGA ~22 instead of ~28). Not the default: "
       "with the five-point model it lost the points after a feature-poor turn; with the "
       "planar model the generated screening (80 replays, QVGA) completed all, with one run "
       "over the targets as the defaults had (another world), so the shipped matrix decides "
       "(docs/evaluation.md).",
       {"features.klt.window_px=9", "features.klt.prior_window_px=9"}},
  };
  return list;
}

const Preset* find_preset(std::string_view name) {
  for (const auto& p : presets()) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

}  // namespace pepper::app
