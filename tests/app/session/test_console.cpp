// The operator's console (session/console.hpp, issue 25): a progress line that is rewritten in
// place on a terminal and printed at most every log period elsewhere, with permanent lines and
// warnings that never end up inside a progress line.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <string>

#include "session/console.hpp"

namespace pepper::app {
namespace {

using Clock = Console::Clock;
using std::chrono::milliseconds;

struct FakeClock {
  Clock::time_point t{std::chrono::seconds(1000)};
  Clock::time_point operator()() const { return t; }
};

Progress replay_at(int64_t frames, int in) {
  Progress p;
  p.phase = "replay";
  p.frames = frames;
  p.key_index = in;
  p.key_count = 10;
  p.distance_m = in > 0 ? 0.5 * in : 0.0;
  p.total_m = 4.5;
  return p;
}

long lines_of(const std::string& s) { return std::count(s.begin(), s.end(), '\n'); }

TEST(Console, FormatsPhaseKeyImageDistanceRateAndElapsed) {
  const std::string s = Console::format(replay_at(100, 4), std::chrono::seconds(72), 14.96);
  EXPECT_EQ(s, "replay  key image 4 of 9  2.00 of 4.50 m  15.0 fps  1:12");
  Progress teach;
  teach.phase = "teach";
  teach.key_index = 4;  // five key images so far, the total unknown
  teach.distance_m = 1.234;
  EXPECT_EQ(Console::format(teach, std::chrono::seconds(5), NAN),
            "teach  5 key images  1.23 m  0:05");
  Progress unknown = replay_at(0, -1);
  unknown.distance_m = NAN;
  unknown.detail = "localising";
  EXPECT_EQ(Console::format(unknown, std::chrono::seconds(0), NAN),
            "replay  key image - of 9  0:00  localising");
}

TEST(Console, LogPrintsAtMostOneProgressLinePerPeriod) {
  std::ostringstream out;
  FakeClock clock;
  Console console(out, /*in_place=*/false, std::chrono::seconds(5), std::ref(clock));
  // 60 s of a 15 Hz replay: 900 samples.
  for (int i = 0; i < 900; ++i) {
    console.progress(replay_at(i + 1, i / 100));
    clock.t += milliseconds(66);
  }
  console.end_progress();
  const std::string text = out.str();
  // The first sample, one every 5 s over about 59 s (11), and the final state.
  EXPECT_GE(lines_of(text), 12);
  EXPECT_LE(lines_of(text), 14);
  EXPECT_EQ(text.find('\r'), std::string::npos) << "no carriage returns in a log";
  // The frame rate is measured: 1 frame per 66 ms.
  EXPECT_NE(text.find("15.2 fps"), std::string::npos) << text;
  // The last line is the final state.
  EXPECT_NE(text.rfind("key image 8 of 9"), std::string::npos) << text;
}

TEST(Console, TerminalRewritesOneLineInPlace) {
  std::ostringstream out;
  FakeClock clock;
  Console console(out, /*in_place=*/true, std::chrono::seconds(5), std::ref(clock));
  for (int i = 0; i < 100; ++i) {
    console.progress(replay_at(i + 1, 2));
    clock.t += milliseconds(66);
  }
  const std::string running = out.str();
  EXPECT_EQ(lines_of(running), 0) << "still one line on screen";
  EXPECT_GT(std::count(running.begin(), running.end(), '\r'), 10);
  console.warning("robot: move failed");
  console.end_progress();
  const std::string text = out.str();
  // The warning is a line of its own (the progress line cleared before it) and the progress line
  // comes back after it; end_progress leaves it as the last line.
  const auto warn = text.find("\r\x1b[Kwarning: robot: move failed\n");
  ASSERT_NE(warn, std::string::npos) << text;
  EXPECT_NE(text.find("\rreplay  key image 2 of 9", warn), std::string::npos);
  EXPECT_EQ(text.back(), '\n');
  EXPECT_EQ(lines_of(text), 2);
}

TEST(Console, ANewPhaseRestartsTheClockAndIsShownAtOnce) {
  std::ostringstream out;
  FakeClock clock;
  Console console(out, /*in_place=*/false, std::chrono::seconds(5), std::ref(clock));
  Progress teach;
  teach.phase = "teach";
  teach.frames = 1;
  console.progress(teach);
  clock.t += std::chrono::seconds(30);
  teach.frames = 451;
  console.progress(teach);
  console.end_progress();  // the last state was printed: not again
  console.line("taught");
  console.progress(replay_at(1, -1));
  const std::string text = out.str();
  EXPECT_NE(
      text.find(
          "teach  0:00\nteach  15.0 fps  0:30\ntaught\nreplay  key image - of 9  0.00 of 4.50 m  "
          "0:00\n"),
      std::string::npos)
      << text;
}

// With `--events -` on a terminal the events share the screen: the console switches to log lines
// and first ends the line it was rewriting, so no event is printed into it.
TEST(Console, SwitchingToLogLinesEndsTheLineOnScreen) {
  std::ostringstream out;
  FakeClock clock;
  Console console(out, /*in_place=*/true, std::chrono::seconds(5), std::ref(clock));
  console.progress(replay_at(1, 0));
  console.set_in_place(false);
  EXPECT_EQ(out.str().back(), '\n');
  out.str("");
  clock.t += std::chrono::seconds(6);
  console.progress(replay_at(90, 1));
  const std::string text = out.str();
  EXPECT_EQ(text.find('\r'), std::string::npos) << text;
  EXPECT_EQ(lines_of(text), 1) << text;
}

}  // namespace
}  // namespace pepper::app
