#pragma once
// Distance driven during teach, from the forward speed commanded to the base.
//
// The teach drive knows what it told the base; integrated over the frames' capture stamps, that
// is the path length between key images (the map's `KeyImage::travelled_m`). The navigator
// turns a segment's image-space geometry into metres with it (VNHV's lateral scale, the taught
// turn's curvature, the blind-switch guard); without it, it falls back to the taught time times
// a nominal speed, which is wrong wherever the operator drove slower or faster (a turn, a pause).
//
// Convention: `v_m_s` given with a frame is the command in force while the base moved from the
// previous frame to this one (as in a recording's frames.jsonl). Reversing counts as distance
// too (|v|): a path length, not a displacement. Stamps that do not increase add nothing.
// Pure and deterministic; not thread-safe.

#include <cstdint>
#include <optional>

namespace pepper::core::mapping {

class DriveOdometer {
 public:
  /// Adds the interval since the previous frame at |v_m_s|; returns the distance driven since
  /// the first frame (0 on the first). A non-finite v_m_s throws std::invalid_argument.
  double on_frame(int64_t t_ns, double v_m_s);
  double travelled_m() const { return travelled_m_; }

 private:
  std::optional<int64_t> last_t_ns_;
  double travelled_m_ = 0.0;
};

}  // namespace pepper::core::mapping
