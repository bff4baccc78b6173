#include "session/console.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>

namespace pepper::app {

namespace {

// A terminal redraws cheaply, but a mock run steps hundreds of frames a second: four redraws a
// second look live and cost nothing.
constexpr std::chrono::milliseconds kInPlacePeriod{250};
// The frame rate is measured over at least this long (shorter windows jitter with the pacing).
constexpr std::chrono::seconds kRateWindow{1};

std::string fixed(double v, int decimals) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace

Console::Console(std::ostream& out, bool in_place, std::chrono::milliseconds log_period,
                 std::function<Clock::time_point()> now)
    : out_(out), in_place_(in_place), log_period_(log_period), now_(std::move(now)) {}

std::string Console::format(const Progress& p, Clock::duration elapsed, double frame_rate_hz) {
  std::string s = p.phase.empty() ? "running" : p.phase;
  if (p.key_count > 0) {
    // Indices as everywhere else (0 = the start): "key image 4 of 9" on a 10-image map, as the
    // result line's "furthest key image K of L".
    s += "  key image " + (p.key_index >= 0 ? std::to_string(p.key_index) : std::string("-")) +
         " of " + std::to_string(p.key_count - 1);
  } else if (p.key_index >= 0) {
    s += "  " + std::to_string(p.key_index + 1) + " key image" + (p.key_index == 0 ? "" : "s");
  }
  if (std::isfinite(p.distance_m)) {
    s += "  " + fixed(p.distance_m, 2);
    if (std::isfinite(p.total_m)) s += " of " + fixed(p.total_m, 2);
    s += " m";
  }
  if (std::isfinite(frame_rate_hz)) s += "  " + fixed(frame_rate_hz, 1) + " fps";
  const auto total_s = std::chrono::duration_cast<std::chrono::seconds>(elapsed).count();
  char clock[32];
  std::snprintf(clock, sizeof clock, "%lld:%02lld", static_cast<long long>(total_s / 60),
                static_cast<long long>(total_s % 60));
  s += std::string("  ") + clock;
  if (!p.detail.empty()) s += "  " + p.detail;
  return s;
}

void Console::progress(const Progress& p) {
  std::lock_guard<std::mutex> lock(mutex_);
  const Clock::time_point now = now_();
  if (!have_progress_ || p.phase != last_.phase) {
    // A new phase: its own clock and frame rate; the first sample is shown at once.
    phase_start_ = now;
    rate_ref_time_ = now;
    rate_ref_frames_ = p.frames;
    rate_hz_ = std::numeric_limits<double>::quiet_NaN();
    last_print_ = Clock::time_point{};
    have_progress_ = true;
    last_ = p;
    printed_latest_ = false;
    print_progress_locked(now);
    return;
  }
  last_ = p;
  printed_latest_ = false;
  if (now - rate_ref_time_ >= kRateWindow) {
    rate_hz_ = static_cast<double>(p.frames - rate_ref_frames_) /
               std::chrono::duration<double>(now - rate_ref_time_).count();
    rate_ref_time_ = now;
    rate_ref_frames_ = p.frames;
  }
  const auto period = in_place_ ? std::chrono::duration_cast<Clock::duration>(kInPlacePeriod)
                                : std::chrono::duration_cast<Clock::duration>(log_period_);
  if (now - last_print_ >= period) print_progress_locked(now);
}

void Console::print_progress_locked(Clock::time_point now) {
  const std::string text = format(last_, now - phase_start_, rate_hz_);
  if (in_place_) {
    out_ << "\r" << text << "\x1b[K" << std::flush;
    showing_ = true;
  } else {
    out_ << text << "\n" << std::flush;
  }
  last_print_ = now;
  printed_latest_ = true;
}

void Console::clear_locked() {
  if (in_place_ && showing_) {
    out_ << "\r\x1b[K";
    showing_ = false;
  }
}

void Console::end_progress() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!have_progress_) return;
  if (!printed_latest_ || in_place_) print_progress_locked(now_());
  if (in_place_) {
    out_ << "\n" << std::flush;
    showing_ = false;
  }
  have_progress_ = false;
}

void Console::line(std::string_view text) {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool redraw = in_place_ && showing_;
  clear_locked();
  out_ << text << "\n";
  if (redraw) {
    out_ << "\r" << format(last_, now_() - phase_start_, rate_hz_) << "\x1b[K";
    showing_ = true;
  }
  out_ << std::flush;
}

void Console::set_in_place(bool in_place) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (in_place == in_place_) return;
  if (showing_) {  // end the line on screen before the other behaviour begins
    out_ << "\n" << std::flush;
    showing_ = false;
  }
  in_place_ = in_place;
}

void Console::warning(std::string_view text) { line("warning: " + std::string(text)); }

Console& terminal_console() {
  static Console console(std::cerr, ::isatty(STDERR_FILENO) == 1);
  return console;
}

}  // namespace pepper::app
