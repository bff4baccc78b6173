// Every `--help` example that can run offline runs (issue 30, "examples that run"): as an operator
// types it, in a scratch folder that holds the checkout's shipped files (worlds/, cameras/,
// tests/, ../shared/) and the user's files the examples name (maps/lab, rec/lab_tour, a.png ...),
// made beforehand by short mock teaches (one in ceiling mode) and a few renders. Each must exit 0
// and write the files it names as outputs. Not run, and counted so that a new example is not
// skipped silently: examples on a real robot (a tcp:// or tcps:// URL not on this machine), with
// --ui (a person at a browser), and `evaluate` (closed-loop runs of minutes: the evaluation's
// job). Adjustments, each said where it is made: /tmp/X becomes the scratch folder's tmp/X; the
// mock teach example stops after 3 m (the whole tour is the demo's job); the mock-robot examples
// listen on a free port, and the doctor example checks the first of them there.
#include <gtest/gtest.h>
#include <signal.h>
#include <stdlib.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "app/e2e/app_process.hpp"
#include "app/e2e/help_examples.hpp"

namespace pepper::app {
namespace {

namespace fs = std::filesystem;

/// An example as a process: arguments after `pepper_app`, the environment it sets, the file its
/// stdout is redirected to ("" for none).
struct ExampleCommand {
  std::vector<std::string> args;
  std::map<std::string, std::string> env;
  std::string stdout_to;
  std::string text;  ///< the example's line, for messages
};

ExampleCommand parse_example(const std::string& line, const fs::path& scratch) {
  ExampleCommand c;
  c.text = line;
  std::istringstream words(line.substr(0, line.find('#')));
  bool after_program = false;
  bool redirect = false;
  for (std::string w; words >> w;) {
    if (!after_program) {  // VAR=value prefixes, then the program
      const auto eq = w.find('=');
      if (w == "pepper_app") {
        after_program = true;
      } else if (eq != std::string::npos) {
        c.env[w.substr(0, eq)] = w.substr(eq + 1);
      }
      continue;
    }
    if (w == ">") {
      redirect = true;
      continue;
    }
    // Adjustment: absolute scratch paths stay inside the test's folder.
    if (w.rfind("/tmp/", 0) == 0) w = (scratch / "tmp" / w.substr(5)).string();
    if (redirect) {
      c.stdout_to = w;
      redirect = false;
    } else {
      c.args.push_back(w);
    }
  }
  return c;
}

bool has(const std::vector<std::string>& args, const std::string& what) {
  return std::find(args.begin(), args.end(), what) != args.end();
}

/// The robot URL of the example, or "".
std::string robot_url(const std::vector<std::string>& args) {
  for (const auto& a : args) {
    if (a.rfind("tcp://", 0) == 0 || a.rfind("tcps://", 0) == 0) return a;
  }
  return "";
}

/// Why the example cannot run offline, or "" when it can.
std::string why_not_offline(const ExampleCommand& c) {
  const std::string url = robot_url(c.args);
  if (!url.empty() && url.find("//127.0.0.1") == std::string::npos) return "a real robot";
  if (has(c.args, "--ui")) return "a person at a browser (--ui)";
  if (!c.args.empty() && c.args.front() == "evaluate") return "closed-loop runs of minutes";
  return "";
}

/// The files an example writes, by the options that name them (checked after it ran).
std::vector<std::string> outputs(const ExampleCommand& c) {
  std::vector<std::string> out;
  if (!c.stdout_to.empty()) out.push_back(c.stdout_to);
  const std::string cmd = c.args.empty() ? "" : c.args.front();
  for (std::size_t i = 0; i + 1 < c.args.size(); ++i) {
    const std::string& o = c.args[i];
    const bool writes_map = (cmd == "teach" || (cmd == "map" && c.args[1] == "build")) && o == "--map";
    if (o == "--out" || o == "--json" || o == "--events" || writes_map) out.push_back(c.args[i + 1]);
  }
  return out;
}

/// Order of the commands, so that an example finds what an earlier one wrote (the replay's map
/// is the teach example's, `map info` reads the map `map build` wrote).
int rank(const ExampleCommand& c) {
  static const std::vector<std::string> order = {"version", "config", "world", "teach", "replay",
                                                 "demo", "map", "replay-log", "perception-demo",
                                                 "mock-robot", "doctor"};
  const std::string cmd = c.args.empty() ? "" : c.args.front();
  const auto it = std::find(order.begin(), order.end(), cmd);
  int r = static_cast<int>(it - order.begin()) * 10;
  if (cmd == "map" && c.args.size() > 1 && c.args[1] == "build") r -= 5;  // before info, trim
  return r;
}

/// Sets the example's environment variables for the child (posix_spawn passes `environ`), and
/// removes them again when it goes.
class ScopedEnv {
 public:
  explicit ScopedEnv(const std::map<std::string, std::string>& env) : env_(env) {
    for (const auto& [k, v] : env_) setenv(k.c_str(), v.c_str(), 1);
  }
  ~ScopedEnv() {
    for (const auto& [k, v] : env_) unsetenv(k.c_str());
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  std::map<std::string, std::string> env_;
};

/// The URL a `mock-robot` prints once it listens (tcp:// or tcps://), "" after 20 s.
std::string listening_url(const test::AppProcess& mock) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < end) {
    const std::string out = mock.out();
    const auto at = out.find(" on tcp");
    if (at != std::string::npos && out.find("Ctrl-C to stop") != std::string::npos) {
      const auto start = at + 4;
      return out.substr(start, out.find_first_of(" \n", start) - start);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return "";
}

class HelpExamples : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / "pepper_e2e_help_run";
    fs::remove_all(root_);
    logs_ = root_ / "logs";
    work_ = root_ / "work";
    fs::create_directories(logs_);
    fs::create_directories(work_ / "tmp");
    fs::create_directories(work_ / "docs");  // `config doc > docs/configuration.md` writes here
    for (const char* shipped : {"worlds", "cameras", "tests"}) {
      fs::create_directory_symlink(fs::path(PEPPER_SOURCE_DIR) / shipped, work_ / shipped);
    }
    // ../shared/ of the examples is the checkout's neighbour.
    fs::create_directory_symlink(fs::path(PEPPER_SHARED_DIR), root_ / "shared");
  }

  /// Runs `args` in the scratch folder; its exit code, with its output in `*both`.
  int run(const std::vector<std::string>& args, const std::string& name, std::string* both,
          std::chrono::seconds limit = std::chrono::seconds(180)) {
    test::AppProcess p(args, logs_, name, work_);
    const int code = p.wait(limit);
    *both = p.both();
    return code;
  }

  /// The user's files the examples name: a map with 13+ key images (maps/lab, for `map trim
  /// --to 12`), its recording as rec/lab_tour and rec/replay1, three views a.png b.png c.png.
  void make_user_files() {
    std::string out;
    ASSERT_EQ(run({"teach", "--robot", "mock:worlds/robotics_room.yaml", "--map", "maps/lab",
                   "--max-distance", "6", "--set", "robot.camera_width_px=320", "--set",
                   "robot.camera_height_px=240"},
                  "fixture_teach", &out),
              0)
        << out;
    ASSERT_EQ(run({"map", "info", "maps/lab"}, "fixture_info", &out), 0) << out;
    const auto at = out.find("key images: ");
    ASSERT_NE(at, std::string::npos) << out;
    ASSERT_GE(std::stoi(out.substr(at + 12)), 13) << "maps/lab is too short for map trim --to 12";
    fs::create_directories(work_ / "rec");
    for (const char* rec : {"rec/lab_tour", "rec/replay1"}) {
      fs::copy(work_ / "maps/lab.recording", work_ / rec, fs::copy_options::recursive);
    }
    // map build's ceiling examples: a ceiling teach's recording (rec/hall_ceiling, 2 m of the
    // ceiling test hall) and the same as recorded before format version 2 (rec/old_ceiling).
    ASSERT_EQ(run({"teach", "--mode", "ceiling", "--robot", "mock:tests/worlds/ceiling_hall.yaml",
                   "--map", "maps/hall_taught", "--recording", "rec/hall_ceiling",
                   "--max-distance", "2", "--set", "robot.camera_width_px=320", "--set",
                   "robot.camera_height_px=240"},
                  "fixture_ceiling_teach", &out),
              0)
        << out;
    fs::copy(work_ / "rec/hall_ceiling", work_ / "rec/old_ceiling", fs::copy_options::recursive);
    {
      const fs::path manifest = work_ / "rec/old_ceiling/recording.json";
      nlohmann::json m = nlohmann::json::parse(test::AppProcess::slurp(manifest));
      m["version"] = 1;
      for (const char* key : {"mode", "head_pitch_rad", "ceiling"}) m.erase(key);
      std::ofstream(manifest, std::ios::trunc) << m.dump(2);
    }
    const char* poses[] = {"1.5,1.8,0", "2,1.8,0", "2.5,1.8,0"};
    const char* names[] = {"a.png", "b.png", "c.png"};
    for (int i = 0; i < 3; ++i) {
      ASSERT_EQ(run({"world", "render", "--world", "worlds/robotics_room.yaml", "--pose", poses[i],
                     "--size", "320x240", "--out", names[i]},
                    std::string("fixture_") + names[i], &out),
                0)
          << out;
    }
  }

  fs::path root_, logs_, work_;
};

TEST_F(HelpExamples, EveryExampleThatCanRunOfflineRunsAndWritesItsFiles) {
  std::string problems;
  const auto examples = test::help_examples(logs_, &problems);
  ASSERT_TRUE(problems.empty()) << problems;
  ASSERT_GE(examples.size(), 15u);
  make_user_files();
  if (HasFatalFailure()) return;

  std::vector<ExampleCommand> runnable;
  std::map<std::string, int> not_run;  // reason -> count
  for (const auto& e : examples) {
    ExampleCommand c = parse_example(e.line, work_);
    ASSERT_FALSE(c.args.empty()) << e.line;
    const std::string why = why_not_offline(c);
    if (why.empty()) {
      runnable.push_back(c);
    } else {
      ++not_run[why];
    }
  }
  std::stable_sort(runnable.begin(), runnable.end(),
                   [](const auto& a, const auto& b) { return rank(a) < rank(b); });

  int ran = 0;
  std::vector<ExampleCommand> doctors;
  for (const auto& c : runnable) {
    if (c.args.front() == "doctor") doctors.push_back(c);
  }
  bool doctor_ran = false;
  for (auto c : runnable) {
    const std::string name = "example_" + std::to_string(ran);
    if (c.args.front() == "doctor") continue;  // run against a mock-robot example below
    if (c.args.front() == "mock-robot") {
      // Adjustment: a free port instead of NAOqi's (another suite may be serving on it).
      for (auto& a : c.args) {
        for (const char* port : {":9559", ":9503"}) {
          const auto at = a.find(port);
          if (a.rfind("tcp", 0) == 0 && at != std::string::npos) a.replace(at, 5, ":0");
        }
      }
      ScopedEnv env(c.env);
      test::AppProcess mock(c.args, logs_, name, work_);
      const std::string url = listening_url(mock);
      ASSERT_FALSE(url.empty()) << c.text << "\n" << mock.both();
      if (!doctor_ran && url.rfind("tcp://", 0) == 0) {
        for (auto d : doctors) {
          for (auto& a : d.args) {
            if (a.rfind("tcp://127.0.0.1", 0) == 0) a = url;
          }
          std::string out;
          EXPECT_EQ(run(d.args, name + "_doctor", &out), 0) << d.text << "\n" << out;
          EXPECT_NE(out.find("all checks passed"), std::string::npos) << d.text << "\n" << out;
          ++ran;
        }
        doctor_ran = true;
      }
      mock.signal(SIGINT);
      EXPECT_EQ(mock.wait(std::chrono::seconds(10)), 0) << c.text << "\n" << mock.both();
      ++ran;
      continue;
    }
    // Adjustment: the mock teach example teaches 3 m, not the whole tour.
    if (c.args.front() == "teach") {
      c.args.insert(c.args.end(), {"--max-distance", "3"});
    }
    std::string out;
    {
      ScopedEnv env(c.env);
      test::AppProcess p(c.args, logs_, name, work_);
      const int code = p.wait(std::chrono::seconds(180));
      out = p.both();
      EXPECT_EQ(code, 0) << c.text << "\n" << out;
      if (!c.stdout_to.empty()) {
        fs::create_directories((work_ / c.stdout_to).parent_path());
        fs::copy_file(logs_ / (name + ".stdout"), work_ / c.stdout_to,
                      fs::copy_options::overwrite_existing);
      }
    }
    for (const auto& f : outputs(c)) {
      const fs::path p = fs::path(f).is_absolute() ? fs::path(f) : work_ / f;
      EXPECT_TRUE(fs::exists(p) && (fs::is_directory(p) || fs::file_size(p) > 0))
          << f << " not written by: " << c.text << "\n" << out;
    }
    ++ran;
  }
  EXPECT_TRUE(doctors.empty() || doctor_ran) << "no mock-robot example to check doctor against";
  std::ostringstream summary;
  for (const auto& [why, n] : not_run) summary << n << " need " << why << "; ";
  std::cout << "[measured] " << ran << " of " << examples.size()
            << " --help examples ran offline; not run: " << summary.str() << "\n";
  // Most examples run; the ones left need what a test does not have.
  EXPECT_GE(ran, 25);
  int skipped = 0;
  for (const auto& [why, n] : not_run) skipped += n;
  EXPECT_EQ(ran + skipped, static_cast<int>(examples.size()));
}

}  // namespace
}  // namespace pepper::app
