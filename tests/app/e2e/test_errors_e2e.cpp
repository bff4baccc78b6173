// Every error exit of the CLI that can be produced offline, from docs/errors.md (issue 30, "every
// error says what to do"). The test reads the tables of that page, runs each row's offline
// trigger with the built `pepper_app` binary and checks that
//   - the exit code is the row's,
//   - stderr (or stdout, for doctor's report) matches the row's message pattern ({name} = a
//     value, ... = any text), which for every row includes what to do next,
//   - that output contains the offending value (the bracketed part of the trigger).
// So the table cannot drift from the code: a changed message, exit code or missing next step
// fails here.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace pepper::app {
namespace {

namespace fs = std::filesystem;

const std::string kBinary = std::string(PEPPER_BINARY_DIR) + "/pepper_app/pepper_app";
const fs::path kSource = PEPPER_SOURCE_DIR;

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string trim(std::string s) {
  const auto b = s.find_first_not_of(" \t");
  const auto e = s.find_last_not_of(" \t");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

std::string strip_code(std::string s) {
  s = trim(s);
  if (s.size() >= 2 && s.front() == '`' && s.back() == '`') s = s.substr(1, s.size() - 2);
  return s;
}

struct AppRun {
  int exit_code = -1;
  std::string out, err;
};

/// Runs pepper_app with `args` (stdin /dev/null, no password in the environment), at most
/// `limit`; exit -1 when it had to be killed.
AppRun run_app(std::vector<std::string> args, const fs::path& dir,
               std::chrono::seconds limit = std::chrono::seconds(120)) {
  args.insert(args.begin(), kBinary);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const fs::path out = dir / "run.stdout", err = dir / "run.stderr";
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  // A password in the test's environment would turn the "no password" row into a login try.
  std::vector<std::string> env_store;
  for (char** e = environ; *e != nullptr; ++e) {
    if (std::string(*e).rfind("PEPPER_PASSWORD=", 0) != 0) env_store.emplace_back(*e);
  }
  std::vector<char*> envp;
  for (auto& e : env_store) envp.push_back(e.data());
  envp.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, kBinary.c_str(), &fa, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&fa);
  AppRun r;
  if (rc != 0) return r;
  const auto end = std::chrono::steady_clock::now() + limit;
  for (;;) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) {
      r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      break;
    }
    if (std::chrono::steady_clock::now() > end) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

struct Row {
  int line = 0;
  std::string command, message, exit_text, trigger;
};

/// The rows of every table in docs/errors.md ("same as the row above" takes the row above's
/// message).
std::vector<Row> read_table() {
  std::ifstream f(kSource / "docs" / "errors.md");
  std::vector<Row> rows;
  std::string line, previous_message;
  int n = 0;
  while (std::getline(f, line)) {
    ++n;
    if (line.rfind("| ", 0) != 0) continue;
    std::vector<std::string> cells;
    std::string cell;
    for (std::size_t i = 1; i < line.size(); ++i) {
      if (line[i] == '|') {
        cells.push_back(trim(cell));
        cell.clear();
      } else {
        cell += line[i];
      }
    }
    if (cells.size() != 6 || cells[0] == "command" || cells[0].rfind("---", 0) == 0) continue;
    Row r;
    r.line = n;
    r.command = cells[0];
    r.message =
        cells[1].rfind("same as the row above", 0) == 0 ? previous_message : strip_code(cells[1]);
    previous_message = r.message;
    r.exit_text = cells[4];
    r.trigger = strip_code(cells[5]);
    rows.push_back(r);
  }
  return rows;
}

/// The message pattern as a regex: {name} is some text, ... any text (both across lines).
std::regex pattern_regex(const std::string& pattern) {
  std::string re;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    const char c = pattern[i];
    if (c == '{') {
      const auto close = pattern.find('}', i);
      if (close != std::string::npos) {
        re += "[\\s\\S]+?";
        i = close;
        continue;
      }
    }
    if (pattern.compare(i, 3, "...") == 0) {  // any text, the spaces around it included
      if (re.size() >= 3 && re.compare(re.size() - 3, 3, "\\s+") == 0) re.resize(re.size() - 3);
      re += "[\\s\\S]*?";
      i += 2;
      while (i + 1 < pattern.size() && pattern[i + 1] == ' ') ++i;
      continue;
    }
    if (c == ' ') {  // a space in the table stands for any white space (line breaks too)
      if (re.size() < 3 || re.compare(re.size() - 3, 3, "\\s+") != 0) re += "\\s+";
      continue;
    }
    if (std::string("\\^$.|?*+()[]{}").find(c) != std::string::npos) re += '\\';
    re += c;
  }
  return std::regex(re);
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size())) {
    s.replace(p, from.size(), to);
  }
  return s;
}

class ErrorsTable : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per test process: ctest -j2 runs this suite's tests side by side, and each
    // would otherwise remove the other's fixture map while it is being taught.
    dir_ = fs::temp_directory_path() / ("pepper_e2e_errors_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "tmp");
    fs::create_directories(dir_ / "empty");
    fs::create_directories(dir_ / "junk_map");
    std::ofstream(dir_ / "junk_map" / "manifest.json") << "this is not JSON\n";
    // A short valid map at 320x240 (the rows that need one refuse something else about it).
    map_ok_ =
        run_app({"teach", "--robot", "mock:" + (kSource / "worlds/robotics_room.yaml").string(),
                 "--map", (dir_ / "map").string(), "--max-distance", "0.6", "--set",
                 "robot.camera_width_px=320", "--set", "robot.camera_height_px=240"},
                dir_)
            .exit_code == 0;
  }
  static std::string expand(const std::string& s) {
    std::string r = replace_all(s, "%TMP%", (dir_ / "tmp").string());
    r = replace_all(r, "%WORLDS%", (kSource / "worlds").string());
    r = replace_all(r, "%MAP%", (dir_ / "map").string());
    r = replace_all(r, "%JUNK_MAP%", (dir_ / "junk_map").string());
    return replace_all(r, "%EMPTY%", (dir_ / "empty").string());
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  static fs::path dir_;
  static bool map_ok_;
};
fs::path ErrorsTable::dir_;
bool ErrorsTable::map_ok_ = false;

TEST_F(ErrorsTable, EveryRowHasAMessageNextStepAndExitCode) {
  const auto rows = read_table();
  ASSERT_GE(rows.size(), 40u) << "docs/errors.md lost rows";
  for (const auto& r : rows) {
    SCOPED_TRACE("docs/errors.md:" + std::to_string(r.line));
    EXPECT_FALSE(r.message.empty());
    EXPECT_FALSE(r.exit_text.empty());
    EXPECT_TRUE(std::isdigit(static_cast<unsigned char>(r.exit_text[0]))) << r.exit_text;
  }
}

TEST_F(ErrorsTable, EveryOfflineTriggerGivesTheTablesMessageAndExitCode) {
  ASSERT_TRUE(map_ok_) << "could not teach the fixture map";
  const auto rows = read_table();
  int triggered = 0;
  for (const auto& r : rows) {
    if (r.trigger.empty()) continue;
    SCOPED_TRACE("docs/errors.md:" + std::to_string(r.line) + ": " + r.trigger);
    // A trigger's row has one exit code.
    std::size_t used = 0;
    const int want_exit = std::stoi(r.exit_text, &used);
    ASSERT_EQ(trim(r.exit_text.substr(used)), "") << "a triggered row needs one exit code";
    // The offending value: the bracketed part of the trigger.
    std::string value;
    std::string trigger = r.trigger;
    const auto open = trigger.find('[');
    const auto close = trigger.find(']', open == std::string::npos ? 0 : open);
    if (open != std::string::npos && close != std::string::npos) {
      value = expand(trigger.substr(open + 1, close - open - 1));
      trigger = trigger.substr(0, open) + trigger.substr(open + 1, close - open - 1) +
                trigger.substr(close + 1);
    }
    std::vector<std::string> args;
    if (trigger != "(no arguments)") {
      std::istringstream words(expand(trigger));
      for (std::string w; words >> w;) args.push_back(w);
    }
    fs::remove_all(dir_ / "tmp");
    fs::create_directories(dir_ / "tmp");
    const AppRun run = run_app(args, dir_);
    ++triggered;
    EXPECT_EQ(run.exit_code, want_exit) << "stderr:\n" << run.err;
    // Errors go to stderr; doctor's report (with its FAIL lines) to stdout.
    const std::string printed = run.err + "\n" + run.out;
    EXPECT_TRUE(std::regex_search(printed, pattern_regex(r.message)))
        << "pattern: " << r.message << "\noutput:\n"
        << printed;
    if (!value.empty()) {
      EXPECT_NE(printed.find(value), std::string::npos)
          << "the message does not name '" << value << "':\n"
          << printed;
    }
  }
  EXPECT_GE(triggered, 30) << "fewer offline triggers than the table had";
}

}  // namespace
}  // namespace pepper::app
