#pragma once
// WifiModel: frame drops and delays between a simulated camera and its consumer, as Pepper's
// WiFi link produces them (PEPPER.md "Streaming over WiFi"). Used by MockBridge; any other
// transport of simulated frames may reuse it.
//
// Model: each captured frame is lost with probability drop_probability; a kept frame arrives
// delay_s + U(0, jitter_s) after its capture stamp. A consumer polling at simulated time `now`
// receives the newest frame that has arrived and is newer than the last one delivered (older
// arrivals are skipped, as a latest-frame subscription does); otherwise nothing.
// Determinism: decisions come from a generator seeded with `seed`.
// Thread-safety: none (the owner serialises access).

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "core/frame.hpp"

namespace pepper::sim {

struct WifiOptions {
  double drop_probability = 0.0;  ///< [0, 1)
  double delay_s = 0.0;           ///< fixed transport delay, >= 0
  double jitter_s = 0.0;          ///< extra uniform delay in [0, jitter_s]
  uint64_t seed = 1;

  std::vector<std::string> validate() const;
};

class WifiModel {
 public:
  /// Throws std::invalid_argument naming the bad field.
  explicit WifiModel(WifiOptions options = {});

  /// A frame captured (stamp frame.t_ns) is handed to the link at simulated time now_ns; returns
  /// what the consumer receives at now_ns, if anything.
  std::optional<core::Frame> transmit(const core::Frame& frame, int64_t now_ns);

  int64_t dropped() const { return dropped_; }
  const WifiOptions& options() const { return options_; }

 private:
  double uniform();
  struct InFlight {
    int64_t arrival_ns;
    core::Frame frame;
  };
  WifiOptions options_;
  std::deque<InFlight> in_flight_;
  uint64_t rng_state_;
  int64_t dropped_ = 0;
  int64_t last_delivered_ns_ = -1;
};

}  // namespace pepper::sim
