// Frame drops and delays of a simulated WiFi link (see wifi_model.hpp).
#include "sim/wifi_model.hpp"

#include <cmath>
#include <stdexcept>

namespace pepper::sim {

std::vector<std::string> WifiOptions::validate() const {
  std::vector<std::string> errors;
  if (!(drop_probability >= 0.0 && drop_probability < 1.0))
    errors.push_back("drop_probability = " + std::to_string(drop_probability) +
                     " must be in [0, 1)");
  if (!(delay_s >= 0.0 && delay_s <= 10.0))
    errors.push_back("delay_s = " + std::to_string(delay_s) + " must be in [0, 10] s");
  if (!(jitter_s >= 0.0 && jitter_s <= 10.0))
    errors.push_back("jitter_s = " + std::to_string(jitter_s) + " must be in [0, 10] s");
  return errors;
}

WifiModel::WifiModel(WifiOptions options)
    : options_(options), rng_state_(options.seed * 0xD1B54A32D192ED03ULL + 7) {
  const auto errors = options_.validate();
  if (!errors.empty()) throw std::invalid_argument("WifiOptions: " + errors.front());
}

double WifiModel::uniform() {
  uint64_t z = (rng_state_ += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

std::optional<core::Frame> WifiModel::transmit(const core::Frame& frame, int64_t now_ns) {
  // Always draw both numbers so that one option does not shift the other's random sequence.
  const double u_drop = uniform();
  const double u_delay = uniform();
  if (u_drop < options_.drop_probability) {
    ++dropped_;
  } else {
    const double delay = options_.delay_s + options_.jitter_s * u_delay;
    in_flight_.push_back({frame.t_ns + std::llround(delay * 1e9), frame});
  }
  std::optional<core::Frame> out;
  for (auto it = in_flight_.begin(); it != in_flight_.end();) {
    if (it->arrival_ns <= now_ns) {
      if (it->frame.t_ns > last_delivered_ns_ && (!out || it->frame.t_ns > out->t_ns))
        out = it->frame;
      it = in_flight_.erase(it);
    } else {
      ++it;
    }
  }
  if (out) last_delivered_ns_ = out->t_ns;
  return out;
}

}  // namespace pepper::sim
