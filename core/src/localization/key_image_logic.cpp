#include "core/localization/key_image_logic.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace pepper::core::localization {

Segment segment_ending_at(int next, int key_image_count) {
  if (key_image_count < 2 || next < 1 || next >= key_image_count) {
    std::ostringstream os;
    os << "segment_ending_at: next = " << next << " not in [1, " << key_image_count - 1
       << "] (key_image_count = " << key_image_count << ")";
    throw std::invalid_argument(os.str());
  }
  Segment s;
  s.prev = next - 1;
  s.next = next;
  if (next + 1 < key_image_count) s.next_next = next + 1;
  return s;
}

std::vector<std::string> InitialLocalizationOptions::validate() const {
  std::vector<std::string> errors;
  if (min_best_count < 1) {
    errors.push_back("localization.initial.min_best_count = " + std::to_string(min_best_count) +
                     " must be >= 1");
  }
  return errors;
}

InitialLocalizationResult localize_from_counts(std::span<const int> counts,
                                               const InitialLocalizationOptions& options) {
  if (const auto errors = options.validate(); !errors.empty()) {
    throw std::invalid_argument("localize_from_counts: " + errors.front());
  }
  const int n = static_cast<int>(counts.size());
  if (n < 2) {
    throw std::invalid_argument("localize_from_counts: a map needs at least 2 key images, got " +
                                std::to_string(n));
  }
  InitialLocalizationResult r;
  for (int k = 0; k < n; ++k) {
    if (counts[k] >= 0 && (r.best < 0 || counts[k] > r.best_count)) {
      r.best = k;
      r.best_count = counts[k];
    }
  }
  if (r.best < 0) return r;
  const int i = r.best;
  const int before = i > 0 ? counts[i - 1] : -1;
  const int after = i + 1 < n ? counts[i + 1] : -1;
  if (i == 0) {
    r.neighbour = 1;
  } else if (i == n - 1) {
    r.neighbour = n - 2;
  } else {
    r.neighbour = after >= before ? i + 1 : i - 1;
  }
  if (r.best_count < options.min_best_count) return r;
  r.segment = segment_ending_at(std::max(i, r.neighbour), n);
  return r;
}

std::vector<std::string> SwitcherOptions::validate() const {
  std::vector<std::string> errors;
  if (consecutive_frames < 1) {
    errors.push_back("localization.switching.consecutive_frames = " +
                     std::to_string(consecutive_frames) + " must be >= 1");
  }
  if (!(min_next_scale_ratio >= 0.0 && min_next_scale_ratio < 2.0)) {
    errors.push_back("localization.switching.min_next_scale_ratio = " +
                     std::to_string(min_next_scale_ratio) + " must be in [0, 2)");
  }
  return errors;
}

const char* to_string(SwitchEvent e) {
  switch (e) {
    case SwitchEvent::kNone:
      return "none";
    case SwitchEvent::kSwitched:
      return "switched";
    case SwitchEvent::kTourComplete:
      return "tour_complete";
  }
  return "unknown";
}

KeyImageSwitcher::KeyImageSwitcher(Segment segment, int key_image_count,
                                   const SwitcherOptions& options)
    : segment_(segment), count_(key_image_count), options_(options) {
  if (const auto errors = options_.validate(); !errors.empty()) {
    throw std::invalid_argument("KeyImageSwitcher: " + errors.front());
  }
  if (!(segment_ == segment_ending_at(segment.next, key_image_count))) {
    throw std::invalid_argument("KeyImageSwitcher: inconsistent segment for IN = " +
                                std::to_string(segment.next));
  }
}

namespace {

using Kind = SwitchRule::Kind;

bool three_view_rule(const SwitchCounts& c, const SwitcherOptions&) {
  return c.three_view_next > c.three_view_prev;
}
bool two_view_rule(const SwitchCounts& c, const SwitcherOptions&) {
  return c.two_view_next_next > c.two_view_next && c.two_view_next_next > c.two_view_prev;
}
// Unknown scale (too few verified points, e.g. facing a plain wall): the guard cannot judge, so
// it blocks only when the caller says a blind switch is not allowed yet; blocking for good
// would stall at IN.
bool scale_guard_blocks(const SwitchCounts& c, const SwitcherOptions& o) {
  if (o.min_next_scale_ratio <= 0.0) return false;
  return std::isnan(c.next_scale_ratio) ? !c.blind_switch_allowed
                                        : !(c.next_scale_ratio >= o.min_next_scale_ratio);
}
bool before_by_odometry(const SwitchCounts& c, const SwitcherOptions&) {
  return c.before_by_odometry;
}
bool passed_by_distance(const SwitchCounts& c, const SwitcherOptions&) {
  return c.passed_by_distance;
}
bool passed_by_odometry(const SwitchCounts& c, const SwitcherOptions&) {
  return c.passed_by_odometry;
}

// clang-format off
const std::array<SwitchRule, 6> kSwitchRules{{
  {"three views", Kind::kPaper, "", static_cast<int>(SwitchCriterion::kThreeView),
   three_view_rule, "nL + nP (Ia, IN, INN) > nL + nP (IP, Ia, IN) (METHOD.md)"},
  {"two views", Kind::kPaper, "", static_cast<int>(SwitchCriterion::kTwoView), two_view_rule,
   "n(Ia, INN) > n(Ia, IN) and n(Ia, INN) > n(IP, Ia) (METHOD.md)"},
  {"scale guard", Kind::kGuard,
   "navigator.switching.min_next_scale_ratio, navigator.blind_switch_min_driven_fraction",
   kCriterionGuardBlocked, scale_guard_blocks,
   "the paper's rules fire too early on short segments: wait until IN's points appear at "
   "nearly their taught size (unknown size: until the commands drove part of the segment)"},
  {"IN ahead by travel (odometry)", Kind::kGuard,
   "",
   kCriterionGuardBlocked, before_by_odometry,
   "the paper's rules fire early where consecutive key images look alike (a turn taught with "
   "key images a few centimetres apart): wait while the robot's odometry, carried along the "
   "taught path, is 2 sigmas of the estimate along the robot before IN"},
  {"passed IN by travel (odometry)", Kind::kAddition,
   "",
   kCriterionPassedByOdometry, passed_by_odometry,
   "the robot's odometry, carried along the taught path, is past IN: when the scale is "
   "unknown at once, when it is known by 2 sigmas of the estimate along the robot (a scene "
   "metres away hardly changes scale over tens of centimetres)"},
  {"passed IN by travel (commands)", Kind::kAddition, "",
   kCriterionPassedByDistance, passed_by_distance,
   "the same where there is no odometry (map or robot): the commands drove twice the taught "
   "length (a bare wall)"},
}};
// clang-format on

}  // namespace

std::span<const SwitchRule> switch_rules() { return kSwitchRules; }

SwitchCriterion switch_criterion(const SwitchCounts& c) {
  const SwitcherOptions none;
  return static_cast<SwitchCriterion>((three_view_rule(c, none) ? 1 : 0) |
                                      (two_view_rule(c, none) ? 2 : 0));
}

const char* to_string(SwitchRule::Kind k) {
  switch (k) {
    case Kind::kPaper: return "paper rule";
    case Kind::kGuard: return "guard (blocks the paper rules)";
    case Kind::kAddition: return "addition (wants a switch)";
  }
  return "?";
}

SwitchUpdate KeyImageSwitcher::update(const SwitchCounts& counts, bool reached_final) {
  SwitchUpdate u;
  if (complete_) {
    u.event = SwitchEvent::kTourComplete;
    return u;
  }
  bool wanted = false;
  if (segment_.next_next) {
    bool paper = false, blocked = false, added = false;
    for (const SwitchRule& r : switch_rules()) {
      if (!r.holds(counts, options_)) continue;
      switch (r.kind) {
        case Kind::kPaper:
          paper = true;
          u.criteria_bits |= r.criterion_bit;
          break;
        case Kind::kGuard:
          blocked = true;
          break;
        case Kind::kAddition:
          added = true;
          u.criteria_bits |= r.criterion_bit;
          break;
      }
    }
    u.criterion = static_cast<SwitchCriterion>(u.criteria_bits & 3);
    if (paper && blocked) u.criteria_bits |= kCriterionGuardBlocked;
    wanted = (paper && !blocked) || added;
  } else {
    wanted = reached_final;
  }
  streak_ = wanted ? streak_ + 1 : 0;
  u.streak = streak_;
  if (streak_ >= options_.consecutive_frames) {
    streak_ = 0;
    if (segment_.next_next) {
      segment_ = segment_ending_at(*segment_.next_next, count_);
      u.event = SwitchEvent::kSwitched;
    } else {
      complete_ = true;
      u.event = SwitchEvent::kTourComplete;
    }
  }
  return u;
}

void append_point_scale_ratios(std::span<const cv::Point2d> key_norm,
                               std::span<const cv::Point2d> current_norm,
                               double min_separation_norm, std::vector<double>& ratios) {
  if (key_norm.size() != current_norm.size()) {
    throw std::invalid_argument("append_point_scale_ratios: sizes differ");
  }
  const size_t n = key_norm.size();
  if (n < 2) return;
  // Pairs (i, i + n/2 ...) would bias towards one layout; all pairs up to a cap, deterministic.
  constexpr size_t kMaxPairs = 4000;
  const size_t stride = std::max<size_t>(1, n * (n - 1) / 2 / kMaxPairs);
  size_t pair = 0;
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j, ++pair) {
      if (pair % stride != 0) continue;
      const double da = std::hypot(key_norm[i].x - key_norm[j].x, key_norm[i].y - key_norm[j].y);
      const double db =
          std::hypot(current_norm[i].x - current_norm[j].x, current_norm[i].y - current_norm[j].y);
      if (da < min_separation_norm || db < min_separation_norm) continue;
      ratios.push_back(db / da);
    }
  }
}

namespace {

// Unit direction of a segment (zero vector when degenerate).
cv::Point2d unit_direction(const cv::Point2d& p0, const cv::Point2d& p1) {
  const cv::Point2d d = p1 - p0;
  const double len = std::hypot(d.x, d.y);
  return len > 1e-12 ? d * (1.0 / len) : cv::Point2d(0.0, 0.0);
}

// Distance of point q from the infinite line through p0 with unit direction u.
double distance_to_line(const cv::Point2d& q, const cv::Point2d& p0, const cv::Point2d& u) {
  const cv::Point2d w = q - p0;
  return std::abs(w.x * u.y - w.y * u.x);
}

// Perpendicular separation of two nearly parallel segments, nullopt when they are not parallel
// within max_angle_rad (sin of the angle between the directions).
std::optional<double> parallel_separation(const cv::Point2d& p0, const cv::Point2d& p1,
                                          const cv::Point2d& q0, const cv::Point2d& q1,
                                          double max_sin) {
  const cv::Point2d u = unit_direction(p0, p1);
  const cv::Point2d v = unit_direction(q0, q1);
  if (u == cv::Point2d(0.0, 0.0) || v == cv::Point2d(0.0, 0.0)) return std::nullopt;
  if (std::abs(u.x * v.y - u.y * v.x) > max_sin) return std::nullopt;
  const cv::Point2d mp = (p0 + p1) * 0.5;
  const cv::Point2d mq = (q0 + q1) * 0.5;
  return 0.5 * (distance_to_line(mq, p0, u) + distance_to_line(mp, q0, v));
}

}  // namespace

void append_line_scale_ratios(std::span<const LineCorrespondence> lines, double max_angle_rad,
                              double min_separation_norm, std::vector<double>& ratios) {
  const double max_sin = std::sin(std::clamp(max_angle_rad, 0.0, 1.5));
  for (size_t i = 0; i < lines.size(); ++i) {
    for (size_t j = i + 1; j < lines.size(); ++j) {
      const LineCorrespondence& l = lines[i];
      const LineCorrespondence& m = lines[j];
      const auto sa = parallel_separation(l.a0_norm, l.a1_norm, m.a0_norm, m.a1_norm, max_sin);
      const auto sb = parallel_separation(l.b0_norm, l.b1_norm, m.b0_norm, m.b1_norm, max_sin);
      if (!sa || !sb || *sa < min_separation_norm || *sb < min_separation_norm) continue;
      ratios.push_back(*sb / *sa);
    }
  }
}

std::optional<double> median_ratio(std::vector<double>& ratios) {
  if (ratios.empty()) return std::nullopt;
  auto mid = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
  std::nth_element(ratios.begin(), mid, ratios.end());
  return *mid;
}

std::optional<double> quantile_ratio(std::vector<double>& ratios, double q) {
  if (ratios.empty()) return std::nullopt;
  if (q == 0.5) return median_ratio(ratios);
  const double clamped = std::clamp(q, 0.0, 1.0);
  const auto k = static_cast<std::ptrdiff_t>(clamped * static_cast<double>(ratios.size() - 1));
  std::nth_element(ratios.begin(), ratios.begin() + k, ratios.end());
  return ratios[static_cast<size_t>(k)];
}

std::optional<double> median_scale_ratio(std::span<const cv::Point2d> key_norm,
                                         std::span<const cv::Point2d> current_norm,
                                         double min_separation_norm) {
  if (key_norm.size() != current_norm.size()) {
    throw std::invalid_argument("median_scale_ratio: sizes differ");
  }
  if (key_norm.size() < 3) return std::nullopt;
  std::vector<double> ratios;
  append_point_scale_ratios(key_norm, current_norm, min_separation_norm, ratios);
  return median_ratio(ratios);
}

}  // namespace pepper::core::localization
