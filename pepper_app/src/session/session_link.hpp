#pragma once
// What a session loop talks to besides the robot: the operator (teach UI intents, Ctrl-C flag)
// and the observers (teach UI, the JSON-lines event log of `--events FILE`, the person's console:
// session/console.hpp).
//
// SessionLink is passive plumbing: the loop polls poll_intent() once per iteration (never blocks)
// and calls the publish helpers; with no UI they do nothing. Frames go to the UI as JPEG, at most
// one per `min_frame_period` on average (about 15 fps). Events are one JSON object per line,
// flushed, e.g.
//   {"event":"command","v_m_s":0.1,"omega_rad_s":0.0,"stop":false}
// (written only when the command changes, so tests and scripts can follow the robot). The events
// are for programs; a person reads the console (progress line, warnings), fed by progress() and
// warning().
// Thread-safety: use from the session thread only (the UiServer itself is thread-safe).

#include <chrono>
#include <functional>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/frame.hpp"
#include "teach_ui/intent.hpp"

namespace pepper::teach_ui {
class UiServer;
}

namespace pepper::app {

class Console;
struct Progress;

class SessionLink {
 public:
  /// `ui` and `events` may be null (not owned; must outlive the link).
  SessionLink(teach_ui::UiServer* ui, std::ostream* events);

  /// The person's console (not owned; null: none, as in the evaluation and most tests).
  void set_console(Console* console) { console_ = console; }
  Console* console() const { return console_; }

  /// Test hook: intents come from here instead of (before) the UI's queue.
  void set_intent_source(std::function<std::optional<teach_ui::Intent>()> source) {
    intent_source_ = std::move(source);
  }

  /// Next pending operator intent, or nullopt (never blocks).
  std::optional<teach_ui::Intent> poll_intent();

  bool has_ui() const { return ui_ != nullptr; }

  /// Publishes the frame (JPEG) with an overlay when the last one is older than the frame period.
  /// `overlay` may be null. Returns true when it was published.
  bool publish_frame(const core::Frame& frame, const nlohmann::json& overlay);
  void publish_state(const nlohmann::json& patch);
  void publish_samples(const nlohmann::json& samples);
  /// Grey image as a JPEG thumbnail of at most `max_width_px` wide.
  void publish_thumbnail(const std::string& name, const cv::Mat& gray, int max_width_px = 160);

  /// Writes one JSON line (adds nothing; the object should carry an "event" key).
  void event(const nlohmann::json& e);
  /// Writes a "command" event when (v, omega, stop) differs from the last one written.
  void command_event(double v_m_s, double omega_rad_s, bool stop, const std::string& why);
  /// The console's progress line (once per frame; the console throttles). No-op without one.
  void progress(const Progress& p);
  /// Leaves the console's last progress line of this phase on screen.
  void end_progress();
  /// A warning for the person (console). The caller writes the matching event itself.
  void warning(const std::string& text);

  std::chrono::milliseconds min_frame_period{66};

 private:
  teach_ui::UiServer* ui_;
  std::ostream* events_;
  Console* console_ = nullptr;
  std::function<std::optional<teach_ui::Intent>()> intent_source_;
  std::chrono::steady_clock::time_point next_frame_due_{};
  bool have_last_command_ = false;
  double last_v_ = 0.0, last_omega_ = 0.0;
  bool last_stop_ = true;
};

}  // namespace pepper::app
