#pragma once
// What a person reads while `teach`, `replay` or `demo` runs (issue 25): one progress line
// (phase, key image k of K, distance driven, frame rate, elapsed), warnings, and permanent lines
// (phases, results). Machine-readable events are not printed here: they go to `--events FILE`
// (session_link.hpp).
//
// On a terminal the progress line is rewritten in place ("\r" and erase-to-end-of-line, at most
// about four times a second, so the terminal is not the bottleneck of a fast mock run). Anywhere
// else (a pipe, a log file, the tests) a carriage return would pile up into one huge line, so a
// progress line is printed whole, at most once per `log_period` (5 s), plus one when the phase
// ends: a log shows the run advancing without a line per frame.
// Warnings and permanent lines clear the progress line first and redraw it after (terminal).
// Thread-safety: every member may be called from any thread (the teach UI's log callback runs on
// its server thread); the output stays line-atomic.

#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <mutex>
#include <ostream>
#include <string>
#include <string_view>

namespace pepper::app {

/// One progress sample from a session loop (once per frame; the console decides what to print).
struct Progress {
  std::string phase;   ///< "teach", "replay", ... (a new phase restarts the elapsed time)
  int64_t frames = 0;  ///< frames processed in this phase (the frame rate comes from it)
  int key_index = -1;  ///< replay: IN (the key image driven to); teach: key images so far - 1
  int key_count = 0;   ///< replay: the map's key images; 0: unknown (teach)
  double distance_m = std::numeric_limits<double>::quiet_NaN();  ///< driven so far; NaN: unknown
  double total_m = std::numeric_limits<double>::quiet_NaN();     ///< the tour's; NaN: unknown
  std::string detail;  ///< optional state, e.g. "localising: best key image 3, 4/8 matches"
};

class Console {
 public:
  using Clock = std::chrono::steady_clock;

  /// `out` is not owned and must outlive the console. `in_place`: rewrite the progress line (a
  /// terminal). `now` is injectable for tests.
  Console(std::ostream& out, bool in_place,
          std::chrono::milliseconds log_period = std::chrono::seconds(5),
          std::function<Clock::time_point()> now = &Clock::now);

  /// Records a sample; prints it when due (see the file comment).
  void progress(const Progress& p);
  /// Ends the current phase's progress: its last state stays as a permanent line (terminal), or
  /// is printed once more when it changed since the last printed line (log).
  void end_progress();
  /// A permanent line (a phase starting, a result).
  void line(std::string_view text);
  /// "warning: TEXT" as a permanent line.
  void warning(std::string_view text);

  bool in_place() const { return in_place_; }
  /// Switches between the terminal and the log behaviour (e.g. to log lines when the events go
  /// to the same terminal on stdout: an in-place line would be torn by them).
  void set_in_place(bool in_place);

  /// The progress text for a sample (no line ends); `elapsed` since the phase began and the frame
  /// rate measured by the caller (NaN: not yet known). Public for the tests.
  static std::string format(const Progress& p, Clock::duration elapsed, double frame_rate_hz);

 private:
  void print_progress_locked(Clock::time_point now);
  void clear_locked();

  std::mutex mutex_;
  std::ostream& out_;
  bool in_place_;
  std::chrono::milliseconds log_period_;
  std::function<Clock::time_point()> now_;

  Progress last_;  ///< the latest sample
  bool have_progress_ = false;
  bool showing_ = false;         ///< terminal: a progress line is on screen (no line end yet)
  bool printed_latest_ = false;  ///< the latest sample has been printed
  Clock::time_point phase_start_{}, last_print_{};
  // Frame rate over windows of at least one second.
  Clock::time_point rate_ref_time_{};
  int64_t rate_ref_frames_ = 0;
  double rate_hz_ = std::numeric_limits<double>::quiet_NaN();
};

/// The console of the command line: on stderr (stdout stays for machine output, `--events -`),
/// in place when stderr is a terminal.
Console& terminal_console();

}  // namespace pepper::app
